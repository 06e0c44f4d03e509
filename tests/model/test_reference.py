"""The optional ``[reference]`` table: published values, validated like every other key."""

from dataclasses import replace

import pytest

from pilegroup.model import ScenarioError, load_scenario


def test_only_the_pier667_scenarios_carry_one():
    for name in ("single_pile", "group2x3_lateral", "group3x3_downdrag"):
        assert load_scenario(name).reference is None, name
    full, lateral, downdrag = (load_scenario(n).reference
                               for n in ("pier667", "pier667_lateral", "pier667_downdrag"))
    # the paper's mesh study (Table 2) is of the pier under its vertical load: pier667's only
    assert replace(full, mesh_study=None) == lateral and full.gauge_sections == (1, 5, 11, 17)
    assert full.mesh_study.elements[0] == 57108 and lateral.mesh_study is None
    assert downdrag.settlement_m is None and downdrag.soft_layers == (1, 2, 3)
    assert downdrag.mesh_study is None


def test_a_reference_set_from_the_command_line():
    ref = load_scenario("single_pile", {"reference.source": "site log 2024",
                                        "reference.settlement_m": 0.02}).reference
    assert ref.source == "site log 2024" and ref.settlement_m == 0.02 and ref.soft_layers == ()


def test_a_published_mesh_study_from_the_command_line():
    ref = load_scenario("single_pile", {
        "reference.source": "a report", "reference.mesh_study.sizes_m": [1.0, 0.5],
        "reference.mesh_study.settlements_m": [0.02, 0.021]}).reference
    assert ref.mesh_study.sizes_m == (1.0, 0.5) and ref.mesh_study.hours == ()
    assert ref.mesh_study.at(ref.mesh_study.settlements_m, 0.5) == 0.021
    assert ref.mesh_study.at(ref.mesh_study.settlements_m, 0.3) is None


@pytest.mark.parametrize(("key", "value", "message"), [
    ("reference.soft_layers", [1, 3], "reference.soft_layers[1] = 3: must be <= 2"),
    ("reference.soft_layers", [2, 1], "reference.soft_layers[1] = 1: must be >= 1 and greater"),
    ("reference.gauge_sections", [5], "reference.gauge_sections[0] = 5: must be <= 4"),
    ("reference.settlement_m", -0.1, "reference.settlement_m = -0.1"),
    ("reference.source", " ", "must name where the values are published"),
    ("reference.nope", 1, "reference.nope = 1: unknown key"),
    ("reference.mesh_study", {"settlements_m": [0.1]}, "reference.mesh_study.sizes_m"),
    ("reference.mesh_study", {"sizes_m": [0.5, 1.0], "settlements_m": [0.1, 0.2]},
     "reference.mesh_study.sizes_m[1] = 1.0 (m): must be smaller than the size before it"),
    ("reference.mesh_study", {"sizes_m": [1.0, 0.5], "settlements_m": [0.1]},
     "reference.mesh_study.settlements_m = [0.1]: must give one value per size"),
    ("reference.mesh_study", {"sizes_m": [1.0], "settlements_m": [0.1], "hours": [-1.0]},
     "reference.mesh_study.hours[0] = -1"),
])
def test_bad_values_are_refused_with_their_key(key, value, message):
    sets = {"reference.source": "a test", key: value}
    with pytest.raises(ScenarioError) as info:
        load_scenario("single_pile", sets)
    assert message in str(info.value)
