"""Biot solver: verification cases (fast sizes), first-step oscillations, presets, stepper."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pilegroup.solver import SolverError, StepControl, StepFailure, StepInfo
from pilegroup.solver.stepping import AdaptiveStepper
from pilegroup.studies import verification as ver

ROOT = Path(__file__).resolve().parents[2]


def test_cases_are_registered_in_run_order():
    assert list(ver.CASES) == ["terzaghi", "terzaghi-water-table", "mandel", "triaxial",
                               "shaft-capacity",
                               "interface-patch", "tied-limit", "consolidation-surcharge",
                               "downdrag-end-bearing", "downdrag-floating",
                               "radial-consolidation", "lateral-single-pile",
                               "cap-equilibrium", "rigid-cap-moment", "pile-capacity",
                               "undrained-loading", "mcc-undrained-triaxial",
                               "mcc-compression-line", "ssc-creep", "ssc-oedometer"]


def test_registry_passes_only_accepted_overrides(monkeypatch):
    from pilegroup.studies.verification import registry

    monkeypatch.setattr(registry, "CASES", {})
    monkeypatch.setattr(registry, "_OPTIONS", {})
    calls = []

    @registry.register("plain")
    def plain(size, **kw):
        calls.append(("plain", size, kw))

    @registry.register("itf", registry.INTERFACE_OPTIONS)
    def itf(size, **kw):
        calls.append(("itf", size, kw))

    registry.run_case("plain", "bench", pair="Q1Q1", preset=None, quadrature="gauss")
    registry.run_case("itf", "fast", pair=None, preset="direct", quadrature="gauss")
    assert calls == [("plain", "bench", {"pair": "Q1Q1"}),
                     ("itf", "fast", {"preset": "direct", "quadrature": "gauss"})]
    assert registry.case_names() == ["plain", "itf"]
    with pytest.raises(KeyError, match="nonsense"):
        registry.case_names(["plain", "nonsense"])
    with pytest.raises(ValueError, match="twice"):
        registry.register("plain")(plain)


@pytest.mark.parametrize("pair", ["Q2Q1", "Q1Q1"])
def test_terzaghi(pair):
    r = ver.terzaghi(size="fast", pair=pair)
    assert len(r.details["rows"]) == 4
    assert r.error <= r.tolerance == 0.01, r.details["rows"]
    assert r.passed


@pytest.mark.parametrize("pair", ["Q2Q1", "Q1Q1"])
def test_mandel(pair):
    r = ver.mandel(size="fast", pair=pair)
    assert r.error <= r.tolerance == 0.02, r.details["rows"]
    # the Mandel-Cryer rise is reproduced: centre pressure above its initial value
    assert r.details["peak_ratio_fe"] > 1.05
    assert r.passed


@pytest.mark.parametrize("law,xi", [("mc", 0.02), ("dp", 0.0)])
def test_triaxial_failure_load(law, xi):
    r = ver.triaxial(size="fast", law=law, xi=xi)
    assert r.error <= r.tolerance == 1e-6
    R = [row["reaction_kN"] for row in r.details["rows"]]
    # plateau: the last three outputs agree with the failure load, earlier ones are below it
    assert abs(R[0]) < abs(r.details["failure_load_ref_kN"]) * 0.99
    assert np.allclose(R[-3:], r.details["failure_load_ref_kN"], rtol=1e-6)


def test_fieldsplit_preset_matches_direct():
    a = ver.mandel(size="fast", pair="Q1Q1", preset="direct")
    b = ver.mandel(size="fast", pair="Q1Q1", preset="fieldsplit_gamg")
    pa = np.array([row["p_h"] for row in a.details["rows"]])
    pb = np.array([row["p_h"] for row in b.details["rows"]])
    assert np.allclose(pa, pb, rtol=1e-7)


@pytest.mark.parametrize("pair,stab", [("Q2Q1", True), ("Q1Q1", True), ("Q1Q1", False)])
def test_undrained_first_step_is_uniform(pair, stab):
    r = ver.first_step_oscillation(pair, stab, nz=20, T_first=0.0)
    assert r["measure"] < 1e-10
    assert np.allclose(r["profile"], r["p0"], rtol=1e-10)


def test_checkerboard_measure_separates_stable_and_unstable_pairs():
    stable = [ver.footing_undrained_roughness(p, s, n=8)["measure"]
              for p, s in [("Q2Q1", True), ("Q1Q1", True)]]
    unstable = ver.footing_undrained_roughness("Q1Q1", False, n=8)["measure"]
    assert max(stable) < 0.1
    assert unstable > 0.2  # the measure does detect the Q1-Q1 checkerboard


def test_oscillation_measure():
    assert ver.oscillation_measure(np.array([0.0, 0.5, 1.0, 1.0]), 1.0) == 0.0
    assert ver.oscillation_measure(np.array([0.0, 1.2, 1.0]), 1.0) == pytest.approx(0.4)


def test_mandel_closed_form_limits():
    # t -> 0+: uniform p0 = F B (1 + nu_u) / (3 a); decays to 0
    F, a, B, nu, nu_u, c = 100.0, 1.0, 0.9, 0.25, 0.45, 1.0
    p0 = F * B * (1 + nu_u) / (3 * a)
    p = ver.mandel_centre_pressure(np.array([1e-6, 0.05, 10.0]), F, a, B, nu, nu_u, c,
                                   n_terms=5000)
    assert p[0] == pytest.approx(p0, rel=1e-3)
    assert p[1] > p0
    assert abs(p[2]) < 1e-6 * p0


def test_terzaghi_series_limits():
    assert ver.terzaghi_series(np.array([5.0]), 10.0, 1e-3, 1.0)[0] == pytest.approx(1.0, 1e-9)
    assert ver.terzaghi_degree(1e-8) == pytest.approx(0.0, abs=1e-3)
    assert ver.terzaghi_degree(3.0) == pytest.approx(1.0, abs=1e-3)


class FakeProblem:
    """Scalar problem failing whenever dt > dt_fail; records commits and rollbacks."""

    def __init__(self, dt_fail):
        self.dt_fail = dt_fail
        self.t = 0.0
        self.trial = None
        self.commits = 0
        self.rollbacks = 0

    def solve_step(self, dt, lam):
        if dt > self.dt_fail or not np.isfinite(dt):
            self.trial = np.nan
            return StepInfo(converged=False, message="too large")
        self.trial = self.t + dt
        return StepInfo(converged=True, newton_its=2)

    def commit(self):
        self.t = self.trial
        self.commits += 1

    def rollback(self):
        self.trial = None
        self.rollbacks += 1

    def fall_back_linear_solver(self, reason):
        return False  # no linear solver to hand over


def test_stepper_cuts_back_grows_and_hits_milestones():
    pb = FakeProblem(dt_fail=0.3)
    hits = []
    st = AdaptiveStepper(StepControl(dt0=1.0, dt_min=1e-3, grow=2.0, cut=0.5,
                                      milestones=(0.7, 2.0)))
    t = st.advance(pb, 0.0, 3.0, lambda t: 1.0, on_milestone=lambda p, t, s: hits.append(t))
    assert t == 3.0 and hits == [0.7, 2.0, 3.0]
    assert pb.rollbacks > 0
    assert pb.t == pytest.approx(3.0, abs=1e-12)
    assert all(s.dt <= 0.3 for s in st.log.steps)


def test_stepper_raises_below_dt_min():
    st = AdaptiveStepper(StepControl(dt0=1.0, dt_min=0.1, cut=0.5))
    with pytest.raises(StepFailure):
        st.advance(FakeProblem(dt_fail=0.01), 0.0, 1.0, lambda t: 1.0)


def test_geostatic_stage_equilibrium_and_reset():
    from mpi4py import MPI

    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.geometry.box import build_box, graded_levels
    from pilegroup.solver import (
        GAMMA_W,
        BiotProblem,
        DisplacementBC,
        PressureBC,
        SoilMaterial,
        SolverStage,
        run_stages,
    )

    md = build_box(MPI.COMM_WORLD, (0, 2), (0, 2), graded_levels(-10, 0, 5, 1.0), 1, 1,
                   layer_tops=[-4.0])
    mats = {"soil_layer_01": SoilMaterial(LinearElastic(5e3, 0.3), 1e-4, 0.5, gamma_sat=18.0),
            "soil_layer_02": SoilMaterial(LinearElastic(2e4, 0.25), 1e-4, 0.4, gamma_sat=20.0,
                                          K0=0.6)}
    bcs = [DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
           DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
           DisplacementBC("bottom", 2)]
    pb = BiotProblem(md, mats, displacement_bcs=bcs, pressure_bcs=[PressureBC("ground_surface")])
    log = run_stages(pb, [SolverStage("geo", "geostatic")], StepControl())
    assert log.geostatic_max_u < 1e-9
    assert pb.max_displacement() == 0.0
    for g in pb.bodies[0].qp.groups:
        z = g.x[:, 2]
        g1, g2 = 18.0 - GAMMA_W, 20.0 - GAMMA_W
        sv = np.where(z > -4, g1 * z, -4 * g1 + g2 * (z + 4))
        s = g.state_n["stress"]
        assert np.allclose(s[:, 2], sv, rtol=1e-8, atol=1e-8)
        k0 = 0.3 / 0.7 if g.name == "soil_layer_01" else 0.6
        assert np.allclose(s[:, 0], k0 * sv, rtol=1e-8, atol=1e-8)
    # a wrong initial stress is detected by the equilibrium check
    pb2 = BiotProblem(md, mats, displacement_bcs=bcs)
    pb2.geostatic_stress = lambda: {g.name: None for g in pb2.bodies[0].qp.groups}
    with pytest.raises(SolverError):
        run_stages(pb2, [SolverStage("geo", "geostatic")], StepControl(), geostatic_tol=1e-6)


def _json_lines(out):
    return {d["case"]: d for d in (json.loads(x) for x in out.splitlines() if x.startswith("{"))}


@pytest.mark.mpi
@pytest.mark.parametrize("cases,extra,err_abs", [
    (["terzaghi", "mandel", "triaxial"], [], 0.0),
    # iterative solver: the solution agrees to 1e-8 relative (measured 2e-9); the error
    # measures, differences of nearly equal numbers, agree to 1e-8 absolute
    (["mandel", "triaxial"], ["--pair", "Q1Q1", "--preset", "fieldsplit_gamg"], 1e-8),
])
def test_cases_under_mpirun_match_serial(cases, extra, err_abs):
    py = sys.executable
    mpirun = str(Path(py).parent / "mpirun")
    cmd = ["-m", "pilegroup.studies.verification", *cases, "--json", *extra]
    serial = subprocess.run([py, *cmd], capture_output=True, text=True, cwd=ROOT, timeout=900)
    par = subprocess.run([mpirun, "-n", "2", py, *cmd], capture_output=True, text=True,
                         cwd=ROOT, timeout=900)
    assert par.returncode == 0, par.stderr[-2000:]
    s, p = _json_lines(serial.stdout), _json_lines(par.stdout)
    for c in cases:
        assert s[c]["passed"] and p[c]["passed"] and p[c]["details"]["ranks"] == 2
        # errors at round-off (triaxial: ~1e-15) are compared in absolute terms
        assert p[c]["error"] == pytest.approx(s[c]["error"], rel=1e-8, abs=max(err_abs, 1e-12))
        for rs, rp in zip(s[c]["details"]["rows"], p[c]["details"]["rows"], strict=True):
            for k, v in rs.items():
                tol_abs = max(err_abs, 1e-12) if k.startswith("err") else 1e-12
                assert rp[k] == pytest.approx(v, rel=1e-8, abs=tol_abs), (c, k)


class FragileElastic:
    """LinearElastic that fails (NaN) on strain increments above a threshold."""

    def __init__(self, E, nu, max_de):
        from pilegroup.constitutive.soil import LinearElastic

        self.inner = LinearElastic(E, nu)
        self.E, self.nu, self.max_de = E, nu, max_de
        self.linear = False
        self.failures = 0

    def state_layout(self):
        return self.inner.state_layout()

    def initial_state(self, n, stress0=None):
        return self.inner.initial_state(n, stress0)

    def update(self, de, state_n, dt):
        s, tr, D = self.inner.update(de, state_n, dt)
        if np.abs(de).max() > self.max_de:
            self.failures += 1
            s = np.full_like(s, np.nan)
        return s, tr, D


def test_nan_from_law_is_cut_back_and_rolled_back():
    from mpi4py import MPI

    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.geometry.box import build_box
    from pilegroup.solver import (
        BiotProblem,
        DisplacementBC,
        PressureBC,
        SoilMaterial,
        SolverStage,
        SurfaceLoad,
        run_stages,
    )

    def run(law, dt0):
        md = build_box(MPI.COMM_WORLD, (0, 1), (0, 1), np.linspace(-4, 0, 5), 1, 1)
        pb = BiotProblem(
            md, {"soil_layer_01": SoilMaterial(law, 1e-3, 0.4)},
            displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
                              DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
                              DisplacementBC("bottom", 2)],
            pressure_bcs=[PressureBC(None)], loads=[SurfaceLoad("ground_surface", 100.0)],
            self_weight=False)
        log = run_stages(pb, [SolverStage("ramp", "load", 1.0, 1.0)],
                         StepControl(dt0=dt0, dt_min=1e-4, grow=1.0, cut=0.5))
        return pb, log

    ref, _ = run(LinearElastic(1e4, 0.3), 1.0)
    law = FragileElastic(1e4, 0.3, max_de=2.5e-3)  # full load gives ~7.4e-3 strain
    pb, log = run(law, 1.0)
    assert law.failures > 0 and log.rejected > 0
    assert all(s.dt <= 0.25 + 1e-12 for s in log.steps)
    assert pb.max_displacement() == pytest.approx(ref.max_displacement(), rel=1e-10)


@pytest.mark.slow
@pytest.mark.parametrize("name", ["terzaghi", "mandel", "triaxial"])
def test_cases_at_bench_size(name):
    r = ver.CASES[name](size="bench")
    assert r.passed, (r.error, r.tolerance)


@pytest.mark.slow
def test_strip_footing_q2_plateau_and_q1_locking():
    q2 = ver.strip_footing("Q2Q1", 10)["q_over_c"]
    q1 = ver.strip_footing("Q1Q1", 10)["q_over_c"]
    prandtl = 2 + np.pi
    assert abs(q2[-1] - q2[-2]) < 0.01 * q2[-1]  # plateau
    assert prandtl < q2[-1] < 1.2 * prandtl  # coarse mesh overestimates
    assert q1[-1] > 1.35 * prandtl and q1[-1] - q1[-2] > 0.01 * q1[-1]  # locking: no plateau


def test_geostatic_step_takes_the_next_steps_size():
    from pilegroup.solver import SolverStage
    from pilegroup.solver.stepping import first_dt

    ts = StepControl(dt0=0.05, dt_max=10.0)
    geo = SolverStage("geo", "geostatic")
    assert first_dt([geo, SolverStage("load", "load", duration=1.0)][1:], ts) == 0.05
    assert first_dt([SolverStage("load", "load", duration=0.01)], ts) == 0.01  # shorter stage
    assert first_dt([SolverStage("load", "load", duration=2.0, dt0=0.2)], ts) == 0.2
    assert first_dt([SolverStage("now", "load", duration=0.0)], ts) == 0.0  # undrained load next
    assert first_dt([], ts) == 0.0
