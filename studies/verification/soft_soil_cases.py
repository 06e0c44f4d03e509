"""Material-point cases of the soft-soil laws against closed forms (no mesh).

Each case drives one material point through :func:`pilegroup.solver.qpstate.guarded_update`,
the call the solver's quadrature-point state makes, with strain increments; where a stress is
held (oedometer, creep) the strain increment of each step is found by a small Newton on the
law's consistent tangent. Invariants compression positive (``p'``, ``q``, ``eps_v``); the laws
work tension positive in Mandel notation.

* ``mcc-undrained-triaxial``: Modified Cam Clay from an isotropic normally consolidated state,
  undrained triaxial compression (no volume change, ``d eps_r = -d eps_a/2``): the effective
  stress path ``p'/p'_0 = (M^2/(M^2 + eta^2))^Lambda``, ``Lambda = (lambda - kappa)/lambda``
  (Wood 1990). Tolerance 1 %.
* ``mcc-compression-line``: Modified Cam Clay in an oedometer from a K0-NC state on its yield
  surface: the normal compression line ``e = e_N - lambda ln p'`` (and, at the constant K0 of
  normal compression, ``e = e_N' - lambda ln sigma'_v``; Wood 1990; Roscoe & Burland 1968).
  Tolerance 0.5 % of the void-ratio change.
* ``ssc-creep``: Soft Soil Creep, primary loading along K0-NC in one day, then the stress held:
  ``eps_v^c = mu* ln(1 + t/tau_c)``, ``tau_c = tau (p_p^eq/p_eq)^beta`` at the start of the hold
  (Vermeer & Neher 1999). Tolerance 1 % of the creep strain at the end.

One case runs the finite-element solver (a column, :class:`~pilegroup.solver.BiotProblem`
through :func:`~pilegroup.solver.run_stages`):

* ``ssc-oedometer``: a Soft Soil Creep column under its weight, a load on its drained top at
  once, then primary consolidation and creep together for 300 days; the settlement history
  against a fine 1D reference of our own (:mod:`.soft_soil_column`: finite volumes in depth,
  backward Euler, the same law in every cell). Tolerance 1 % of the final settlement.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np

from pilegroup.constitutive.cam_clay import ModifiedCamClay, mcc_undrained_path
from pilegroup.constitutive.critical_state import k0_stress, pq
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep, ssc_creep_strain
from pilegroup.errors import ConstitutiveError
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box, graded_levels
from pilegroup.solver import (
    BiotProblem,
    Discretisation,
    PressureBC,
    SoilMaterial,
    SolverOptions,
    SolverStage,
    StepControl,
    SurfaceLoad,
    run_stages,
)
from pilegroup.solver.qpstate import guarded_update
from pilegroup.studies.verification.common import (
    box_bcs,
    eval_points,
    load_then_consolidate,
    world,
)
from pilegroup.studies.verification.registry import CaseResult, register
from pilegroup.studies.verification.soft_soil_column import CreepColumn, column_settlement

__all__ = ["MCC_CLAY", "SSC_CLAY", "SSC_OEDOMETER", "mcc_compression_line",
           "mcc_undrained_triaxial", "ssc_creep", "ssc_oedometer", "ssc_oedometer_column"]

#: Modified Cam Clay of a soft clay (lambda, kappa, e0, M, nu), values of the order of
#: Wood (1990)'s examples; only the relation to the closed form matters.
MCC_CLAY = {"lam": 0.25, "kappa": 0.05, "e0": 1.5, "M": 1.0, "nu": 0.25}
#: Soft Soil Creep of a soft clay (PLAXIS Material Models manual's ranges:
#: lambda*/mu* ~ 15-25, lambda*/kappa* ~ 5-10).
SSC_CLAY = {"lambda_star": 0.10, "kappa_star": 0.02, "mu_star": 0.004, "phi_deg": 25.0,
            "nu_ur": 0.15}

TOL_UNDRAINED = 0.01  # Wood (1990): p'/p'0 = (M^2/(M^2 + eta^2))^Lambda
TOL_COMPRESSION = 0.005  # Roscoe & Burland (1968), Wood (1990): e = e_N - lambda ln p'
TOL_CREEP = 0.01  # Vermeer & Neher (1999): eps = mu* ln(1 + t/tau_c)
#: ssc-oedometer against the 1D reference (our own, :mod:`.soft_soil_column`; Vermeer & Neher
#: 1999 for the law, Biot's consolidation for the column): 1 % of the final settlement.
TOL_OEDOMETER = 0.01

#: The ssc-oedometer column: 4 m of SSC_CLAY (POP 10 kPa) under its weight (17 kN/m^3),
#: k = 3e-3 m/day, 50 kPa at once on the drained top; primary consolidation is mostly over by
#: 100 days, creep goes on to the end at 300 days.
SSC_OEDOMETER = {"H": 4.0, "q": 50.0, "gamma_sat": 17.0, "k_m_per_day": 3e-3, "porosity": 0.5,
                 "POP": 10.0, "t_end": 300.0}

#: Relative tolerance of a held stress in the material-point Newton.
HOLD_TOL = 1e-11


def _update(law: Any, d: np.ndarray, state: dict, dt: float) -> tuple[np.ndarray, dict, np.ndarray]:
    """One step through the solver's guarded call; a failure is raised, not hidden."""
    sig, trial, tangent, error = guarded_update(law, d[None, :], state, dt)
    if error:
        raise ConstitutiveError(f"material point: {error}")
    return sig[0], trial, tangent[0]


def _hold(law: Any, state: dict, d0: np.ndarray, free: list[int], target: np.ndarray,
          dt: float) -> tuple[dict, np.ndarray, int]:
    """The strain increment whose ``free`` components give the stresses ``target`` there."""
    d = d0.copy()
    scale = max(float(np.abs(target).max()), 1.0)
    for it in range(1, 41):
        sig, trial, D = _update(law, d, state, dt)
        r = sig[free] - target
        if np.abs(r).max() <= HOLD_TOL * scale:
            return trial, d, it
        d[free] -= np.linalg.solve(D[np.ix_(free, free)], r)
    raise ConstitutiveError("material point: the held stresses were not reached in 40 "
                            "Newton iterations")


@register("mcc-undrained-triaxial", options=())
def mcc_undrained_triaxial(size: str = "fast") -> CaseResult:
    """Undrained triaxial compression of isotropically NC Cam Clay against Wood's path."""
    t0 = time.perf_counter()
    law = ModifiedCamClay(**MCC_CLAY)
    p0 = 100.0
    state = law.initial_state(1, -p0 * np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]), pc0=p0)
    steps = 200 if size == "fast" else 2000
    d_ax = 0.20 / steps  # 20 % axial strain
    d = np.array([0.5 * d_ax, 0.5 * d_ax, -d_ax, 0.0, 0.0, 0.0])  # tr(d) = 0 exactly
    err, rows = 0.0, []
    for k in range(1, steps + 1):
        sig, state, _ = _update(law, d, state, 0.0)
        p, q, _ = pq(sig[None, :])
        ref = float(mcc_undrained_path(p0, q / p, law)[0])
        err = max(err, abs(float(p[0]) - ref) / ref)
        if k % (steps // 10) == 0:
            rows.append({"eps_a": k * d_ax, "p_kPa": float(p[0]), "q_kPa": float(q[0]),
                         "p_closed_form_kPa": ref, "u_kPa": p0 + float(sig[0])})
    lam_big = (law.lam - law.kappa) / law.lam
    p_cs = p0 * 0.5**lam_big
    return CaseResult(
        "mcc-undrained-triaxial", err, TOL_UNDRAINED, bool(err <= TOL_UNDRAINED),
        time.perf_counter() - t0, 6, 0, steps,
        reference="Wood (1990): p'/p'0 = (M^2/(M^2 + eta^2))^Lambda, Lambda = (lambda - "
                  "kappa)/lambda (undrained, from isotropic NC)",
        details={"law": MCC_CLAY, "p0_kPa": p0, "path": rows,
                 "q_end_over_q_cs": rows[-1]["q_kPa"] / (law.m * p_cs),
                 "p_cs_closed_form_kPa": p_cs})


@register("mcc-compression-line", options=())
def mcc_compression_line(size: str = "fast") -> CaseResult:
    """Oedometric loading of K0-NC Cam Clay against the normal compression line."""
    t0 = time.perf_counter()
    law = ModifiedCamClay(**MCC_CLAY)
    k0 = law.k0nc()
    sv0, sv1 = 50.0, 800.0
    state = law.initial_state(1, k0_stress(sv0, k0)[0])  # OCR = 1: on the yield surface
    p_start = float(pq(state["stress"])[0][0])
    steps = 40 if size == "fast" else 400
    eps_z, its, err_p, err_v, rows = 0.0, 0, 0.0, 0.0, []
    for k in range(1, steps + 1):
        sv = sv0 * (sv1 / sv0) ** (k / steps)
        state, d, n_it = _hold(law, state, np.zeros(6), [2], np.array([-sv]), 0.0)
        its += n_it
        eps_z += d[2]
        e = law.e0 + (1.0 + law.e0) * eps_z  # eps_v = -eps_z (no lateral strain)
        p = float(pq(state["stress"])[0][0])
        change = law.lam * math.log(sv1 / sv0)  # the whole void-ratio change
        err_p = max(err_p, abs(e - (law.e0 - law.lam * math.log(p / p_start))) / change)
        err_v = max(err_v, abs(e - (law.e0 - law.lam * math.log(sv / sv0))) / change)
        if k % (steps // 8) == 0:
            s = state["stress"][0]
            rows.append({"sigma_v_kPa": sv, "p_kPa": p, "e": float(e),
                         "K0": float(s[0] / s[2])})
    err = float(max(err_p, err_v))
    return CaseResult(
        "mcc-compression-line", err, TOL_COMPRESSION, bool(err <= TOL_COMPRESSION),
        time.perf_counter() - t0, 6, its, steps,
        reference="Roscoe & Burland (1968), Wood (1990): normal compression line "
                  "e = e_N - lambda ln p' (K0-NC, also in sigma'_v); error over the "
                  "void-ratio change lambda ln(800/50)",
        details={"law": MCC_CLAY, "K0nc": k0, "error_in_p": float(err_p),
                 "error_in_sigma_v": float(err_v),
                 "path": rows})


def _ssc_load(law: SoftSoilCreep, sv0: float, sv1: float, t_load: float, steps: int
              ) -> tuple[dict, int]:
    """K0-NC state at ``sv0``, then the K0-NC stress raised to ``sv1`` over ``t_load`` days."""
    state = law.initial_state(1, k0_stress(sv0, law.k0nc)[0])
    its = 0
    for k in range(1, steps + 1):
        target = k0_stress(sv0 + (sv1 - sv0) * k / steps, law.k0nc)[0]
        state, _, n_it = _hold(law, state, np.zeros(6), list(range(6)), target, t_load / steps)
        its += n_it
    return state, its


@register("ssc-creep", options=())
def ssc_creep(size: str = "fast") -> CaseResult:
    """Creep of Soft Soil Creep under a constant effective stress after primary loading."""
    t0 = time.perf_counter()
    law = SoftSoilCreep(**SSC_CLAY)
    state, its = _ssc_load(law, 100.0, 200.0, 1.0, 20)
    held = state["stress"][0].copy()
    tau_c = float(law.creep_time(state["stress"], state["pp"])[0])
    growth = 1.1 if size == "fast" else 1.01  # ratio of successive times
    t_first, t_end = 1e-3 * tau_c, 1e3
    times = np.geomspace(t_first, t_end, math.ceil(math.log(t_end / t_first) / math.log(growth))
                         + 1)
    t_prev, eps_v, err, rows = 0.0, 0.0, 0.0, []
    ref_end = float(ssc_creep_strain(times[-1], tau_c, law.mu_star))
    for k, t in enumerate(times):
        state, d, n_it = _hold(law, state, np.zeros(6), list(range(6)), held, t - t_prev)
        its += n_it
        eps_v -= d[:3].sum()
        t_prev = t
        err = max(err, abs(eps_v - float(ssc_creep_strain(t, tau_c, law.mu_star))) / ref_end)
        if k % max(1, times.size // 8) == 0 or k == times.size - 1:
            rows.append({"t_day": float(t), "eps_v": float(eps_v),
                         "closed_form": float(ssc_creep_strain(t, tau_c, law.mu_star))})
    return CaseResult(
        "ssc-creep", float(err), TOL_CREEP, bool(err <= TOL_CREEP), time.perf_counter() - t0, 6,
        its, times.size,
        reference="Vermeer & Neher (1999): eps_v^c = mu* ln(1 + t/tau_c), tau_c = tau "
                  "(p_p^eq/p_eq)^((lambda*-kappa*)/mu*) at the start of the hold; error over "
                  "the creep strain at t = 1000 days",
        details={"law": SSC_CLAY, "M": law.m, "tau_c_day": tau_c, "time_ratio": growth,
                 "loading": "K0-NC, sigma'_v 100 -> 200 kPa in 1 day (20 steps)",
                 "history": rows})


def ssc_oedometer_column() -> CreepColumn:
    """The column of ``ssc-oedometer`` (:data:`SSC_OEDOMETER`)."""
    c = SSC_OEDOMETER
    law = SoftSoilCreep(**SSC_CLAY, POP=c["POP"])
    return CreepColumn(law, H=c["H"], q=c["q"], gamma_sat=c["gamma_sat"],
                       k_m_per_day=c["k_m_per_day"], porosity=c["porosity"])


def _column_problem(col: CreepColumn, nz: int, pair: str, preset: str, comm: Any
                    ) -> BiotProblem:
    """The column on a 1 x 1 x H box, cells finer towards the drained top."""
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), graded_levels(-col.H, 0.0, nz, ratio=4.0),
                   1, 1)
    soil = SoilMaterial(col.law, k_m_per_day=col.k_m_per_day, porosity=col.porosity,
                        gamma_sat=col.gamma_sat, K0=col.law.k0nc)
    return BiotProblem(md, {groups.soil_layer(1): soil}, Discretisation(pair=pair),
                       displacement_bcs=box_bcs(), pressure_bcs=[PressureBC(groups.GROUND)],
                       loads=[SurfaceLoad(groups.GROUND, col.q)],
                       options=SolverOptions(preset=preset, prefix=f"sscoed_{pair}_"))


@register("ssc-oedometer")
def ssc_oedometer(size: str = "fast", pair: str = "Q2Q1", preset: str = "direct",
                  comm: Any = None) -> CaseResult:
    """Primary consolidation and creep of a Soft Soil Creep column against a fine 1D reference.

    The column of :func:`ssc_oedometer_column` (sides on rollers, bottom fixed and
    impermeable, top drained): the geostatic stage, the load at once (one undrained step),
    then consolidation to 300 days. Error: the largest difference of the top's settlement from
    the reference's at 13 times from 0.1 to 300 days (log-spaced), over the reference's
    settlement at 300 days. Fast: 16 element layers, steps growing by 10^(1/32) (7.5 %);
    bench: 32 and 10^(1/64). The reference: 200 cells and steps growing by 2 % (fast), 400 and
    1 % (bench). Both are backward Euler: the error is the finite-element steps' lag, about
    half for twice the steps (docs/model.md).
    """
    comm = comm or world()
    t0 = time.perf_counter()
    col = ssc_oedometer_column()
    nz, spd = {"fast": (16, 32), "bench": (32, 64)}[size]
    t_end = SSC_OEDOMETER["t_end"]
    times = np.geomspace(0.1, t_end, 13)
    pb = _column_problem(col, nz, pair, preset, comm)
    ts = StepControl(dt0=1e-4, dt_min=1e-10, grow=10.0 ** (1.0 / spd), easy_newton=50,
                     milestones=tuple(times[:-1]))
    fe: dict[float, float] = {}

    def record(problem: Any, t: float, stage: str) -> None:
        if stage == "consolidation" and np.any(np.isclose(t, times, rtol=1e-9)):
            fe[t] = -float(np.atleast_1d(eval_points(problem.u, np.array([[0.5, 0.5, 0.0]])))[2])

    stages = [SolverStage("geostatic", "geostatic"), *load_then_consolidate(t_end)]
    log = run_stages(pb, stages, ts, on_milestone=record)
    t_fe = time.perf_counter() - t0
    cells, growth = {"fast": (200, 1.02), "bench": (400, 1.01)}[size]
    ref, ref_steps = column_settlement(col, times, cells=cells, growth=growth)
    s_fe = np.array([fe.get(float(t), math.nan) for t in times])
    err = float(np.max(np.abs(s_fe - ref)) / ref[-1]) if np.all(np.isfinite(s_fe)) else math.inf
    rows = [{"t_day": float(t), "settlement_m": float(a), "reference_m": float(b)}
            for t, a, b in zip(times, s_fe, ref, strict=True)]
    return CaseResult(
        "ssc-oedometer", err, TOL_OEDOMETER, bool(err <= TOL_OEDOMETER),
        time.perf_counter() - t0, pb.num_dofs, log.newton_total, len(log.steps),
        reference="a fine 1D reference of our own (studies/verification/soft_soil_column.py:"
                  " finite volumes in depth, backward Euler, the same Soft Soil Creep law of"
                  " Vermeer & Neher 1999 in each cell); error over the settlement at 300 days",
        details={"law": SSC_CLAY, "column": SSC_OEDOMETER, "pair": pair, "nz": nz,
                 "steps_per_decade": spd, "reference_cells": cells,
                 "reference_growth": growth, "reference_steps": ref_steps,
                 "fe_wall_s": t_fe, "geostatic_max_u_m": log.geostatic_max_u,
                 "ranks": comm.size, "history": rows})
