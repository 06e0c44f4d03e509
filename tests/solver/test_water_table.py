"""The ground at rest with the water table below the ground surface, and K0 per layer.

A column of three layers (the water table 2 m down, inside the first; K0 given, from an
over-consolidation ratio, and Jaky's) against the stresses worked out by hand at every layer
boundary; its geostatic equilibrium; a water table lowered from below the ground; and
Terzaghi's column under 2 m of dry soil (``pilegroup verify terzaghi-water-table``).
"""

import math

import numpy as np
import pytest

from pilegroup.constitutive.soil import LinearElastic, MohrCoulomb
from pilegroup.errors import SolverInputError
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box, graded_levels
from pilegroup.model import Layer, Site
from pilegroup.model.insitu import vertical_effective_stress
from pilegroup.solver import (
    GAMMA_W,
    BiotProblem,
    Discretisation,
    PressureBC,
    SoilMaterial,
    SolverOptions,
    SolverStage,
    StepControl,
    run_stages,
)
from pilegroup.solver.probes import eval_points
from pilegroup.studies import verification as ver
from pilegroup.studies.verification.common import ElasticSoil, box_bcs, world
from pilegroup.studies.verification.consolidation import terzaghi_degree

# layer: (top, bottom) depth m, saturated and dry unit weight kN/m^3, phi deg, K0 or OCR
WT = 2.0
LAYERS = (dict(top=0.0, bottom=3.0, gamma=18.0, dry=16.0, phi=30.0, K0=None, OCR=None),
          dict(top=3.0, bottom=7.0, gamma=17.0, dry=None, phi=20.0, K0=None, OCR=2.0),
          dict(top=7.0, bottom=10.0, gamma=20.0, dry=None, phi=35.0, K0=0.8, OCR=None))


def _k0(lay):
    """K0 by hand: given; else Mayne & Kulhawy's (1 - sin phi) OCR^sin(phi)."""
    if lay["K0"] is not None:
        return lay["K0"]
    s = math.sin(math.radians(lay["phi"]))
    return (1 - s) * (lay["OCR"] or 1.0) ** s


# sigma'_v (kPa, compression positive) at 0, the water table, and the layer boundaries
HAND = {0.0: 0.0,
        2.0: 16.0 * 2.0,                         # dry: the total weight
        3.0: 16.0 * 2.0 + (18.0 - GAMMA_W) * 1.0,  # below the water table: buoyant
        7.0: 16.0 * 2.0 + (18.0 - GAMMA_W) * 1.0 + (17.0 - GAMMA_W) * 4.0,
        10.0: 16.0 * 2.0 + (18.0 - GAMMA_W) * 1.0 + (17.0 - GAMMA_W) * 4.0
        + (20.0 - GAMMA_W) * 3.0}


def _materials():
    out = {}
    for j, lay in enumerate(LAYERS):
        law = MohrCoulomb(1.0e4, 0.3, 10.0, lay["phi"])
        out[groups.soil_layer(j + 1)] = SoilMaterial(law, 1e-3, 0.4, gamma_sat=lay["gamma"],
                                                     gamma_unsat=lay["dry"], K0=_k0(lay))
    return out


def _column():
    z = np.unique(np.concatenate([np.linspace(-10.0, 0.0, 11), [-WT, -2.5, -6.5]]))
    md = build_box(world(), (0.0, 1.0), (0.0, 1.0), z, 1, 1, layer_tops=[-3.0, -7.0])
    return BiotProblem(md, _materials(), Discretisation("Q1Q1"), displacement_bcs=box_bcs(),
                       pressure_bcs=[PressureBC(None, level=-WT)], water_table=-WT,
                       options=SolverOptions(preset="direct"))


def test_geostatic_stress_against_hand_calculation_at_every_layer_boundary():
    pb = _column()
    col = pb.column
    depths = np.array(sorted(HAND))
    sv = -col.sigma_v(-depths)
    ref = np.array([HAND[d] for d in depths])
    assert np.all(np.abs(sv - ref) <= 1e-9 * ref), (sv, ref)
    # the model's own column (validation before any mesh) gives the same numbers
    site = Site(1.0, 1.0, 10.0, water_table_depth_m=WT)
    layers = [Layer(name=f"l{j}", gamma_kN_per_m3=lay["gamma"], E_MPa=10.0, nu=0.3,
                    phi_deg=lay["phi"], c_kPa=10.0, k_m_per_day=1e-3, e0=1.0,
                    thickness_m=lay["bottom"] - lay["top"], gamma_unsat_kN_per_m3=lay["dry"],
                    K0=lay["K0"], OCR=lay["OCR"]) for j, lay in enumerate(LAYERS)]
    for d in depths:
        assert vertical_effective_stress(site, layers, d) == pytest.approx(HAND[d], rel=1e-9,
                                                                            abs=1e-12)
    for j, lay in enumerate(LAYERS):
        assert layers[j].k0 == pytest.approx(_k0(lay), rel=1e-12)
        # on both sides of each boundary, each layer starts at its own K0: the soil's horizontal
        # stress and the interface's normal stress on a shaft in the layer
        for d in (lay["top"], lay["bottom"]):
            x = np.array([[0.5, 0.5, -d]])
            t = col.interface_traction(x, np.array([-d]), groups.soil_layer(j + 1))
            assert -t[0, 0] == pytest.approx(_k0(lay) * HAND[d], rel=1e-9, abs=1e-12)
        assert col.k0(np.array([-0.5 * (lay["top"] + lay["bottom"])]))[0] == _k0(lay)
    # the quadrature points: sigma_h = K0 sigma_v of their layer, sigma_v the column's
    s = pb.geostatic_stress()
    for qp in (b.qp for b in pb.bodies):
        for g in qp.groups:
            zq = g.x[:, 2]
            svq = col.sigma_v(zq)
            assert np.allclose(s[g.name][:, 2], svq, rtol=1e-12, atol=1e-12)
            assert np.allclose(s[g.name][:, 0], g.material.k0 * svq, rtol=1e-12, atol=1e-12)


def test_column_with_a_water_table_starts_in_equilibrium():
    pb = _column()
    log = run_stages(pb, [SolverStage("geostatic", "geostatic"),
                          SolverStage("rest", "consolidation", 10.0)], StepControl(dt0=1.0),
                     geostatic_tol=1e-9)
    assert log.geostatic_max_u < 1e-12  # measured 6e-18 m
    assert pb.max_displacement() < 1e-12
    assert np.abs(pb.p.x.array).max() < 1e-9  # nothing flows in a column at rest


def test_cells_across_the_water_table_are_refused():
    md = build_box(world(), (0.0, 1.0), (0.0, 1.0), np.linspace(-10.0, 0.0, 6), 1, 1)
    with pytest.raises(SolverInputError, match="water table z = -3 m: .* reach across it"):
        BiotProblem(md, {groups.soil_layer(1): SoilMaterial(LinearElastic(1e4, 0.3), 1e-3, 0.4,
                                                            18.0)},
                    Discretisation("Q1Q1"), displacement_bcs=box_bcs(), water_table=-3.0)


def test_water_table_lowered_from_below_the_ground():
    """Lowering a water table that starts 2 m down by d: the 8 m below it consolidate by
    ``gamma_w d H / m``; the dry soil above keeps its stress and carries no pore pressure."""
    soil = ElasticSoil()
    m = soil.E * (1 - soil.nu) / ((1 + soil.nu) * (1 - 2 * soil.nu))
    mat = SoilMaterial(LinearElastic(soil.E, soil.nu), soil.k, soil.porosity, 18.0,
                       gamma_unsat=16.0)
    H, d, T = 8.0, 1.0, 1.0
    z = np.concatenate([graded_levels(-WT - H, -WT, 12, ratio=4.0)[:-1],
                        np.linspace(-WT, 0.0, 3)])
    md = build_box(world(), (0.0, 1.0), (0.0, 1.0), z, 1, 1)
    pb = BiotProblem(md, {groups.soil_layer(1): mat}, Discretisation("Q2Q1"),
                     displacement_bcs=box_bcs(),
                     pressure_bcs=[PressureBC(None, level=-WT, value=-GAMMA_W, action=0)],
                     water_table=-WT, options=SolverOptions(preset="direct"))
    cv = (soil.k / GAMMA_W) / (mat.storage + 1.0 / m)
    t_end = T * H**2 / cv
    run_stages(pb, [SolverStage("geostatic", "geostatic"),
                    SolverStage("pumping", "ground", 0.0, ground=(d,)),
                    SolverStage("consolidation", "consolidation", t_end)],
               StepControl(dt0=1e-4 * t_end, dt_min=1e-12, dt_max=2e-2 * t_end,
                           grow=10 ** (1 / 8), hold=1))
    top, wt = eval_points(pb.u, np.array([[0.5, 0.5, 0.0], [0.5, 0.5, -WT]]))[:, 2]
    s_e = GAMMA_W * d * H / m * terzaghi_degree(T)
    assert -top == pytest.approx(s_e, rel=1e-2)
    assert top - wt == pytest.approx(0.0, abs=1e-9 * s_e)  # the dry soil is not compressed
    p_dry = eval_points(pb.p, np.array([[0.5, 0.5, -1.0], [0.5, 0.5, -0.2]]))
    assert np.abs(p_dry).max() < 1e-12


@pytest.mark.parametrize("pair", ["Q2Q1", "Q1Q1"])
def test_terzaghi_under_dry_soil(pair):
    r = ver.terzaghi_water_table(size="fast", pair=pair)
    assert len(r.details["rows"]) == 4
    assert r.details["geostatic_max_u_m"] < 1e-12
    assert r.error <= r.tolerance == 0.01, r.details["rows"]
    assert r.passed


@pytest.mark.parametrize(("depth", "level"), [(0.0, None), (1.5, None), (1.5, 4.0)])
def test_pile_with_a_lowered_water_table_from_either_start(small_pile_source, depth, level):
    """The small single pile with the water table at the surface or 1.5 m down (and its lower
    layer, where the toe stands, held at a piezometric level 4 m down), a groundwater stage
    lowering the water table by 1 m: the pile starts in equilibrium, the dry soil keeps no pore
    pressure and the drained boundary (the water table's level) follows the drawdown."""
    import tomllib

    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.model import scenario_from_dict
    from pilegroup.studies.run.pipeline import build_problem, solver_stages, time_stepping

    text = small_pile_source.replace("water_table_depth_m = 0.0",
                                     f"water_table_depth_m = {depth}").replace(
        '[[stages]]\nname = "consolidation"',
        '[[stages]]\nname = "pumping"\nkind = "groundwater"\ndrawdown_m = 1.0\n'
        'duration_day = 0.5\n\n[[stages]]\nname = "consolidation"', 1)
    data = tomllib.loads(text)
    data["layers"][1]["piezometric_depth_m"] = level
    sc = scenario_from_dict(data)
    assert sc.site.water_table_depth_m == depth and sc.stages[2].kind == "groundwater"
    geo = resolve_geometry(sc)
    pb = build_problem(sc, geo, build_mesh(geo.spec, MPI.COMM_WORLD, cache_dir=False))
    log = run_stages(pb, solver_stages(sc), time_stepping(sc), geostatic_tol=1e-4)
    assert log.geostatic_max_u < 1e-5  # measured 2.8e-6, 2.3e-6, 2.3e-6 m
    x = sc.site.size_x_m / 2 - 0.01  # far from the pile, inside the quarter model
    p = eval_points(pb.p, np.array([[x, x, -depth], [x, x, 0.0], [x, x, -15.0]]))
    if level is not None:  # the aquifer the region holds, whatever the water table does
        assert p[2] == pytest.approx(GAMMA_W * (depth - level), rel=1e-9)
    assert p[0] == pytest.approx(-GAMMA_W * 1.0, rel=1e-9)  # the drained boundary, lowered
    if depth > 0.0:
        assert p[1] == 0.0  # the dry soil's nodes


def _aquifer_column():
    """Clay 2-10 m below a water table 2 m down, an under-drained sand 10-14 m (its
    piezometric level 6 m down), clay to 20 m: the scenario's seepage and held layers."""
    from pilegroup.model.insitu import own_levels, seepage

    site = Site(1.0, 1.0, 20.0, water_table_depth_m=WT)
    kw = dict(E_MPa=10.0, nu=0.3, phi_deg=25.0, c_kPa=5.0, e0=1.0)
    layers = [Layer(name="clay", gamma_kN_per_m3=18.0, k_m_per_day=1e-3, thickness_m=10.0,
                    gamma_unsat_kN_per_m3=16.0, **kw),
              Layer(name="sand", gamma_kN_per_m3=20.0, k_m_per_day=1.0, thickness_m=4.0,
                    piezometric_depth_m=6.0, **kw),
              Layer(name="clay2", gamma_kN_per_m3=18.0, k_m_per_day=1e-3, **kw)]
    z = np.unique(np.concatenate([np.linspace(-20.0, 0.0, 21), [-WT]]))
    md = build_box(world(), (0.0, 1.0), (0.0, 1.0), z, 1, 1, layer_tops=[-10.0, -14.0])
    mats = {groups.soil_layer(j + 1): SoilMaterial(
        LinearElastic(lay.E, lay.nu), lay.k_m_per_day, lay.porosity, lay.gamma_kN_per_m3,
        K0=lay.k0, gamma_unsat=lay.gamma_unsat_kN_per_m3) for j, lay in enumerate(layers)}
    held = [PressureBC(None, u, cells=groups.soil_layer(j + 1))
            for j, u in own_levels(site, layers)]
    return site, layers, lambda bcs: BiotProblem(
        md, mats, Discretisation("Q1Q1"), displacement_bcs=box_bcs(),
        pressure_bcs=[*bcs, *held], water_table=-WT,
        seepage=[(-d, u) for d, u in seepage(site, layers)], options=SolverOptions(preset="direct"))


def test_under_drained_layer_seeps_steadily_and_the_stresses_follow():
    site, layers, problem = _aquifer_column()
    d = GAMMA_W * (WT - 6.0)  # the sand's pore pressure above the water table's hydrostatic
    from pilegroup.model.insitu import seepage

    # by hand: linear through the clay from 0 at the water table to d at the sand, d below
    np.testing.assert_allclose(seepage(site, layers), [(2.0, 0.0), (10.0, d), (10.0, d),
                                                       (14.0, d), (20.0, d)], rtol=1e-12)
    pb = problem([PressureBC(None, level=-WT)])
    hydro = {2.0: 32.0, 10.0: 32.0 + (18.0 - GAMMA_W) * 8.0,
             14.0: 32.0 + (18.0 - GAMMA_W) * 8.0 + (20.0 - GAMMA_W) * 4.0,
             20.0: 32.0 + (18.0 - GAMMA_W) * 14.0 + (20.0 - GAMMA_W) * 4.0}
    u0 = {2.0: 0.0, 10.0: d, 14.0: d, 20.0: d}
    pb.column.set_excess_levels(pb.layout.Q.tabulate_dof_coordinates()[:, 2], pb.comm)
    for depth, sv in hydro.items():
        z = np.array([-depth])
        eff = -(pb.column.sigma_v(z) + pb.column.excess(z))[0]
        assert eff == pytest.approx(sv - u0[depth], rel=1e-9)  # sigma'_v - u0, compressive
        assert vertical_effective_stress(site, layers, depth) == pytest.approx(sv, rel=1e-12)
    log = run_stages(pb, [SolverStage("geostatic", "geostatic"),
                          SolverStage("rest", "consolidation", 1000.0)],
                     StepControl(dt0=1.0, dt_max=200.0), geostatic_tol=1e-9)
    assert log.geostatic_max_u < 1e-12
    assert pb.max_displacement() < 1e-9  # steady: nothing moves at rest
    p = eval_points(pb.p, np.array([[0.5, 0.5, -6.0], [0.5, 0.5, -12.0], [0.5, 0.5, -18.0]]))
    assert p == pytest.approx([0.5 * d, d, d], rel=1e-9)


def test_water_table_lowered_above_an_under_drained_layer():
    """The water table's drawdown reaches the clay above the sand, whose level the region
    holds: the clay consolidates towards the new steady seepage."""
    _, _, problem = _aquifer_column()
    pb = problem([PressureBC(None, level=-WT, value=-GAMMA_W, action=0)])
    run_stages(pb, [SolverStage("geostatic", "geostatic"),
                    SolverStage("pumping", "ground", 1.0, ground=(1.0,)),
                    SolverStage("consolidation", "consolidation", 1.0e5)],
               StepControl(dt0=0.1, dt_max=1.0e4))
    d = GAMMA_W * (WT - 6.0)
    p = eval_points(pb.p, np.array([[0.5, 0.5, -WT], [0.5, 0.5, -6.0], [0.5, 0.5, -12.0]]))
    assert p == pytest.approx([-GAMMA_W, 0.5 * (d - GAMMA_W), d], rel=1e-6)
    assert pb.max_displacement() > 1e-3  # the clay settled


@pytest.mark.parametrize(("depth", "level", "mud"), [
    (9.0, None, {"K0": 0.4}),  # the soft mud dry: the silty clay decides
    (1.5, -1.0, {}),  # the silty clay artesian: its seepage takes room at its top
    (3.0, None, {"excess_pore_pressure_kPa": 10.0}),  # largest just below the water table
])
def test_installation_refused_where_the_solver_refuses_it(small_pile_source, depth, level, mud):
    """The scenario's rule (``model/law_rules.py::installation_ratio``) and the solver's check at
    the pressure nodes see the same ratio of the installation pore pressure to the horizontal
    effective stress, with the water table below the ground and a layer's pore pressure at
    rest: where the largest lies on a node (a layer boundary) the solver refuses a ratio 1 %
    beyond the rule's limit; the solver accepts one 1 % within it everywhere. The mud's
    ``excess_pore_pressure_kPa`` starts at the water table, where the solver's nodal pressure
    is still 0: its largest ratio is at the first node below, less than the rule's limit from
    below the water table by what the node's depth gives (5.4 m here: 6 %)."""
    import dataclasses
    import re
    import tomllib

    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.model import scenario_from_dict
    from pilegroup.model.law_rules import installation_ratio
    from pilegroup.studies.run.pipeline import build_problem

    data = tomllib.loads(small_pile_source)
    data["site"]["water_table_depth_m"] = depth
    data["piles"]["installation"] = {"excess_pore_pressure_ratio": 0.2, "radius_ratio": 5.0}
    data["layers"][1]["piezometric_depth_m"] = level
    data["layers"][0].update(mud)
    sc = scenario_from_dict(data)
    limit = 0.2 / installation_ratio(sc).ratio  # the ratio at which the rule refuses
    geo = resolve_geometry(sc)
    pb = build_problem(sc, geo, build_mesh(geo.spec, MPI.COMM_WORLD, cache_dir=False))
    x, ins = pb.layout.Q.tabulate_dof_coordinates(), pb.column.installation
    share = 1.0  # the solver's largest ratio over the rule's
    if "excess_pore_pressure_kPa" in mud:  # the rule's formula at the first node below it
        below = x[x[:, 2] < -depth - 1e-6, 2]
        node = -pb.comm.allreduce(float(np.max(below, initial=-np.inf)), op=MPI.MAX)
        sv, sv_wt = sc.vertical_effective_stress(node), sc.vertical_effective_stress(depth)
        share = sv / (sv - 10.0) / (sv_wt / (sv_wt - 10.0))
        assert node == pytest.approx(5.42, abs=0.01) and share == pytest.approx(0.94, abs=0.01)
    for factor in (0.99, 1.01, 1.1):
        pb.column.installation = dataclasses.replace(ins, ratio=factor * limit)
        if factor * share < 1.0:
            pb.column.check_installation(x, pb.comm)  # accepted
            continue
        with pytest.raises(SolverInputError) as err:
            pb.column.check_installation(x, pb.comm)
        reached = float(re.search(r"reaches (\S+) times", str(err.value)).group(1))
        assert reached == pytest.approx(factor * share, abs=0.006)
