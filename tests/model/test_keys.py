"""The scenario reference (docs/scenario.md) is generated from the validator's dataclasses.

It fails when the page and the dataclasses differ (regenerate with
``pilegroup scenario keys --markdown > docs/scenario.md``), when a key lacks its meaning or,
being a number, what is allowed, and when a key of a bundled scenario is missing from it.
"""

import tomllib
from pathlib import Path

import pytest

from pilegroup.model import BUNDLED, bundled_text, keys
from pilegroup.model.bounds import BOUNDS
from pilegroup.studies.cli.commands import EXIT_INPUT, main

DOC = Path(__file__).resolve().parents[2] / "docs" / "scenario.md"


def test_docs_scenario_md_is_the_generated_reference():
    assert DOC.read_text() == keys.markdown(), (
        "docs/scenario.md differs from the scenario's dataclasses: regenerate it with "
        "`pilegroup scenario keys --markdown > docs/scenario.md`")


def test_every_key_says_what_it_means_and_what_is_allowed():
    for k in keys.keys():
        assert k.meaning, f"{k.path}: give the field a docstring (its meaning)"
        if k.type in ("number", "integer") or k.type.startswith("list of"):
            assert k.allowed, f"{k.path}: give it a bound (model/bounds.py) or an 'allowed' rule"
        assert k.used_by


def test_a_key_s_unit_suffix_and_its_bound_agree():
    by_path = {k.path: k for k in keys.keys()}
    for path, bound in BOUNDS.items():
        suffix = next((u for s, u in keys.SUFFIX_UNITS if path.endswith(s)), None)
        if path in by_path and suffix is not None:
            assert suffix == bound.unit == by_path[path].unit, path
    assert by_path["numerics.newton_atol"].unit == "kN, m^3"  # the field's own unit


def _paths(node, prefix=""):
    """Every key path of a TOML document, without list indices (tables of keys: their keys)."""
    for k, v in node.items():
        path = f"{prefix}{k}"
        if isinstance(v, dict) and path not in ("numerics.solver.options",):
            yield from _paths(v, path + ".")
        elif isinstance(v, list) and v and isinstance(v[0], dict):
            for entry in v:
                yield from _paths(entry, path + ".")
        else:
            yield path


@pytest.mark.parametrize("name", BUNDLED)
def test_every_key_of_the_bundled_scenarios_is_listed(name):
    listed = {k.path for k in keys.keys()}
    doc = tomllib.loads(bundled_text(name))
    doc.update(doc.pop("scenario"))
    missing = sorted(set(_paths(doc)) - listed)
    assert not missing, missing


def test_stage_keys_say_which_kinds_use_them():
    by_path = {k.path: k for k in keys.keys()}
    assert by_path["stages.drawdown_m"].used_by == "stages of kind groundwater (required)"
    assert "soil.model mohr_coulomb, drucker_prager" in by_path["layers.phi_deg"].used_by
    assert by_path["layers.phi_deg"].default == "not set"
    assert by_path["layers.interface.eta_MPa_day"].used_by == "interface.mode viscoplastic"


def test_scenario_keys_prints_a_table(capsys):
    assert main(["scenario", "keys", "numerics.mesh"]) == 0
    out = capsys.readouterr().out
    assert out.startswith("[numerics.mesh]") and "size_m" in out and "automatic" in out
    assert main(["scenario", "keys", "scenario"]) == 0
    assert capsys.readouterr().out.startswith("[scenario]")
    assert main(["scenario", "keys", "nope"]) == EXIT_INPUT
    assert "TABLE = 'nope': unknown table" in capsys.readouterr().err
    assert main(["scenario", "keys", "--markdown"]) == 0
    assert capsys.readouterr().out == keys.markdown()


def test_the_page_states_the_coordinates_once():
    text = keys.markdown()
    assert text.count("z = 0 is the ground surface") == 1
    assert "x and y are horizontal, z points up" in text
