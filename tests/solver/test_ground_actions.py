"""Ground actions of the solver: surcharge, water table and consolidating layers, 1D closed forms.

Each runs a soil column (box, rollers, bottom fixed and impermeable, top drained) through
``run_stages`` and compares the final or time-dependent settlement with the closed form of 1D
consolidation (Terzaghi 1925; the oedometric modulus ``m``): a consolidating layer with
``u0 = r |sigma'_v|`` settles by ``r gamma' H^2 / (2 m)``, a water table lowered by ``d`` by
``gamma_w d H / m``.
"""

import dataclasses

import numpy as np
import pytest

from pilegroup.constitutive.soil import LinearElastic
from pilegroup.errors import ScenarioError, SolverInputError
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box, graded_levels
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
from pilegroup.studies.verification.common import ElasticSoil, box_bcs, world
from pilegroup.studies.verification.consolidation import terzaghi_degree
from pilegroup.studies.verification.ground_cases import consolidation_surcharge

SOIL = ElasticSoil()
H = 10.0
M_OED = SOIL.E * (1 - SOIL.nu) / ((1 + SOIL.nu) * (1 - 2 * SOIL.nu))
CV = (SOIL.k / GAMMA_W) / (SOIL.material().storage + 1.0 / M_OED)


def _column(material, pressure_bcs):
    md = build_box(world(), (0.0, 1.0), (0.0, 1.0), graded_levels(-H, 0.0, 12, ratio=4.0), 1, 1)
    return BiotProblem(md, {groups.soil_layer(1): material}, Discretisation("Q2Q1"),
                       displacement_bcs=box_bcs(), pressure_bcs=pressure_bcs,
                       options=SolverOptions(preset="direct"))


def _settlement(pb):
    return -float(np.atleast_1d(eval_points(pb.u, np.array([[0.5, 0.5, 0.0]])))[2])


def _steps(t_end):
    return StepControl(dt0=1e-4 * t_end, dt_min=1e-12, dt_max=2e-2 * t_end,
                       grow=10 ** (1 / 8), hold=1)


def test_consolidating_layer_starts_in_equilibrium_and_settles_by_its_excess():
    gamma, r = 18.0, 0.5
    mat = SoilMaterial(LinearElastic(SOIL.E, SOIL.nu), SOIL.k, SOIL.porosity, gamma,
                       excess_ratio=r)
    pb = _column(mat, [PressureBC(groups.GROUND)])
    T = 2.0
    log = run_stages(pb, [SolverStage("geostatic", "geostatic"),
                          SolverStage("consolidation", "consolidation", T * H**2 / CV)],
                     _steps(T * H**2 / CV), geostatic_tol=1e-9)
    assert log.geostatic_max_u < 1e-9  # the excess pore pressure carries its share of weight
    # u0 = a d (d depth below the drained top, impermeable bottom): Terzaghi's series with
    # A_m = 2 a H (-1)^m / M^2, so s(T) = a H^2 / (2 m) - sum 2 a H^2 (-1)^m / (m M^3) e^{-M^2 T}
    a = r * (gamma - GAMMA_W)
    M = np.pi * (2 * np.arange(200) + 1) / 2
    s_e = a * H**2 / (2 * M_OED) - np.sum(2 * a * H**2 * (-1.0) ** np.arange(200)
                                          / (M_OED * M**3) * np.exp(-M**2 * T))
    assert _settlement(pb) == pytest.approx(s_e, rel=3e-3)


def test_lowered_water_table_consolidates_the_layer():
    drawdown, T = 2.0, 1.0
    mat = SoilMaterial(LinearElastic(SOIL.E, SOIL.nu), SOIL.k, SOIL.porosity, 18.0)
    pb = _column(mat, [PressureBC(groups.GROUND, value=-GAMMA_W, action=0)])
    t_end = T * H**2 / CV
    run_stages(pb, [SolverStage("geostatic", "geostatic"),
                    SolverStage("pumping", "ground", 0.0, ground=(drawdown,)),
                    SolverStage("consolidation", "consolidation", t_end)], _steps(t_end))
    # an instantaneous drop of the drained boundary's pressure: Terzaghi's problem with
    # p0 = -gamma_w d (the water compressibility is negligible at this modulus)
    s_e = GAMMA_W * drawdown * H / M_OED * terzaghi_degree(T)
    assert _settlement(pb) == pytest.approx(s_e, rel=1e-2)


def test_ground_amplitudes_must_cover_every_action():
    mat = SoilMaterial(LinearElastic(SOIL.E, SOIL.nu), SOIL.k, SOIL.porosity, 18.0)
    pb = _column(mat, [PressureBC(groups.GROUND, value=-GAMMA_W, action=1)])
    with pytest.raises(SolverInputError, match="ground amplitudes: 1 given"):
        pb.set_ground((1.0,))
    with pytest.raises(SolverInputError, match="kind 'ground' or 'load'"):
        SolverStage("x", "consolidation", 1.0, ground=(1.0,))
    assert SolverStage("x", "load", 1.0, ground=(1.0,)).ground == (1.0,)  # cap actions


def test_consolidation_surcharge_case_within_its_tolerance():
    r = consolidation_surcharge()
    assert r.passed, r.line()
    assert r.details["geostatic_max_u_m"] < 1e-9
    assert len(r.details["rows"]) == 6


@pytest.mark.parametrize("ratio", [0.0, 0.3])
def test_pile_in_a_consolidating_layer_starts_in_equilibrium(small_pile, ratio):
    """The pile, the interface and the soil start in equilibrium with an excess pore pressure:
    the interface law carries the effective part of the soil's stress, the pile the total."""
    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.model import load_scenario
    from pilegroup.studies.run.pipeline import build_problem

    sc = load_scenario(small_pile, {"layers[0].excess_pore_pressure_ratio": ratio,
                                    "layers[1].excess_pore_pressure_ratio": ratio})
    geo = resolve_geometry(sc)
    pb = build_problem(sc, geo, build_mesh(geo.spec, MPI.COMM_WORLD))
    pb.set_initial_stress(pb.geostatic_stress())
    pb.set_initial_pressure()
    assert pb.has_initial_excess == (ratio > 0)
    assert pb.solve_step(0.0, 0.0).converged
    # counting the excess pore pressure twice on the shaft (once in the law's traction, once
    # beside it) gave 3.9e-5 m here and 2.2e-4 m on the quarter pier; taking the pressure part
    # of the law's initial traction at the node (where the lumped pressure term acts), not at
    # its weighted height, 2.75e-6 m, as without excess pore pressure (the faceted shaft's
    # normal scaling, docs/solver.md); with the Gauss interface 2e-17 m (next test)
    assert pb.max_displacement() < 1e-5


@pytest.mark.parametrize("where", ["layers", "installation"])
def test_gauss_interface_starts_in_exact_equilibrium_with_excess(small_pile_source, tmp_path,
                                                                 where):
    """With the Gauss interface the pressure beside the law is integrated by the law's rule, so
    an excess pore pressure at the start (layers or installation) leaves the state exact."""
    text = small_pile_source.replace("[interface]\n", '[interface]\nquadrature = "gauss"\n', 1)
    if where == "layers":
        text = text.replace("[[layers]]\n", "[[layers]]\nexcess_pore_pressure_ratio = 0.3\n")
        _, pb = _installed_pile(text, tmp_path, None)
    else:
        _, pb = _installed_pile(text, tmp_path, 0.2)
    pb.set_initial_stress(pb.geostatic_stress())
    pb.set_initial_pressure()
    assert pb.has_initial_excess
    assert pb.solve_step(0.0, 0.0).converged
    assert pb.max_displacement() < 1e-12  # measured 2e-17 m (no excess: 2e-17 m)


def _installed_pile(small_pile_source, tmp_path, ratio, radius_ratio=5.0):
    """The small pile with installation pore pressures: its problem, after the initial state."""
    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.model import load_scenario
    from pilegroup.studies.run.pipeline import build_problem

    f = tmp_path / "installed.toml"
    text = small_pile_source
    if ratio is not None:
        line = (f"installation = {{ excess_pore_pressure_ratio = {ratio:g},"
                f" radius_ratio = {radius_ratio:g} }}")
        text = text.replace("[piles]\n", f"[piles]\n{line}\n", 1)
    f.write_text(text)
    sc = load_scenario(str(f))
    geo = resolve_geometry(sc)
    return sc, build_problem(sc, geo, build_mesh(geo.spec, MPI.COMM_WORLD))


def test_pile_with_installation_pore_pressure_starts_in_equilibrium(small_pile_source, tmp_path):
    """The installation's excess pore pressure: ratio x sigma'_v at the shaft, 0 beyond R, and
    the soil, the interface and the pile start in equilibrium with it (total stress held)."""
    sc, pb = _installed_pile(small_pile_source, tmp_path, 0.2)
    assert pb.has_initial_excess
    pb.set_initial_stress(pb.geostatic_stress())
    pb.set_initial_pressure()
    x = pb.layout.Q.tabulate_dof_coordinates()
    r = np.hypot(x[:, 0], x[:, 1])
    r0 = sc.piles.diameter_m / 2
    p = pb.layout.p.x.array
    shaft = (np.abs(r - r0) < 1e-6) & (x[:, 2] < -0.5) & (x[:, 2] > -sc.piles.length_in_soil_m)
    if shaft.any():
        sv = -pb.column.sigma_v(x[shaft, 2])
        np.testing.assert_allclose(p[shaft], 0.2 * sv, rtol=1e-12)
    assert np.all(p[r > 5.0 * r0 + 1e-9] == 0.0)
    assert pb.solve_step(0.0, 0.0).converged
    # the same bound as the consolidating layers' test above (faceted shaft, interface law)
    assert pb.max_displacement() < 1e-5


def test_installation_beyond_the_horizontal_effective_stress_is_refused(small_pile_source,
                                                                        tmp_path):
    """Refused when the scenario is built, in one line naming the key (before any mesh), and by
    the solver's own check at the pressure nodes, which the scenario's rule anticipates."""
    with pytest.raises(ScenarioError, match=r"^piles\.installation\.excess_pore_pressure_ratio"
                                            r" = 0\.9 \(-\): the installation pore pressure"
                                            r" reaches 1\.02 times .* must stay below it") as e:
        _installed_pile(small_pile_source, tmp_path, 0.9)
    assert "\n" not in str(e.value)
    _, pb = _installed_pile(small_pile_source, tmp_path, 0.2)
    pb.column.installation = dataclasses.replace(pb.column.installation, ratio=0.9)
    with pytest.raises(SolverInputError, match=r"piles\.installation\.excess_pore_pressure_"
                                               r"ratio = 0\.9: .* reaches 1\.02 times .*"
                                               r" allowed: < 1"):
        pb.column.check_installation(pb.layout.Q.tabulate_dof_coordinates(), pb.comm)


def test_horizontal_conductivity_leaves_vertical_consolidation_alone():
    """k_h acts in x and y only: a 1D column consolidates as with the isotropic k."""
    gamma, r, T = 18.0, 0.5, 0.3
    runs = []
    for k_h in (None, 100.0 * SOIL.k):
        mat = SoilMaterial(LinearElastic(SOIL.E, SOIL.nu), SOIL.k, SOIL.porosity, gamma,
                           excess_ratio=r, k_h_m_per_day=k_h)
        pb = _column(mat, [PressureBC(groups.GROUND)])
        assert (pb.coef.mob_h is None) == (k_h is None)
        run_stages(pb, [SolverStage("geostatic", "geostatic"),
                        SolverStage("consolidation", "consolidation", T * H**2 / CV)],
                   _steps(T * H**2 / CV), geostatic_tol=1e-9)
        runs.append(_settlement(pb))
    assert runs[1] == pytest.approx(runs[0], rel=1e-9)


@pytest.mark.parametrize("T", [0.2, 3.0])
def test_drained_layer_halves_the_drainage_path(T):
    """A clay on a drained sand layer (an aquifer) consolidates from both faces: Terzaghi's
    double drainage, drainage path H/2, against the settlement of a uniform excess pore pressure
    ``u0``: ``s = u0 H U(T) / m`` with ``T = c_v t / (H/2)^2`` (tolerance 0.5 %)."""
    u0 = 20.0
    levels = np.concatenate([graded_levels(-H - 2.0, -H, 2), graded_levels(-H, 0.0, 24)[1:]])
    md = build_box(world(), (0.0, 1.0), (0.0, 1.0), levels, 1, 1, layer_tops=[-H])
    clay = SoilMaterial(LinearElastic(SOIL.E, SOIL.nu), SOIL.k, SOIL.porosity, 18.0,
                        excess_kPa=u0)
    # the sand starts with the same excess, drained at once: the clay's initial excess then
    # reaches its bottom face (the interpolant would otherwise ramp it to 0 over one element)
    sand = SoilMaterial(LinearElastic(100.0 * SOIL.E, SOIL.nu), SOIL.k, SOIL.porosity, 18.0,
                        excess_kPa=u0)
    pb = BiotProblem(md, {groups.soil_layer(1): clay, groups.soil_layer(2): sand},
                     Discretisation("Q2Q1"), displacement_bcs=box_bcs(),
                     pressure_bcs=[PressureBC(groups.GROUND),
                                   PressureBC(None, cells=groups.soil_layer(2))],
                     options=SolverOptions(preset="direct"))
    t_end = T * (H / 2) ** 2 / CV
    run_stages(pb, [SolverStage("geostatic", "geostatic"),
                    SolverStage("consolidation", "consolidation", t_end)], _steps(t_end),
               geostatic_tol=1e-9)
    U = terzaghi_degree(T)
    s_sand = u0 * 2.0 / (100.0 * M_OED)  # the sand's compression, at once
    assert _settlement(pb) == pytest.approx(u0 * H * U / M_OED + s_sand, rel=5e-3)
    p = pb.layout.p.x.array
    z = pb.layout.Q.tabulate_dof_coordinates()[:, 2]
    assert np.all(p[z < -H - 1e-9] == 0.0)  # the aquifer holds the water table's pressure


def test_installation_in_the_pier_on_its_default_mesh_builds(tmp_path, monkeypatch):
    """Pier 667 with installation pore pressures on its defaults (Q2-Q1, quarter): the
    interface's in-situ normal traction at the ground surface, where sigma'_v and the excess
    both vanish, is 0, not a round-off tension the interface law refuses."""
    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.model.loader import load_scenario
    from pilegroup.studies.run.pipeline import build_problem

    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario("pier667", {"piles.installation.excess_pore_pressure_ratio": 0.15,
                                   "piles.installation.radius_ratio": 5.0})
    geo = resolve_geometry(sc)
    pb = build_problem(sc, geo, build_mesh(geo.spec, MPI.COMM_WORLD))
    assert pb.has_initial_excess and pb.interface is not None
