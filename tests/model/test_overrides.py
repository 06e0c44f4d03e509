"""Dotted-key overrides of a scenario (``pilegroup run ... --set KEY=VALUE``)."""

import pytest

from pilegroup.model import ScenarioError, load_scenario
from pilegroup.model.loader import apply_overrides, parse_override


def test_overrides_reach_the_scenario():
    sc = load_scenario("pier667", dict([parse_override("numerics.mesh.size_m=0.6"),
                                        parse_override("layers[0].E_MPa=3.5"),
                                        parse_override("interface.mode='elastic'")]))
    assert sc.numerics.mesh.size_m == 0.6
    assert sc.layers[0].E == pytest.approx(3500.0)  # kPa inside the code
    assert sc.interface.mode == "elastic"
    assert load_scenario("pier667").numerics.mesh.size_m != 0.6  # the bundled file is untouched


@pytest.mark.parametrize("text, value", [("a.b=1", 1), ("a=0.25", 0.25), ("a=true", True),
                                         ("a = [1, 2]", [1, 2]), ("a=viscoplastic",
                                                                  "viscoplastic")])
def test_values_are_read_as_toml_else_as_text(text, value):
    assert parse_override(text)[1] == value


@pytest.mark.parametrize("override, match", [
    ({"numerics.mesh.sise_m": 1.0}, r"numerics.mesh.sise_m = 1.0: unknown key"),
    ({"layers[40].E_MPa": 1.0},
         r"layers\[40\].E_MPa \(layer 41\) = 1.0: layers has 10 entries"),
    ({"numerics.mesh.size_m": -1.0}, r"size_m = -1.0 \(m\)"),
])
def test_bad_overrides_name_the_key(override, match):
    with pytest.raises(ScenarioError, match=match):
        load_scenario("pier667", override)


def test_parse_override_needs_key_and_value():
    with pytest.raises(ScenarioError, match="must be KEY=VALUE"):
        parse_override("numerics.mesh.size_m")


def test_apply_overrides_copies():
    data = {"a": {"b": 1}}
    assert apply_overrides(data, {"a.b": 2}) == {"a": {"b": 2}} and data == {"a": {"b": 1}}
