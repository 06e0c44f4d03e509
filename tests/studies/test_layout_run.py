"""The whole pipeline on two piles of different diameters and lengths (``piles.layout``).

The fast-tier single pile's site and run (0.5-day load of 500 kN, consolidation to day 2) with
pile 1 (d = 1.0 m, 12 m) at x = -1.5 m and pile 2 (d = 0.6 m, 8 m) at x = +1.5 m: mirror images
about x = 0 that differ, so ``auto`` runs the half model about y = 0, both piles cut in half.
The top metre of the soil is sleeved (interface K = 1: next to no shaft friction), so the
axial force at a pile's first section, 0.24 m down, is its head load.

* Free heads (no cap): the load is a uniform pressure on the pile heads, so each pile takes
  its share of the meshed head area (octagons, N = 8) and together the applied load: both to
  1e-3 (measured 1.3e-4; the residual is the sleeve's friction above the first section).
* Under a cap (1 m thick, free of the soil): the longer, thicker pile is the stiffer one and
  takes the larger load (measured 343 and 156 kN), and the cap tilts towards the other one
  (head settlements 7.2 and 8.8 mm). Their sum is the applied load to 2e-3 (measured 1.3e-3):
  the axial force is the volume times the plain mean of a cell's quadrature-point stresses,
  which is not the cell's mean stress on the o-grid's non-parallelogram cells where the stress
  varies across the pile, as it does under the cap (weighting the points by the Jacobian
  gives 499.95 kN).
"""

import csv
import json
import math

import numpy as np
import pytest

from pilegroup.errors import StepFailure
from pilegroup.model import load_scenario
from pilegroup.model.loader import parse_override
from pilegroup.studies.run.capacity_probe import CapacityProbe
from pilegroup.studies.run.job import run_scenario
from pilegroup.studies.run.pipeline import check_runaway, installation

LOAD_KN = 500.0
PILES = """[piles]
diameter_m = 0.8
length_in_soil_m = 12.0
grid = [1, 1]"""
LAYOUT = """[piles]
embedment_m = 0.0
layout = [ { x_m = -1.5, y_m = 0.0, diameter_m = 1.0, length_in_soil_m = 12.0 },
           { x_m = 1.5, y_m = 0.0, diameter_m = 0.6, length_in_soil_m = 8.0 } ]
"""
CAP = """
[cap]
size_x_m = 5.0
size_y_m = 2.4
thickness_m = 1.0
"""
SLEEVE = """[[layers]]
name = "sleeved_mud"
thickness_m = 1.0
gamma_kN_per_m3 = 16.9
E_MPa = 3.0
nu = 0.42
phi_deg = 2.6
c_kPa = 5.6
k_m_per_day = 5.184e-05
e0 = 1.2
interface = { delta_deg = 2.6, K = 1, n = 0.0, R_f = 0.27, eta_MPa_day = 6.23 }

[[layers]]
name = "mud"
thickness_m = 7.0"""


def layout_text(small_pile: str, cap: bool) -> str:
    """The small pile's scenario with the two-pile layout (and a cap), gauges on both piles."""
    for old in (PILES, '[[layers]]\nname = "mud"\nthickness_m = 8.0',
                "gauge_depths_m = [1.0, 4.0, 8.0, 11.5]", f"cap_load_kN = {LOAD_KN}"):
        assert old in small_pile, old
    return (small_pile.replace(PILES, LAYOUT + (CAP if cap else ""))
            .replace('[[layers]]\nname = "mud"\nthickness_m = 8.0', SLEEVE)
            .replace("gauge_depths_m = [1.0, 4.0, 8.0, 11.5]", "gauge_depths_m = [1.0, 4.0, 7.5]"))


@pytest.fixture(scope="module")
def runs(small_pile_source, tmp_path_factory):
    """Output folders of the free-head and the capped runs."""
    base = tmp_path_factory.mktemp("layout_runs")
    out = {}
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PILEGROUP_MESH_CACHE", str(base / "cache"))
        for name, cap in (("free", False), ("capped", True)):
            f = base / f"{name}.toml"
            f.write_text(layout_text(small_pile_source, cap))
            run_scenario(load_scenario(f), base / name)
            out[name] = base / name
    return out


def _rows(path):
    with path.open() as fh:
        return list(csv.DictReader(fh))


def _heads(folder):
    """{t_day: (head load of pile 1, of pile 2)} after the load (kN)."""
    by_t = {}
    for r in _rows(folder / "pile_loads.csv"):
        by_t.setdefault(float(r["t_day"]), {})[int(r["pile"])] = float(r["head_force_kN"])
    return {t: (v[1], v[2]) for t, v in by_t.items() if t > 0}


def test_half_model_with_both_piles_reported(runs):
    for folder in runs.values():
        solver = json.loads((folder / "summary.json").read_text())["solver"]
        assert solver["symmetry"]["model"] == "half_y"
        assert "pile 1 and its mirror image, pile 2, differ in diameter" in \
            solver["symmetry"]["reason"]
        prof = _rows(folder / "pile_profiles.csv")
        deepest = {i: max(float(r["depth_m"]) for r in prof if r["pile"] == str(i))
                   for i in (1, 2)}
        assert deepest == {1: pytest.approx(12.0), 2: pytest.approx(8.0)}
        gauges = _rows(folder / "gauges.csv")
        assert {(r["pile"], r["depth_m"]) for r in gauges} == {
            (str(i), z) for i in (1, 2) for z in ("1", "4", "7.5")}


def test_free_heads_share_the_load_by_head_area(runs):
    def octagon(d):  # the meshed octagon has the circle's area
        return math.pi * d * d / 4

    share = octagon(1.0) / (octagon(1.0) + octagon(0.6))
    heads = _heads(runs["free"])
    assert set(heads) == {0.5, 2.0}
    for n1, n2 in heads.values():
        assert n1 + n2 == pytest.approx(LOAD_KN, rel=1e-3)
        assert n1 == pytest.approx(share * LOAD_KN, rel=1e-3)
        assert n2 == pytest.approx((1 - share) * LOAD_KN, rel=1e-3)


def test_under_a_cap_the_stiffer_pile_takes_more_and_the_cap_tilts(runs):
    heads = _heads(runs["capped"])
    assert set(heads) == {0.5, 2.0}
    for n1, n2 in heads.values():
        assert n1 > 2.0 * n2 > 0.0
        assert n1 + n2 == pytest.approx(LOAD_KN, rel=2e-3)
    plane = [r for r in _rows(runs["capped"] / "neutral_plane.csv") if r["t_day"] == "2"]
    w = {int(r["pile"]): float(r["head_settlement_m"]) for r in plane}
    assert w[2] > w[1] > 0.0


# ---------------------------------------------------------------- per-pile rules, no run
def _scenario(small_pile_source, tmp_path, sets=()):
    f = tmp_path / "two.toml"
    f.write_text(layout_text(small_pile_source, cap=False))
    return load_scenario(f, dict(parse_override(kv) for kv in sets))


def test_installation_cavities_have_each_piles_radius_and_toe(small_pile_source, tmp_path):
    """Each cavity's r0 is its pile's meshed circumradius (every shaft node at the wall)."""
    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.plan import circumferential_divisions, meshed_radii, polygon_radius

    sets = ("piles.installation={excess_pore_pressure_ratio = 0.3, radius_ratio = 8.0}",)
    sc = _scenario(small_pile_source, tmp_path, sets)
    spec = resolve_geometry(sc).spec
    n = circumferential_divisions(spec)
    ins = installation(sc, meshed_radii(spec))
    assert ins.piles == ((-1.5, 0.0, polygon_radius(0.5, n), -12.0),
                         (1.5, 0.0, polygon_radius(0.3, n), -8.0))
    assert 0.5 < polygon_radius(0.5, n) < 0.5 * 1.06  # at most 5.4 % beyond (8 edges)


def test_runaway_is_measured_against_the_smallest_diameter(small_pile_source, tmp_path):
    sc = _scenario(small_pile_source, tmp_path)
    check_runaway(sc, 0.59, 1.0, 1.0, "loading")
    with pytest.raises(StepFailure, match="exceeds the smallest pile diameter 0.6 m"):
        check_runaway(sc, 0.61, 1.0, 1.0, "loading")


def test_capacity_criteria_per_pile_diameter_and_the_group_smallest(small_pile_source,
                                                                      tmp_path):
    sets = ('stages[2].kind="capacity"', "stages[2].max_load_kN=5000.0",
            "stages[2].duration_day=1.5")
    probe = CapacityProbe(_scenario(small_pile_source, tmp_path, sets), None, None, None,
                          tmp_path)
    w = np.linspace(0.0, 0.2, 11)  # the same settlement curve for the group and both piles
    probe.points = [[t, t, 1000.0 * t, wi, [800.0 * t, 200.0 * t], [wi, wi]]
                    for t, wi in zip(np.linspace(0.0, 1.0, 11), w, strict=True)]
    res = probe.result()
    limits = [p["settlement_10pct_d"]["settlement_m"] for p in res["piles"]]
    assert limits == pytest.approx([0.1, 0.06])
    assert res["group"]["settlement_10pct_d"]["settlement_m"] == pytest.approx(0.06)
    assert res["settlement_criterion_m"] == pytest.approx(0.06)
    assert res["piles"][0]["settlement_10pct_d"]["load_kN"] == pytest.approx(400.0)
    assert res["piles"][1]["settlement_10pct_d"]["load_kN"] == pytest.approx(60.0)
