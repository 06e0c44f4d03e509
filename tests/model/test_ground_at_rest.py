"""Scenario keys of the ground at rest: the water table's depth, K0 or OCR per layer, the unit
weight above the water table; their refusals at validation, and the mesh surface at the water
table."""

import copy
import math
import tomllib

import numpy as np
import pytest

from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.geometry.vertical import vertical_segments
from pilegroup.model import ScenarioError, bundled_text, scenario_from_dict
from pilegroup.model.insitu import own_levels, seepage
from pilegroup.model.law_rules import installation_ratio
from pilegroup.model.units import GAMMA_WATER
from pilegroup.studies.cli.commands import EXIT_INPUT, main
from pilegroup.studies.run.pipeline import ground_drainage, water_table

BASE = tomllib.loads(bundled_text("pier667"))
PUMP = {"name": "pumping", "kind": "groundwater", "drawdown_m": 2.0, "duration_day": 5.0}


def _with(wt=0.0, stages=(), **layer0):
    data = copy.deepcopy(BASE)
    data["site"]["water_table_depth_m"] = wt
    data["stages"][1:1] = [dict(s) for s in stages]
    data["layers"][0].update(layer0)
    return data


def test_water_table_below_the_ground_surface():
    sc = scenario_from_dict(_with(3.0, [PUMP, dict(PUMP, name="back", drawdown_m=-2.0)],
                                  gamma_unsat_kN_per_m3=16.0))
    lay0, lay1 = sc.layers[0], sc.layers[1]  # clay 0-0.4 m (dry), mud 0.4-19.7 m (cut)
    assert lay0.gamma_unsat == 16.0 and lay1.gamma_unsat == lay1.gamma_kN_per_m3
    sv = 16.0 * 0.4 + lay1.gamma_kN_per_m3 * 2.6 + (lay1.gamma_kN_per_m3 - GAMMA_WATER) * 2.0
    assert sc.vertical_effective_stress(5.0) == pytest.approx(sv, rel=1e-12)
    assert sc.vertical_effective_stress(3.0) == pytest.approx(16.0 * 0.4 + lay1.gamma_kN_per_m3
                                                              * 2.6, rel=1e-12)
    # the drained boundary is the water table, lowered by the groundwater stages
    assert water_table(sc) == -3.0
    bc = ground_drainage(sc)
    assert (bc.facet, bc.level, bc.value) == (None, -3.0, pytest.approx(-GAMMA_WATER))
    assert water_table(scenario_from_dict(_with())) is None
    assert ground_drainage(scenario_from_dict(_with())).facet == "ground_surface"
    # the mesh has a surface at the water table; the slabs above and below keep layer 2
    geo = resolve_geometry(sc)
    assert geo.spec.levels == (3.0,)
    soil, _ = vertical_segments(geo.spec)
    cut = [(s.z_start, s.z_end, s.layer) for s in soil if s.layer == 2]
    assert cut == [(-0.4, -3.0, 2), (-3.0, -19.7, 2)]
    assert resolve_geometry(scenario_from_dict(_with())).spec.levels == ()


def test_k0_per_layer_from_k0_ocr_or_jaky():
    phi = BASE["layers"][0]["phi_deg"]
    s = math.sin(math.radians(phi))
    assert scenario_from_dict(_with()).layers[0].k0 == pytest.approx(1 - s, rel=1e-12)
    assert scenario_from_dict(_with(K0=0.65)).layers[0].k0 == 0.65
    ocr = scenario_from_dict(_with(OCR=4.0)).layers[0]
    assert ocr.k0 == pytest.approx((1 - s) * 4.0**s, rel=1e-12)  # Mayne & Kulhawy 1982


@pytest.mark.parametrize(("wt", "stages", "layer", "key", "words"), [
    (-1.0, (), {}, "site.water_table_depth_m", "must be in [0, 128)"),
    (0.0, (), {"K0": 0.0}, "layers[0].K0", "must be in (0, 3]"),
    (0.0, (), {"K0": 3.5}, "layers[0].K0", "must be in (0, 3]"),
    (0.0, (), {"OCR": 0.5}, "layers[0].OCR", "must be in [1, 100]"),
    (0.0, (), {"OCR": 2.0, "K0": 0.5}, "layers[0].OCR", "either K0 or OCR"),
    (0.0, (), {"OCR": 100.0, "phi_deg": 40.0}, "layers[0].OCR", "must give K0 <= 3"),
    (0.0, (), {"gamma_unsat_kN_per_m3": 20.0}, "layers[0].gamma_unsat_kN_per_m3",
     "must be <= gamma_kN_per_m3"),
    (0.0, (), {"gamma_unsat_kN_per_m3": 2.0}, "layers[0].gamma_unsat_kN_per_m3",
     "must be in [5, 25]"),
    (1.0, (), {"excess_pore_pressure_ratio": 0.2}, "layers[0].excess_pore_pressure_ratio",
     "above the water table"),
    (2.0, (dict(PUMP, drawdown_m=-0.5),), {}, "stages[1].drawdown_m",
     "raises the water table 0.5 m above its start"),
    (2.0, (PUMP, dict(PUMP, name="up", drawdown_m=-3.0)), {}, "stages[2].drawdown_m",
     "raises the water table 1 m above its start"),
])
def test_bad_keys_are_refused_with_key_value_and_rule(wt, stages, layer, key, words):
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(_with(wt, stages, **layer))
    assert err.value.key == key
    assert words in str(err.value) and "\n" not in str(err.value)


def test_seepage_towards_an_under_drained_aquifer():
    """Pier 667's gravel (layer 8, 51.8-60 m) held at a level 6 m down below a water table 2 m
    down: the seven layers above seep steadily, the same flow through each."""
    data = _with(2.0)
    data["layers"][7]["piezometric_depth_m"] = 6.0
    sc = scenario_from_dict(data)
    d = GAMMA_WATER * (2.0 - 6.0)
    bottoms = [0.4 + sum(lay["thickness_m"] for lay in BASE["layers"][1:j + 1])
               for j in range(1, 7)]  # mud .. silty clay above the gravel
    tops = [2.0] + bottoms[:-1]
    r = [(b - t) / BASE["layers"][j + 1]["k_m_per_day"]
         for j, (t, b) in enumerate(zip(tops, bottoms, strict=True))]
    expected = [(2.0, 0.0)] + [(b, d * sum(r[:i + 1]) / sum(r)) for i, b in enumerate(bottoms)]
    expected += [(51.8, d), (60.0, d), (64.3, d), (128.0, d)]
    got = seepage(sc.site, sc.layers)
    assert [g[0] for g in got] == pytest.approx([e[0] for e in expected], rel=1e-12)
    assert [g[1] for g in got] == pytest.approx([e[1] for e in expected], rel=1e-12, abs=1e-12)
    assert own_levels(sc.site, sc.layers) == [(7, pytest.approx(d))]


@pytest.mark.parametrize(("wt", "layers", "key", "words"), [
    (2.0, {0: {"piezometric_depth_m": 1.0}}, "layers[0].piezometric_depth_m",
     "lies above the water table"),
    (2.0, {1: {"piezometric_depth_m": 1.0}}, "layers[1].piezometric_depth_m",
     "a layer through which the water seeps must lie between them"),
    (2.0, {7: {"piezometric_depth_m": 6.0}, 8: {"drained": True}}, "layers[8].drained",
     "a layer through which the water seeps"),
    (2.0, {7: {"piezometric_depth_m": -60.0}}, "layers[7].piezometric_depth_m",
     "the ground would heave"),
    (2.0, {7: {"piezometric_depth_m": 6.0, "drained": True}}, "layers[7].piezometric_depth_m",
     "not with drained"),
    (0.0, {1: {"piezometric_depth_m": 6.0, "excess_pore_pressure_ratio": 0.2}},
     "layers[1].piezometric_depth_m", "not with excess_pore_pressure_ratio"),
    (0.0, {1: {"piezometric_depth_m": -101.0}}, "layers[1].piezometric_depth_m",
     "must be in [-100, 500]"),
])
def test_bad_piezometric_levels_are_refused(wt, layers, key, words):
    data = _with(wt)
    for j, keys in layers.items():
        data["layers"][j].update(keys)
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(data)
    assert err.value.key == key
    assert words in str(err.value) and "\n" not in str(err.value)


def test_validate_refuses_before_meshing_with_one_line(tmp_path, capsys):
    good = bundled_text("pier667").replace("water_table_depth_m = 0.0",
                                           "water_table_depth_m = 2.5")
    bad = good.replace('name = "clay"', 'name = "clay"\nOCR = 0.8', 1)
    assert bad != good
    for name, text, code in (("good", good, 0), ("bad", bad, EXIT_INPUT)):
        f = tmp_path / f"{name}.toml"
        f.write_text(text)
        assert main(["scenario", "validate", str(f)]) == code
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "layers[0].OCR" in err and "= 0.8" in err


# ---- the installation pore pressures against the ground at rest ----------------------------

SINGLE = tomllib.loads(bundled_text("single_pile"))  # mud 0-8 m over silty clay, toe at 12 m


def _installed(ratio, wt=0.0, level=None, **mud):
    """single_pile with installation pore pressures, the water table ``wt`` m down, its lower
    layer held at the piezometric level ``level`` and the mud's keys ``mud``."""
    data = copy.deepcopy(SINGLE)
    data["site"]["water_table_depth_m"] = wt
    data["piles"]["installation"] = {"excess_pore_pressure_ratio": ratio, "radius_ratio": 10.0}
    data["layers"][1]["piezometric_depth_m"] = level
    data["layers"][0].update(mud)
    return scenario_from_dict(data)


def test_installation_in_dry_soil_is_not_refused():
    """A mud with K0 = 0.4 takes a ratio of 0.5 of the vertical effective stress only where it
    is dry: with the water table at the surface it is refused there, with the water table 9 m
    down (the mud dry) the silty clay below decides, ``0.5 / K0``."""
    with pytest.raises(ScenarioError) as err:
        _installed(0.5, K0=0.4)
    assert "reaches 1.25 times" in str(err.value) and "layer 1" in str(err.value)
    sc = _installed(0.5, 9.0, K0=0.4)
    peak = installation_ratio(sc)
    assert peak.ratio == pytest.approx(0.5 / sc.layers[1].k0, rel=1e-9)
    assert peak.layer == 1 and peak.depth >= 9.0


def test_installation_at_a_water_table_below_the_ground():
    """The mud's initial excess pore pressure (10 kPa) acts below the water table (3 m down),
    where sigma'_v is the dry mud's weight: the ratio is largest just below it,
    ``r / (K0 (1 - 10 / sigma'_v(3 m)))``."""
    sc = _installed(0.5, 3.0, excess_pore_pressure_kPa=10.0)
    sv = 3.0 * SINGLE["layers"][0]["gamma_kN_per_m3"]
    assert sc.vertical_effective_stress(3.0) == pytest.approx(sv, rel=1e-12)
    peak = installation_ratio(sc)
    assert peak.ratio == pytest.approx(0.5 / (sc.layers[0].k0 * (1 - 10.0 / sv)), rel=1e-7)
    assert (peak.layer, peak.depth) == (0, pytest.approx(3.0, abs=1e-6))
    with pytest.raises(ScenarioError) as err:
        _installed(0.8, 3.0, excess_pore_pressure_kPa=10.0)
    assert "3 m deep, layer 1" in str(err.value) and "\n" not in str(err.value)


def test_installation_on_an_artesian_layer():
    """The silty clay held 1 m above the ground (artesian) below a water table 1.5 m down: its
    pore pressure at rest is ``gamma_w 2.5 m`` above the hydrostatic one and leaves less
    horizontal effective stress at its top, ``K0 (sigma'_v - u)``: a ratio of 0.6, accepted
    without the head, is refused with it."""
    assert installation_ratio(_installed(0.6, 1.5)).ratio < 1.0
    sc = _installed(0.5, 1.5, -1.0)
    mud, clay = SINGLE["layers"][0]["gamma_kN_per_m3"], sc.layers[1]
    sv = mud * 1.5 + (mud - GAMMA_WATER) * 6.5
    u = GAMMA_WATER * 2.5
    peak = installation_ratio(sc)
    assert peak.ratio == pytest.approx(0.5 * sv / (clay.k0 * (sv - u)), rel=1e-9)
    assert (peak.layer, peak.depth) == (1, pytest.approx(8.0))
    with pytest.raises(ScenarioError) as err:
        _installed(0.6, 1.5, -1.0)
    assert err.value.key == "piles.installation.excess_pore_pressure_ratio"
    assert "reaches 1.03 times" in str(err.value) and "8 m deep, layer 2" in str(err.value)


@pytest.mark.parametrize("k0, phi, c", [(0.426, 35.0, 0.0), (0.7, 20.0, 5.0), (1.3, 25.0, 2.0),
                                        (0.95, 2.6, 5.6)])
def test_strength_room_puts_the_state_on_mohr_coulomb(k0, phi, c):
    """At the pore pressure ``strength_room`` allows, the state at rest lowered by it lies on
    the Mohr-Coulomb surface of the soil law itself (f = 0), and within it just below."""
    from pilegroup.constitutive.soil import MohrCoulomb
    from pilegroup.model.law_rules import strength_room

    s = 120.0
    u = strength_room(s, k0, phi, c)
    law = MohrCoulomb(E=1e4, nu=0.3, c=c, phi_deg=phi)

    def f(u_):  # tension positive Mandel vector: xx, yy, zz, then shear
        return law.yield_function(np.array([[-(k0 * s - u_), -(k0 * s - u_), -(s - u_),
                                             0.0, 0.0, 0.0]]))[0]
    assert math.isfinite(u) and 0.0 < u
    assert f(u) == pytest.approx(0.0, abs=1e-9 * s)
    assert f(0.99 * u) < 0.0 < f(1.01 * u)


def test_installation_in_the_pier_is_bounded_by_the_gravel_strength():
    """Pier 667's gravel (phi 35 deg, c 0, K0 = 1 - sin phi) holds less installation pore
    pressure than its horizontal effective stress: Mohr-Coulomb is reached first, and the run's
    geostatic check would find the soil yielding (0.4-0.8 mm); validation refuses the ratio,
    naming the gravel (layer 8)."""
    data = tomllib.loads(bundled_text("pier667"))
    data["piles"]["installation"] = {"excess_pore_pressure_ratio": 0.15, "radius_ratio": 5.0}
    assert installation_ratio(scenario_from_dict(copy.deepcopy(data))).ratio < 1.0
    data["piles"]["installation"]["excess_pore_pressure_ratio"] = 0.2
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(data)
    assert "layer 8" in str(err.value) and "strength" in str(err.value)
    assert "\n" not in str(err.value)
