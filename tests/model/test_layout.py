"""Explicit pile layouts (``piles.layout``): per-pile values, defaults and every rule's message.

Built on the bundled single_pile scenario (no cap, 20 m deep, two layers): fast, no mesh.
"""

import dataclasses
import math
import tomllib

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.model import ScenarioError, bundled_text, scenario_from_dict
from pilegroup.model.mesh_estimate import estimated_cells
from pilegroup.model.piles import MAX_PILES
from pilegroup.studies.cli.commands import EXIT_INPUT, main

SINGLE = bundled_text("single_pile")
GRID = """[piles]
diameter_m = 0.8
length_in_soil_m = 12.0
grid = [1, 1]"""
assert GRID in SINGLE


def _doc(layout=None, **piles):
    """single_pile's document with ``[piles]`` = ``piles`` plus ``layout`` (a list of tables).

    The gauges are left out (they must lie on the shortest pile).
    """
    d = tomllib.loads(SINGLE)
    d["piles"] = dict(piles)
    if layout is not None:
        d["piles"]["layout"] = [dict(e) for e in layout]
    d["outputs"].pop("gauge_depths_m")
    return d


TWO = [{"x_m": -2.0, "y_m": 0.0, "diameter_m": 1.0, "length_in_soil_m": 12.0},
       {"x_m": 2.0, "y_m": 0.0, "diameter_m": 0.6, "length_in_soil_m": 9.0}]


def _error(d):
    with pytest.raises(ScenarioError) as info:
        scenario_from_dict(d)
    return info.value


def test_layout_gives_every_pile_its_own_position_diameter_and_length():
    sc = scenario_from_dict(_doc(TWO))
    p = sc.piles
    assert p.count == 2 and p.xy == ((-2.0, 0.0), (2.0, 0.0))
    assert p.diameters == (1.0, 0.6) and p.lengths == (12.0, 9.0)
    assert p.diameter_m is None and p.length_in_soil_m is None
    spec = geometry_spec(sc)
    assert [(q.x, q.y, q.diameter, q.length_in_soil) for q in spec.piles] == [
        (-2.0, 0.0, 1.0, 12.0), (2.0, 0.0, 0.6, 9.0)]


def test_omitted_values_take_the_piles_level_defaults():
    layout = [{"x_m": -2.0, "y_m": 0.0}, {"x_m": 2.0, "y_m": 0.0, "diameter_m": 0.6},
              {"x_m": 0.0, "y_m": 2.5, "length_in_soil_m": 10.0}]
    p = scenario_from_dict(_doc(layout, diameter_m=0.9, length_in_soil_m=12.0)).piles
    assert p.diameters == (0.9, 0.6, 0.9) and p.lengths == (12.0, 12.0, 10.0)
    assert p.key_of(1, "diameter_m") == "piles.diameter_m"
    assert p.key_of(2, "diameter_m") == "piles.layout[1].diameter_m"
    assert p.key_of(3, "length_in_soil_m") == "piles.layout[2].length_in_soil_m"


def test_array_of_tables_syntax_reads_the_same():
    text = SINGLE.replace("gauge_depths_m = [1.0, 4.0, 8.0, 11.5]\n", "").replace(GRID, """
[piles]
embedment_m = 0.0

[[piles.layout]]
x_m = -2.0
y_m = 0.0
diameter_m = 1.0
length_in_soil_m = 12.0

[[piles.layout]]
x_m = 2.0
y_m = 0.0
diameter_m = 0.6
length_in_soil_m = 9.0
""")
    assert scenario_from_dict(tomllib.loads(text)).piles == scenario_from_dict(_doc(TWO)).piles


def test_grid_and_positions_are_shorthands_for_equal_piles():
    grid = scenario_from_dict(_doc(diameter_m=0.8, length_in_soil_m=12.0, grid=[2, 1],
                                   spacing_m=[3.0, 3.0])).piles
    assert grid.diameters == (0.8, 0.8) and grid.lengths == (12.0, 12.0)
    pos = scenario_from_dict(_doc(diameter_m=0.8, length_in_soil_m=12.0,
                                  positions_m=[[-1.5, 0.0], [1.5, 0.0]])).piles
    assert pos.xy == grid.xy and pos.diameters == grid.diameters
    assert pos.key_of(1, "diameter_m") == "piles.diameter_m"


def test_a_layout_of_equal_piles_is_the_positions_scenario():
    """Same piles, same geometry spec and cache key: the same mesh, the same cell estimate."""
    xy = [[-1.5, -1.2], [1.5, -1.2], [-1.5, 1.2], [1.5, 1.2]]
    pos = scenario_from_dict(_doc(diameter_m=0.8, length_in_soil_m=12.0, positions_m=xy))
    lay = scenario_from_dict(_doc([{"x_m": x, "y_m": y} for x, y in xy], diameter_m=0.8,
                                  length_in_soil_m=12.0))
    assert geometry_spec(lay) == geometry_spec(pos)
    assert geometry_spec(lay).cache_key() == geometry_spec(pos).cache_key()
    assert estimated_cells(lay) == estimated_cells(pos)


# ---- the messages: one line naming the key, the value and what is allowed ----
@pytest.mark.parametrize("key", ["rake_deg", "batter", "inclination_deg", "batter_ratio"])
def test_a_rake_is_rejected_vertical_piles_only(key):
    layout = [TWO[0], dict(TWO[1], **{key: 5.0})]
    err = _error(_doc(layout))
    assert err.key == f"piles.layout[1].{key}" and err.value == 5.0
    assert "raked piles are not supported" in str(err) and "vertical" in str(err)
    assert "x_m, y_m, diameter_m, length_in_soil_m" in str(err)


def test_any_unknown_key_of_an_entry_lists_the_keys_and_says_vertical_only():
    err = _error(_doc([dict(TWO[0], colour="red"), TWO[1]]))
    assert err.key == "piles.layout[0].colour"
    assert "unknown key; allowed keys: x_m, y_m, diameter_m, length_in_soil_m" in str(err)
    assert "raked piles are not supported" in str(err)


def test_a_rake_exits_2_with_one_line(tmp_path, capsys):
    f = tmp_path / "raked.toml"
    f.write_text(SINGLE.replace(GRID, """[piles]
layout = [ { x_m = -2.0, y_m = 0.0, diameter_m = 1.0, length_in_soil_m = 12.0 },
           { x_m = 2.0, y_m = 0.0, diameter_m = 0.6, length_in_soil_m = 11.5, rake_deg = 10.0 } ]
"""))
    assert main(["scenario", "validate", str(f)]) == EXIT_INPUT
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("pilegroup: invalid input: ")
    assert "piles.layout[1].rake_deg (pile 2) = 10.0" in err
    assert "raked piles are not supported" in err


@pytest.mark.parametrize("key", ["diameter_m", "length_in_soil_m"])
def test_a_missing_value_names_the_entry(key):
    layout = [TWO[0], TWO[1], {k: v for k, v in TWO[1].items() if k != key} | {"y_m": 3.0}]
    err = _error(_doc(layout))
    assert err.key == f"piles.layout[2].{key}" and err.value is None
    assert f"piles.{key}" in err.allowed and "missing" in err.allowed


@pytest.mark.parametrize("key", ["diameter_m", "length_in_soil_m"])
def test_the_shorthands_still_need_both_values(key):
    piles = {"diameter_m": 0.8, "length_in_soil_m": 12.0, "grid": [1, 1]}
    del piles[key]
    err = _error(_doc(**piles))
    assert err.key == f"piles.{key}" and "missing key" in str(err)


@pytest.mark.parametrize(("piles", "key", "words"), [
    ({"grid": [2, 1], "spacing_m": [4.0, 4.0]}, "piles.layout", "here also grid"),
    ({"positions_m": [[-2.0, 0.0], [2.0, 0.0]]}, "piles.layout", "here also positions_m"),
    ({"spacing_m": [4.0, 4.0]}, "piles.spacing_m", "goes with grid only: leave it out with"
                                                   " layout"),
])
def test_exactly_one_of_grid_positions_and_layout(piles, key, words):
    err = _error(_doc(TWO, **piles))
    assert err.key == key and words in str(err)
    assert "spacing_m" in piles or \
        "give exactly one of grid (with spacing_m), positions_m or layout" in str(err)


def test_no_layout_at_all_names_the_three_ways():
    err = _error(_doc(diameter_m=0.8, length_in_soil_m=12.0))
    assert err.key == "piles.grid" and "positions_m or layout" in str(err)


def test_an_empty_layout_and_too_many_piles():
    assert _error(_doc([])).key == "piles.layout"
    many = [{"x_m": 1.2 * (k % 10), "y_m": 1.2 * (k // 10)} for k in range(MAX_PILES + 1)]
    err = _error(_doc(many, diameter_m=0.5, length_in_soil_m=5.0))
    assert err.key == "piles.layout" and err.value == MAX_PILES + 1
    assert f"at most {MAX_PILES} piles" in str(err)


@pytest.mark.parametrize(("change", "key", "words"), [
    ({"x_m": math.nan}, "piles.layout[1].x_m", "finite"),
    ({"y_m": math.inf}, "piles.layout[1].y_m", "finite"),
    ({"x_m": "2.0"}, "piles.layout[1].x_m", "must be a number"),
    ({"diameter_m": 0.0}, "piles.layout[1].diameter_m", "> 0"),
    ({"diameter_m": 7.0}, "piles.layout[1].diameter_m", "must be in [0.1, 5] (bored and driven"),
    ({"length_in_soil_m": 200.0}, "piles.layout[1].length_in_soil_m", "must be in [1, 150]"),
    ({"length_in_soil_m": -1.0}, "piles.layout[1].length_in_soil_m", "> 0"),
])
def test_entry_values_are_finite_positive_and_in_bounds(change, key, words):
    err = _error(_doc([TWO[0], dict(TWO[1], **change)]))
    assert err.key == key and words in str(err)


def test_overlap_rule_is_the_mean_of_the_two_diameters():
    # centres 0.8 m apart, diameters 1.0 and 0.6: the mean is 0.8, the sections touch
    touching = [dict(TWO[0], x_m=-0.4), dict(TWO[1], x_m=0.4)]
    assert scenario_from_dict(_doc(touching)).piles.count == 2
    err = _error(_doc([dict(TWO[0], x_m=-0.4), dict(TWO[1], x_m=0.399)]))
    assert err.key == "piles.layout[1]" and err.value == [[-0.4, 0.0], [0.399, 0.0]]
    assert ("piles 1 and 2 overlap: centre distance 0.799 m must be >= the mean of their"
            " diameters (1 + 0.6) / 2 = 0.8 m") in str(err)


def test_the_longest_pile_ends_above_the_block_bottom():
    err = _error(_doc([TWO[0], dict(TWO[1], length_in_soil_m=25.0)]))
    assert err.key == "piles.layout[1].length_in_soil_m" and err.value == 25.0
    assert "must be < site.depth_m = 20" in str(err)
    err = _error(_doc([TWO[0], {"x_m": 2.0, "y_m": 0.0}], diameter_m=0.6,
                      length_in_soil_m=19.9))
    assert err.key == "piles.length_in_soil_m" and "room for one element" in str(err)


def test_gauges_lie_on_the_shortest_pile():
    d = _doc(TWO)
    d["outputs"]["gauge_depths_m"] = [1.0, 9.0]
    assert scenario_from_dict(d).outputs.gauge_depths_m == (1.0, 9.0)
    d["outputs"]["gauge_depths_m"] = [1.0, 10.0]
    err = _error(d)
    assert err.key == "outputs.gauge_depths_m[1]" and "shortest" in str(err)


def test_mesh_size_resolves_the_thinnest_pile():
    d = _doc([TWO[0], dict(TWO[1], diameter_m=0.15)])
    d.setdefault("numerics", {}).setdefault("mesh", {})["size_m"] = 1.0
    err = _error(d)
    assert err.key == "numerics.mesh.size_m"
    assert "5 x piles.layout[1].diameter_m = 0.75" in str(err)


def test_interface_needed_down_to_the_longest_pile():
    d = _doc([dict(TWO[0], length_in_soil_m=7.0), dict(TWO[1], length_in_soil_m=9.0)])
    del d["layers"][1]["interface"]  # below 8 m: the 9 m pile reaches it
    err = _error(d)
    assert err.key == "layers[1].interface"
    d["piles"]["layout"][1]["length_in_soil_m"] = 7.5
    assert max(scenario_from_dict(d).piles.lengths) == 7.5


def test_pile_in_the_cap_uses_its_own_radius():
    d = tomllib.loads(bundled_text("pier667"))
    d["piles"] = {"embedment_m": 1.0, "length_in_soil_m": 63.5, "layout": [
        {"x_m": -3.5, "y_m": 0.0, "diameter_m": 1.0}, {"x_m": 3.5, "y_m": 0.0,
                                                       "diameter_m": 2.8}]}
    err = _error(d)  # cap half-width 5.05 m: 3.5 + 1.4 leaves 0.15 m < 0.2 x 1.4
    assert err.key == "piles.layout[1]" and "0.2 x the radius = 0.28 m" in str(err)
    d["piles"]["layout"][1]["diameter_m"] = 2.0
    assert scenario_from_dict(d).piles.diameters == (1.0, 2.0)


def test_estimate_grades_from_every_toe_and_every_diameter():
    one = scenario_from_dict(_doc([dict(TWO[0]), dict(TWO[1], diameter_m=1.0,
                                                      length_in_soil_m=12.0)]))
    two = scenario_from_dict(_doc(TWO))
    assert estimated_cells(two) > estimated_cells(one)


def test_mirror_images_of_different_diameter_break_the_symmetry():
    sc = scenario_from_dict(_doc(TWO))
    geo = resolve_geometry(sc)
    assert geo.symmetry == "half_y"
    assert "pile 1 and its mirror image, pile 2, differ in diameter (1 vs 0.6 m)" in geo.reason
    same = scenario_from_dict(_doc([TWO[0], dict(TWO[1], diameter_m=1.0)]))
    assert "differ in length_in_soil (12 vs 9 m)" in resolve_geometry(same).reason
    equal = dataclasses.replace(same, piles=dataclasses.replace(
        same.piles, layout=(same.piles.layout[0], dataclasses.replace(
            same.piles.layout[1], length_in_soil_m=12.0))))
    assert resolve_geometry(equal).symmetry == "quarter"


ODD = [0, -1.0, 0.3, 1e300, math.nan, math.inf, "1.0", True, [1.0], {"a": 1}, None]


@settings(max_examples=300, deadline=None)
@given(entry=st.integers(0, 2), key=st.sampled_from(["x_m", "y_m", "diameter_m",
                                                    "length_in_soil_m", "rake_deg", "z_m"]),
       value=st.sampled_from(ODD),
       top=st.sampled_from([None, (0.8, 10.0), (-0.8, 10.0), (0.8, "x")]))
def test_mutated_layouts_load_or_raise_one_scenario_error(entry, key, value, top):
    layout = [dict(TWO[0]), dict(TWO[1]), {"x_m": 0.0, "y_m": 3.0, "diameter_m": 0.8,
                                           "length_in_soil_m": 10.0}]
    if value is None:
        layout[entry].pop(key, None)
    else:
        layout[entry][key] = value
    piles = {} if top is None else {"diameter_m": top[0], "length_in_soil_m": top[1]}
    try:
        sc = scenario_from_dict(_doc(layout, **piles))
    except ScenarioError as exc:
        assert exc.key.startswith(("piles", "numerics", "outputs", "layers")) and exc.allowed
    else:
        assert len(sc.piles.diameters) == len(sc.piles.lengths) == sc.piles.count == 3
        assert all(d > 0 for d in sc.piles.diameters) and max(sc.piles.lengths) < 20.0
