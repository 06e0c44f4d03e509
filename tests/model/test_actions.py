"""The cap actions of a scenario: keys, validation, holding, the action point, symmetry."""

from __future__ import annotations

import numpy as np
import pytest

from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.model import ScenarioError, load_scenario
from pilegroup.model.actions import held_actions, transfer


def _pier(**overrides):
    return load_scenario("pier667", overrides=overrides)


def test_vertical_load_as_fz_equals_cap_load():
    a = _pier()
    b = _pier(**{"stages[1].cap_load_kN": None, "stages[1].Fz_kN": -10856.0})
    assert a.total_cap_load() == b.total_cap_load() == 10856.0
    assert np.array_equal(a.cap_actions()[0][1], b.cap_actions()[0][1])


@pytest.mark.parametrize("overrides, key, words", [
    ({"stages[1].Fz_kN": -5.0}, "stages[1].cap_load_kN", "not both"),
    ({"stages[1].cap_load_kN": None}, "stages[1].cap_load_kN", "neither"),
    ({"stages[1].cap_load_kN": None, "stages[1].Fz_kN": 5.0}, "stages[1].Fz_kN", "uplift"),
    ({"stages[1].Fx_kN": float("nan")}, "stages[1].Fx_kN", "finite"),
    ({"stages[1].My_kNm": 1e11}, "stages[1].My_kNm", "typo guard"),
    ({"stages[2].Fx_kN": 5.0}, "stages[2].Fx_kN", "not allowed"),
    ({"actions.point_m": [0.0, float("inf"), 1.0]}, "actions.point_m[1]", "finite"),
])
def test_bad_actions_name_the_key(overrides, key, words):
    with pytest.raises(ScenarioError) as exc:
        _pier(**overrides)
    assert str(exc.value).startswith(key), str(exc.value)
    assert words in str(exc.value)


def test_lateral_actions_need_a_cap_or_a_single_pile():
    sc = load_scenario("single_pile", overrides={"stages[1].Fx_kN": 10.0})
    assert sc.has_lateral_actions()
    with pytest.raises(ScenarioError, match="need a cap") as exc:
        load_scenario("single_pile", overrides={
            "piles.grid": [2, 1], "piles.spacing_m": [3.0, 3.0], "stages[1].Fy_kN": 10.0})
    assert str(exc.value).startswith("stages[1].Fy_kN")


def test_components_are_held_until_a_stage_sets_them():
    held = held_actions([[1.0, None, -5.0, None, None, None],
                         [None, 2.0, None, None, None, None],
                         [0.0, None, -7.0, None, None, 3.0]])
    assert np.allclose(held[1], [1.0, 2.0, -5.0, 0.0, 0.0, 0.0])
    assert np.allclose(held[2], [0.0, 2.0, -7.0, 0.0, 0.0, 3.0])


def test_moments_move_to_the_face_centre():
    # a horizontal force 9.5 m above the cap top is a moment about y at the top
    sc = _pier(**{"stages[1].Fx_kN": 500.0, "actions.point_m": [0.0, 0.0, 12.0]})
    a = sc.cap_actions()[0][1]
    assert np.allclose(a, [500.0, 0.0, -10856.0, 0.0, 500.0 * 9.5, 0.0])
    # the vertical load off the centre by e along y gives Mx = e Fz
    b = transfer(np.array([0, 0, -100.0, 0, 0, 0]), (0.0, 2.0, 0.0), (0.0, 0.0, 0.0))
    assert np.allclose(b[3:], [-200.0, 0.0, 0.0])


@pytest.mark.parametrize("overrides, mode, why", [
    ({}, "quarter", None),
    ({"stages[1].Fx_kN": 500.0}, "half_y", "Fx = 500"),
    ({"stages[1].My_kNm": 50.0}, "half_y", "My = 50"),
    ({"stages[1].Fy_kN": 5.0}, "half_x", "Fy = 5"),
    ({"stages[1].Mx_kNm": 5.0}, "half_x", "Mx = 5"),
    ({"stages[1].Mz_kNm": 5.0}, "none", "Mz = 5"),
    ({"actions.point_m": [0.0, 1.0, 5.0]}, "half_x", "Mx = -10856"),
])
def test_symmetry_follows_the_actions(overrides, mode, why):
    geo = resolve_geometry(_pier(**overrides))
    assert geo.symmetry == mode
    if why is not None:
        assert why in geo.reason


def test_explicit_symmetry_against_the_actions_is_an_error():
    with pytest.raises(ScenarioError, match="numerics.symmetry"):
        resolve_geometry(_pier(**{"stages[1].Fx_kN": 5.0, "numerics.symmetry": "quarter"}))
