"""The automatic discretisation: element pair and mesh sizes chosen from the scenario.

docs/model.md, "The default discretisation"; pilegroup.model.mesh_defaults.
"""

import tomllib

import pytest

from pilegroup.errors import ScenarioError
from pilegroup.model import bundled_text, scenario_from_dict
from pilegroup.model.loader import BUNDLED
from pilegroup.model.mesh_defaults import UNKNOWN_BUDGET
from pilegroup.model.mesh_estimate import estimated_unknowns
from pilegroup.model.mirror import kept_fraction

#: The trilinear sizes of Pier 667: those its mesh study validated (docs/results.md).
PIER_SIZES = {"size_m": 1.0, "far_field_size_m": 16.0, "growth": 1.6, "n_circ_min": 28,
              "dz_surface_m": 1.0, "dz_toe_m": 1.0, "dz_max_m": 6.0, "dz_max_deep_m": 15.0,
              "dz_growth": 1.4, "dz_cap_m": 1.5, "min_layer_divisions": 2}
#: Its default: Q2Q1 at the axial sizes (every length 4 times the trilinear one, the size next
#: to the piles from the clear gap of 1.5 m, the cap's at most its 2.5 m; 8 edges).
PIER_AXIAL = {"size_m": 3.0, "far_field_size_m": 32.0, "growth": 1.6, "n_circ_min": 8,
              "dz_surface_m": 4.0, "dz_toe_m": 4.0, "dz_max_m": 24.0, "dz_max_deep_m": 60.0,
              "dz_growth": 1.4, "dz_cap_m": 2.5, "min_layer_divisions": 1}


def doc(name="pier667", element=None):
    data = tomllib.loads(bundled_text(name))
    if element is not None:
        data.setdefault("numerics", {})["element"] = element
    return data


def group(n, d, length=40.0, lateral=False):
    """An n x n group of piles of diameter d at 3 d under a cap, five layers, no [numerics]."""
    data = doc("pier667")
    s = 3.0 * d
    width = (n - 1) * s + 2.0 * d
    data["piles"] = {"diameter_m": d, "length_in_soil_m": length, "embedment_m": 0.5,
                     "grid": [n, n], "spacing_m": [s, s]}
    data["cap"] = {"size_x_m": width, "size_y_m": width, "thickness_m": 2.0}
    data["site"] |= {"size_x_m": width + 60.0, "size_y_m": width + 60.0,
                     "depth_m": length + 30.0}
    data["layers"] = data["layers"][:4] + [data["layers"][-1]]
    data["layers"][-1]["interface"] = data["layers"][3]["interface"]  # the piles reach it
    data["outputs"].pop("gauge_depths_m")
    data.pop("reference")  # the paper's values name layers and gauges of the pier
    if lateral:
        data["stages"][1] |= {"Fx_kN": 500.0}
    data.pop("numerics", None)
    return data


@pytest.mark.parametrize("name", BUNDLED)
def test_bundled_scenarios_use_the_defaults(name):
    data = doc(name)
    assert "element" not in data.get("numerics", {})
    assert "mesh" not in data.get("numerics", {})
    sc = scenario_from_dict(data)
    assert set(sc.numerics.mesh.automatic) == set(PIER_SIZES)


def test_pier_defaults_are_q2q1_at_the_axial_sizes():
    sc = scenario_from_dict(doc())
    assert sc.numerics.mesh.given() == pytest.approx(PIER_AXIAL | {"scale": 1.0})
    assert sc.numerics.element == "Q2Q1"
    assert sc.numerics.element_reason.startswith("auto: every action is vertical")
    assert sc.locking_reason() is None and sc.discretisation_warning() is None


def test_an_explicit_q1q1_gets_the_validated_trilinear_mesh():
    sc = scenario_from_dict(doc(element="Q1Q1"))
    assert sc.numerics.mesh.given() == PIER_SIZES | {"scale": 1.0}
    assert sc.numerics.element_reason == "numerics.element"


def test_vertical_actions_take_twice_the_bending_lengths_and_8_edges():
    """The same 2 x 2 group with and without a horizontal force: Q2Q1 both; without it every
    automatic length twice the bending one and 8 edges around a pile instead of 16."""
    axial = scenario_from_dict(group(2, 1.2)).numerics
    bending = scenario_from_dict(group(2, 1.2, lateral=True)).numerics
    assert axial.element == bending.element == "Q2Q1"
    assert (axial.mesh.n_circ_min, bending.mesh.n_circ_min) == (8, 16)
    for k in ("size_m", "far_field_size_m", "dz_surface_m", "dz_toe_m", "dz_max_m",
              "dz_max_deep_m"):
        assert getattr(axial.mesh, k) == pytest.approx(2.0 * getattr(bending.mesh, k)), k
    assert axial.mesh.dz_cap_m == bending.mesh.dz_cap_m == 2.0  # the cap's thickness


def test_the_whole_pier_takes_q2q1_at_the_axial_sizes():
    """Its estimate, 239,911 unknowns (215,471 meshed), fits the budget."""
    data = doc()
    data.setdefault("numerics", {})["symmetry"] = "none"
    sc = scenario_from_dict(data)
    assert sc.numerics.element == "Q2Q1" and sc.numerics.mesh.given() == PIER_AXIAL | {"scale": 1.0}
    assert 200_000 < estimated_unknowns(sc) < 300_000


def test_where_q2q1_exceeds_the_budget_vertical_actions_take_q1q1_without_a_warning():
    data = group(8, 1.0)
    data["numerics"] = {"symmetry": "none"}  # the whole block of an 8 x 8 group
    sc = scenario_from_dict(data)
    assert sc.numerics.element == "Q1Q1" and "memory budget" in sc.numerics.element_reason
    assert estimated_unknowns(sc) <= UNKNOWN_BUDGET
    assert sc.discretisation_warning() is None  # nothing bends


def test_given_keys_are_kept_and_others_stay_automatic():
    data = doc()
    data["numerics"] = {"mesh": {"size_m": 0.3, "n_circ_min": 16}}
    sc = scenario_from_dict(data)
    m = sc.numerics.mesh
    assert (m.size_m, m.n_circ_min) == (0.3, 16)
    assert "size_m" not in m.automatic and "dz_max_m" in m.automatic
    assert m.dz_max_m == PIER_AXIAL["dz_max_m"]


def test_given_far_field_below_the_automatic_size_keeps_the_scenario_valid():
    data = doc()
    data["numerics"] = {"mesh": {"far_field_size_m": 0.5}}
    m = scenario_from_dict(data).numerics.mesh
    assert m.size_m <= m.far_field_size_m == 0.5


def test_automatic_is_not_a_scenario_key():
    data = doc()
    data["numerics"] = {"mesh": {"automatic": ["size_m"]}}
    with pytest.raises(ScenarioError, match="unknown key"):
        scenario_from_dict(data)


@pytest.mark.parametrize("n", [2, 4, 6])
@pytest.mark.parametrize("d", [0.3, 1.0, 2.5])
def test_groups_up_to_6x6_fit_the_budget(n, d):
    """The budget holds for the part the run models (a quarter for these symmetric groups)."""
    sc = scenario_from_dict(group(n, d))
    assert kept_fraction(sc) == 0.25
    assert estimated_unknowns(sc, kept_fraction(sc)) <= UNKNOWN_BUDGET


def test_the_budget_is_on_the_part_modelled():
    """A 6 x 6 group of 1 m piles in the pier's soil: its quarter fits the budget at the nominal
    sizes (h = d, 28 edges around a pile), where its whole block would not; the full model of
    the same group (``numerics.symmetry = "none"``) coarsens to fit."""
    quarter_data = group(6, 1.0)
    quarter_data["numerics"] = {"element": "Q1Q1"}
    quarter = scenario_from_dict(quarter_data)
    data = group(6, 1.0)
    data["numerics"] = {"element": "Q1Q1", "symmetry": "none"}
    full = scenario_from_dict(data)
    assert estimated_unknowns(quarter) > UNKNOWN_BUDGET
    assert (quarter.numerics.mesh.size_m, quarter.numerics.mesh.n_circ_min) == (1.0, 28)
    assert full.numerics.mesh.size_m > 1.0 or full.numerics.mesh.n_circ_min < 28
    assert estimated_unknowns(full) <= UNKNOWN_BUDGET


def test_loads_that_break_a_mirror_plane_halve_the_part_not_quarter_it():
    data = group(2, 1.0, lateral=True)
    sc = scenario_from_dict(data)
    assert kept_fraction(sc) == 0.5


def test_sizes_follow_the_pile_diameter_and_the_gap():
    def q1(data):
        data["numerics"] = {"element": "Q1Q1"}
        return data

    small = scenario_from_dict(q1(group(2, 0.6))).numerics.mesh
    big = scenario_from_dict(q1(group(2, 1.2))).numerics.mesh
    assert (small.size_m, big.size_m) == (0.6, 1.2)
    data = q1(group(2, 1.0))
    data["piles"]["spacing_m"] = [1.5, 1.5]  # a clear gap of 0.5 m between shafts
    data["cap"] |= {"size_x_m": 3.5, "size_y_m": 3.5}
    assert scenario_from_dict(data).numerics.mesh.size_m == pytest.approx(0.5)


def test_horizontal_actions_choose_q2q1_where_it_fits_with_a_reason():
    small = group(1, 0.6, length=15.0, lateral=True)
    small["site"] |= {"size_x_m": 30.0, "size_y_m": 30.0, "depth_m": 25.0}
    layer = dict(small["layers"][0])
    layer.pop("thickness_m")
    small["layers"] = [layer]  # one layer down to the bottom
    sc = scenario_from_dict(small)
    assert sc.numerics.element == "Q2Q1"
    assert sc.discretisation_warning() is None
    pier = scenario_from_dict(doc("pier667_lateral"))  # its half model fits
    assert pier.numerics.element == "Q2Q1" and pier.numerics.mesh.min_layer_divisions == 1
    assert pier.discretisation_warning() is None
    whole = doc("pier667_lateral")
    whole.setdefault("numerics", {})["symmetry"] = "none"  # the whole block does not
    pier = scenario_from_dict(whole)
    assert pier.numerics.element == "Q1Q1"
    assert "memory budget" in pier.numerics.element_reason
    warning = pier.discretisation_warning()
    assert warning is not None and "'Q2Q1'" in warning and "bend the piles" in warning


def test_q2q1_spans_two_trilinear_lengths_within_the_gap():
    data = group(2, 1.2, lateral=True)
    trilinear = group(2, 1.2)
    trilinear["numerics"] = {"element": "Q1Q1"}
    q1 = scenario_from_dict(trilinear).numerics.mesh
    sc = scenario_from_dict(data)
    q2 = sc.numerics.mesh
    assert sc.numerics.element == "Q2Q1"
    assert q2.size_m == pytest.approx(min(2.0 * q1.size_m, 3 * 1.2 - 1.2))
    for k in ("dz_surface_m", "dz_toe_m", "dz_max_m", "dz_max_deep_m"):
        assert getattr(q2, k) == pytest.approx(2.0 * getattr(q1, k)), k
    assert q2.dz_cap_m == pytest.approx(min(2.0 * q1.dz_cap_m, 2.0))  # at most the cap
    assert (q1.n_circ_min, q2.n_circ_min) == (28, 16)
    assert q2.far_field_size_m == q1.far_field_size_m


def test_an_explicit_q1q1_with_horizontal_actions_warns():
    data = doc("pier667_lateral")
    data.setdefault("numerics", {})["element"] = "Q1Q1"
    sc = scenario_from_dict(data)
    assert sc.numerics.element_reason == "numerics.element"
    assert "trilinear hexahedra lock" in sc.discretisation_warning()


def test_record_names_every_size_and_where_it_came_from():
    rec = scenario_from_dict(doc()).discretisation()
    assert rec["element"] == "Q2Q1" and rec["mesh"] == pytest.approx(PIER_AXIAL | {"scale": 1.0})
    assert sorted(rec["automatic"]) == sorted(PIER_SIZES)


def test_scale_refines_every_automatic_length_and_the_edges_around_a_pile():
    data = doc()
    data["numerics"] = {"element": "Q1Q1", "mesh": {"scale": 1.5, "dz_cap_m": 1.5}}
    m = scenario_from_dict(data).numerics.mesh
    assert m.size_m == pytest.approx(1.5) and m.dz_max_deep_m == pytest.approx(22.5)
    assert m.dz_cap_m == 1.5  # given: not scaled
    assert m.n_circ_min == 20  # 28 / 1.5 to the nearest multiple of 4
    data["numerics"] = {"element": "Q1Q1", "mesh": {"scale": 0.5}}  # the edges refine too
    m = scenario_from_dict(data).numerics.mesh
    assert m.size_m == pytest.approx(0.5) and m.n_circ_min == 56
    data["numerics"] = {"mesh": {"scale": 0.1}}
    with pytest.raises(ScenarioError, match="scale"):
        scenario_from_dict(data)


def test_a_size_set_on_a_resolved_scenario_is_kept_and_the_others_chosen_again():
    import dataclasses

    sc = scenario_from_dict(doc())
    mesh = sc.numerics.mesh.with_given(size_m=0.3)
    again = dataclasses.replace(sc, numerics=dataclasses.replace(sc.numerics, mesh=mesh))
    m = again.numerics.mesh
    assert m.size_m == 0.3 and "size_m" not in m.automatic
    assert {k: v for k, v in m.given().items() if k != "size_m"} == \
        {k: v for k, v in sc.numerics.mesh.given().items() if k != "size_m"}
    assert again.numerics.element_reason == sc.numerics.element_reason
