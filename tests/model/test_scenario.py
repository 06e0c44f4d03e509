"""Scenario loading and validation: every rule, on broken copies of pier667.toml."""

import dataclasses
import math
import subprocess
import sys
import tomllib

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pilegroup.constitutive.paper import delta_eq17
from pilegroup.model import Layer, ScenarioError, bundled_text, load_scenario, scenario_from_dict
from pilegroup.studies.cli.commands import EXIT_INPUT, main

PIER = bundled_text("pier667")


def _first_layer_block_replace(text, old, new, occurrence: int = 1) -> str:
    """Replace the ``occurrence``-th exact line ``old`` with ``new`` (or several, as tuples)."""
    if isinstance(old, tuple):
        for o, n in zip(old, new, strict=True):
            text = _first_layer_block_replace(text, o, n, occurrence)
        return text
    lines = text.splitlines()
    seen = 0
    for i, line in enumerate(lines):
        if old in (line.strip(), line.split("#")[0].strip()):
            seen += 1
            if seen == occurrence:
                lines[i] = new
                return "\n".join(lines) + "\n"
    raise AssertionError(f"line {old!r} (occurrence {occurrence}) not in pier667.toml")


# (id, old line, new line, occurrence, key named in the message, words that must appear)
BROKEN = [
    ("unknown-key", "water_table_depth_m = 0.0", "water_table_depth_m = 0.0\ncolour = 1", 1,
     "site.colour", "unknown key"),
    ("missing-key", "diameter_m = 1.0", "", 1, "piles.diameter_m", "missing key"),
    ("water-table-below-block", "water_table_depth_m = 0.0", "water_table_depth_m = 128.0", 1,
     "site.water_table_depth_m", "must be in [0, 128) (in the soil block"),
    ("wrong-type", "E_MPa = 6.8", 'E_MPa = "soft"', 1, "layers[0].E_MPa", "must be a number"),
    ("wrong-type-int", "grid = [3, 3]", "grid = [3.0, 3]", 1, "piles.grid[0]", "integer"),
    ("thickness-nonpositive", "thickness_m = 19.3", "thickness_m = -1.0", 1,
     "layers[1].thickness_m", "> 0"),
    ("modulus-nonpositive", "E_MPa = 3.0", "E_MPa = 0.0", 1, "layers[1].E_MPa", "> 0"),
    ("structure-modulus", "E_MPa = 32300.0", "E_MPa = -5.0", 1, "structure.E_MPa", "> 0"),
    ("diameter-nonpositive", "diameter_m = 1.0", "diameter_m = 0", 1, "piles.diameter_m", "> 0"),
    ("nu-high", "nu = 0.42", "nu = 0.5", 1, "layers[1].nu", "(0, 0.5)"),
    ("nu-zero", "nu = 0.17", "nu = 0.0", 1, "structure.nu", "(0, 0.5)"),
    ("phi-60", "phi_deg = 35", "phi_deg = 60", 1, "layers[7].phi_deg", "[0, 60)"),
    ("phi-negative", "phi_deg = 2.6", "phi_deg = -1", 1, "layers[1].phi_deg", "[0, 60)"),
    ("pile-longer-than-block", "length_in_soil_m = 63.5", "length_in_soil_m = 130.0", 1,
     "piles.length_in_soil_m", "longer than the block"),
    ("pile-outside-cap", "spacing_m = [3.5, 2.5]", "spacing_m = [4.8, 2.5]", 1,
     "piles.grid", "pile 1 (diameter 1 m) lies outside the cap"),
    ("piles-overlap", "spacing_m = [3.5, 2.5]", "spacing_m = [0.8, 2.5]", 1,
     "piles.spacing_m", "overlap"),
    ("stack-short-of-toe", ("# thickness_m omitted: layer 10 extends to the bottom of the block",
                            "length_in_soil_m = 63.5"),
     ("thickness_m = 1.0", "length_in_soil_m = 70.0"), 1, "layers", "must reach the pile toe"),
    ("end-before-load", "duration_day = 1.0", "duration_day = 400.0", 1, "time.end_day",
     "end of load stage"),
    ("bad-choice", "[numerics.time]", '[numerics]\nelement = "P3"\n[numerics.time]', 1,
     "numerics.element", "one of"),
    ("bad-symmetry", "[numerics.time]", '[numerics]\nsymmetry = "octant"\n[numerics.time]', 1,
     "numerics.symmetry", "one of 'auto'"),
    ("bad-interface-quadrature", "base = true", 'base = true\nquadrature = "lobatto"', 1,
     "interface.quadrature", "one of 'nodal', 'gauss'"),
    ("output-after-end", "output_days = [0.0, 1.0, 30.0, 89.0, 180.0, 317.0]",
     "output_days = [0.0, 400.0]", 1, "time.output_days[1]", "end_day"),
    ("output-unsorted", "output_days = [0.0, 1.0, 30.0, 89.0, 180.0, 317.0]",
     "output_days = [0.0, 30.0, 1.0, 317.0]", 1, "time.output_days[2]",
     "= 1.0 (day): must be > 30, the time before it: output times are listed in increasing "
     "order, each once"),
    ("output-twice", "output_days = [0.0, 1.0, 30.0, 89.0, 180.0, 317.0]",
     "output_days = [0.0, 1.0, 1.0, 317.0]", 1, "time.output_days[2]",
     "= 1.0 (day): must be > 1, the time before it"),
]


@pytest.mark.parametrize("case", BROKEN, ids=[c[0] for c in BROKEN])
def test_each_rule_names_key_and_value(case):
    _, old, new, occ, key, words = case
    text = _first_layer_block_replace(PIER, old, new, occ)
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(tomllib.loads(text))
    assert info.value.key == key
    assert words in str(info.value)
    assert str(info.value).startswith(key)


def _pier_dict():
    return tomllib.loads(PIER)


def test_layer_stack_must_reach_pile_toe():
    d = _pier_dict()
    d["layers"][-1]["thickness_m"] = 1.0  # stack now ends at 65.3 m
    d["piles"]["length_in_soil_m"] = 70.0
    with pytest.raises(ScenarioError, match="must reach the pile toe at 70 m") as info:
        scenario_from_dict(d)
    assert info.value.key == "layers"


def test_layer_stack_must_fill_block_or_leave_last_open():
    d = _pier_dict()
    d["layers"][-1]["thickness_m"] = 1.0
    with pytest.raises(ScenarioError, match="must equal site.depth_m = 128"):
        scenario_from_dict(d)
    d["layers"][-1]["thickness_m"] = 128.0 - 64.3
    assert scenario_from_dict(d).layer_bottom(9) == pytest.approx(128.0)


def test_only_last_layer_may_omit_thickness():
    d = _pier_dict()
    del d["layers"][3]["thickness_m"]
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d)
    assert info.value.key == "layers[3].thickness_m"


def test_interface_parameters_required_where_piles_cross_a_layer():
    d = _pier_dict()
    del d["layers"][8]["interface"]
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d)
    assert info.value.key == "layers[8].interface"
    d["interface"]["mode"] = "tied"
    assert scenario_from_dict(d).interface.mode == "tied"


def test_interface_quadrature_reaches_the_solver_coupling():
    from pilegroup.studies.run.pipeline import interface_coupling

    d = _pier_dict()
    assert "quadrature" not in d["interface"]  # optional key: the bundled scenario omits it
    assert scenario_from_dict(d).interface.quadrature == "nodal"
    d["interface"]["quadrature"] = "gauss"
    d["numerics"] = {"element": "Q1Q1"}  # Gauss points on trilinear facets
    sc = scenario_from_dict(d)
    assert sc.interface.quadrature == "gauss"
    assert interface_coupling(sc, sc.numerics.mesh.size_m).quadrature == "gauss"


def test_bundled_pier667_matches_paper():
    sc = load_scenario("pier667")
    assert sc.piles.count == 9
    assert len(sc.layers) == 10
    assert sc.total_cap_load() == 10856.0
    assert sc.layer_depths()[9] == pytest.approx(64.3)
    assert sc.layers[1].E == pytest.approx(3000.0)  # kPa
    assert sc.layers[1].interface.eta == pytest.approx(6230.0)  # kPa day / m
    # Eq. 17 reproduces Table 1's delta where the table gives one (to the table's 0.1 degree)
    for layer in sc.layers:
        if layer.interface is not None:
            assert delta_eq17(layer.phi_deg) == pytest.approx(layer.interface.delta_deg,
                                                                  abs=0.06)
    stages = sc.stage_times()
    assert [(s.kind, a, b) for s, a, b in stages] == [
        ("geostatic", 0.0, 0.0), ("load", 0.0, 1.0), ("consolidation", 1.0, 317.0)]


def test_single_pile_and_other_grids_are_expressible():
    d = _pier_dict()
    d["piles"] = {"diameter_m": 0.8, "length_in_soil_m": 20.0, "grid": [1, 1]}
    d["layers"] = [dict(d["layers"][1], thickness_m=None)]
    del d["layers"][0]["thickness_m"]
    del d["cap"]
    d["outputs"]["gauge_depths_m"] = [1.0, 19.0]
    d.pop("reference")  # the paper's values name layers of the pier
    sc = scenario_from_dict(d)
    assert sc.piles.xy == ((0.0, 0.0),)
    d["piles"] = {"diameter_m": 0.6, "length_in_soil_m": 20.0,
                  "positions_m": [[0, 0], [2, 0], [0, 2], [2, 2], [4, 4]]}
    assert scenario_from_dict(d).piles.count == 5


@given(st.floats(allow_nan=True, allow_infinity=True, width=64))
def test_property_nu_accepted_iff_in_open_interval(nu):
    base = load_scenario("pier667").layers[0]
    ok = 0.0 < nu < 0.5
    try:
        dataclasses.replace(base, nu=nu)
    except ScenarioError as exc:
        assert not ok and exc.key == "nu"
    else:
        assert ok


@given(st.floats(min_value=-100, max_value=100))
def test_property_phi_accepted_iff_in_range(phi):
    base = load_scenario("pier667").layers[0]
    ok = 0.0 <= phi < 60.0
    try:
        Layer(**{**dataclasses.asdict(base), "phi_deg": phi, "psi_deg": 0.0, "interface": None})
    except ScenarioError as exc:
        assert not ok and exc.key == "phi_deg"
    else:
        assert ok and math.isfinite(phi)


def test_cli_validate_broken_file_exits_2_with_one_line(tmp_path, capsys):
    for name, old, new, occ, key, _ in BROKEN:
        f = tmp_path / f"{name}.toml"
        f.write_text(_first_layer_block_replace(PIER, old, new, occ))
        assert main(["scenario", "validate", str(f)]) == EXIT_INPUT, name
        err = capsys.readouterr().err.strip()
        assert len(err.splitlines()) == 1 and key in err, (name, err)


def test_console_script_has_no_traceback(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text(_first_layer_block_replace(PIER, "nu = 0.42", "nu = 0.7"))
    r = subprocess.run([sys.executable, "-m", "pilegroup", "scenario", "validate", str(f)],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 2
    assert "Traceback" not in r.stderr
    assert "layers[1].nu (layer 2) = 0.7 (-): must be in (0, 0.5)" in r.stderr


def test_missing_file_and_bad_toml(tmp_path, capsys):
    assert main(["scenario", "validate", str(tmp_path / "nope.toml")]) == EXIT_INPUT
    f = tmp_path / "x.toml"
    f.write_text("[site\n")
    assert main(["scenario", "validate", str(f)]) == EXIT_INPUT
    assert "not valid TOML" in capsys.readouterr().err


def test_show_prints_bundled_scenario(capsys):
    assert main(["scenario", "show"]) == 0
    assert capsys.readouterr().out == PIER


def test_geometry_adapter_reproduces_bundled_pier():
    from pilegroup.geometry.adapter import geometry_spec
    from pilegroup.geometry.spec import pier667_default

    g = geometry_spec(load_scenario("pier667", {"numerics.element": "Q1Q1"}))
    ref = pier667_default()  # the trilinear sizes
    assert (g.block, g.piles, g.cap, g.sizing) == (ref.block, ref.piles, ref.cap, ref.sizing)
    assert g.symmetry == "quarter"  # numerics.symmetry = "auto" (the default)
    assert [lay.thickness for lay in g.layers] == [lay.thickness for lay in ref.layers]
    assert geometry_spec(load_scenario("pier667"), mesh_size=0.3).sizing.h_pile == 0.3


@pytest.mark.parametrize("mode, contact", [("tied", False), ("viscoplastic", True),
                                           ("elastic", True)])
def test_cap_contact_that_contradicts_the_interface_model_is_invalid(mode, contact):
    with pytest.raises(ScenarioError, match="cap.in_contact_with_soil"):
        load_scenario("pier667", {"interface.mode": mode, "cap.in_contact_with_soil": contact})


@pytest.mark.parametrize("mode, contact", [("tied", True), ("viscoplastic", False),
                                           ("tied", None)])
def test_cap_contact_that_follows_the_interface_model_is_valid(mode, contact):
    sets = {"interface.mode": mode} | ({} if contact is None else
                                       {"cap.in_contact_with_soil": contact})
    assert load_scenario("pier667", sets).cap.in_contact_with_soil is contact


def test_a_stage_that_unloads_is_a_load_factor_below_one():
    """Load factor 1 is the largest cap load, not the last one: a load stage that takes the
    load off to 0 after the loading ramps the factor from 1 to 0 (a run of it once applied no
    load at all, the last load being 0)."""
    from pilegroup.studies.run.pipeline import solver_stages

    d = tomllib.loads(bundled_text("single_pile"))
    d["stages"][2] = {"name": "unloading", "kind": "load", "cap_load_kN": 0.0,
                      "duration_day": 2.0}
    d["stages"].append({"name": "rest", "kind": "consolidation"})
    sc = scenario_from_dict(d)
    assert sc.total_cap_load() == 500.0
    factors = [st.load_factor for st in solver_stages(sc) if st.kind == "load"]
    assert factors == [1.0, 0.0]
    d["stages"][2]["cap_load_kN"] = 250.0
    assert [st.load_factor for st in solver_stages(scenario_from_dict(d))
            if st.kind == "load"] == [1.0, 0.5]
