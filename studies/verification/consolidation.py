"""Consolidation cases: Terzaghi's column (also under dry soil) and Mandel's slab.

Each case meshes a column or slab with :func:`pilegroup.geometry.box.build_box`, runs a
:class:`~pilegroup.solver.BiotProblem` through :func:`~pilegroup.solver.run_stages` and returns a
:class:`~pilegroup.studies.verification.registry.CaseResult` with its error, the tolerance and
the source of the reference. Also here: the pressure profile of the Terzaghi column after its
first step (the spurious-oscillation check of the element pairs, docs/solver.md).
"""

from __future__ import annotations

import functools
import math
import time
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box, graded_levels
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver import (
    GAMMA_W,
    BiotProblem,
    Discretisation,
    DisplacementBC,
    PressureBC,
    RigidPlate,
    SolverOptions,
    SolverStage,
    StepControl,
    SurfaceLoad,
    run_stages,
)
from pilegroup.studies.verification.common import (
    ElasticSoil,
    box_bcs,
    eval_points,
    load_then_consolidate,
    p_along,
    soil_problem,
    world,
)
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["MandelSlab", "TerzaghiColumn", "TerzaghiWaterTable", "first_step_oscillation",
           "mandel", "mandel_centre_pressure", "mandel_roots", "oscillation_measure", "terzaghi",
           "terzaghi_degree", "terzaghi_series", "terzaghi_water_table"]


# ---------------------------------------------------------------------------- closed forms
def terzaghi_series(depth: np.ndarray, H: float, T: float, p0: float,
                    n_terms: int = 400) -> np.ndarray:
    """Terzaghi's excess pressure (kPa) at ``depth`` (m below the drained top).

    The layer has thickness ``H`` and is drained at the top only; ``T = c_v t / H^2``.
    ``p = sum_m 2 p0 / M sin(M depth / H) exp(-M^2 T)``, ``M = pi (2m + 1)/2`` (Terzaghi 1925;
    Verruijt, *Theory and Problems of Poroelasticity*, 2016, ch. 2).
    """
    d = np.asarray(depth, dtype=float) / H
    m = np.arange(n_terms)
    M = np.pi * (2 * m + 1) / 2.0
    c = 2.0 * p0 / M * np.exp(-(M**2) * T)
    keep = np.abs(c) > 1e-16 * p0
    return np.sin(np.outer(d, M[keep])) @ c[keep]


def terzaghi_degree(T: float, n_terms: int = 400) -> float:
    """Average degree of consolidation ``U(T) = 1 - sum 2/M^2 exp(-M^2 T)``."""
    m = np.arange(n_terms)
    M = np.pi * (2 * m + 1) / 2.0
    return float(1.0 - np.sum(2.0 / M**2 * np.exp(-(M**2) * T)))


def mandel_roots(C: float, n: int) -> np.ndarray:
    """First ``n`` positive roots of ``tan(a) = C a`` (``C > 1``), by bisection."""
    roots = []
    for i in range(n):
        lo = (i - 0.5) * np.pi + 1e-12 if i > 0 else 1e-9
        hi = (i + 0.5) * np.pi - 1e-12

        def f(a: float) -> float:
            return math.sin(a) - C * a * math.cos(a)

        flo = f(lo)
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            fm = f(mid)
            if (fm > 0) == (flo > 0):
                lo, flo = mid, fm
            else:
                hi = mid
        roots.append(0.5 * (lo + hi))
    return np.array(roots)


def mandel_centre_pressure(t: np.ndarray, F: float, a: float, B: float, nu: float,
                           nu_u: float, c: float, n_terms: int = 200) -> np.ndarray:
    """Mandel's pore pressure (kPa) at the centre ``x = 0`` of a specimen of half-width ``a``.

    Formula: ``p(x,t) = 2 F B (1+nu_u) / (3a) sum_i sin(a_i)/(a_i - sin a_i cos a_i)
    (cos(a_i x/a) - cos a_i) exp(-a_i^2 c t / a^2)`` with ``tan a_i = (1-nu)/(nu_u-nu) a_i``;
    ``2F`` is the force per unit length on the plate of width ``2a`` (Abousleiman, Cheng,
    Cui, Detournay & Roegiers, Géotechnique 46(2), 1996, Eq. 21; Cheng & Detournay, Int. J.
    Numer. Anal. Methods Geomech. 12, 1988). At ``t = 0+`` the pressure is uniform,
    ``F B (1+nu_u)/(3a)``.
    """
    al = mandel_roots((1.0 - nu) / (nu_u - nu), n_terms)
    coef = np.sin(al) / (al - np.sin(al) * np.cos(al)) * (1.0 - np.cos(al))
    tt = np.atleast_1d(np.asarray(t, dtype=float))
    return 2.0 * F * B * (1.0 + nu_u) / (3.0 * a) * (
        np.exp(-np.outer(tt, al**2) * c / a**2) @ coef)


# ---------------------------------------------------------------------------- Terzaghi
#: Time factors ``T_v = c_v t / H^2`` at which the Terzaghi column is compared.
TERZAGHI_T_V = (0.05, 0.2, 0.5, 1.0)


@dataclass(frozen=True)
class TerzaghiColumn:
    """Terzaghi's column: 1 x 1 x ``H`` m of ``soil``, ``q`` (kPa) on the drained top.

    Sides on rollers, bottom fixed and impermeable, top drained and loaded.
    """

    H: float = 10.0
    q: float = 100.0
    soil: ElasticSoil = ElasticSoil()

    @property
    def m_oed(self) -> float:
        """Oedometric modulus, kPa."""
        E, nu = self.soil.E, self.soil.nu
        return E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))

    @property
    def p0(self) -> float:
        """Excess pressure after the undrained loading, ``q / (1 + m S)``, kPa."""
        return self.q / (1.0 + self.m_oed * self.soil.material().storage)

    @property
    def cv(self) -> float:
        """Coefficient of consolidation ``(k / gamma_w) / (S + 1/m)``, m^2/day."""
        return (self.soil.k / GAMMA_W) / (self.soil.material().storage + 1.0 / self.m_oed)

    def settlement(self, T: float) -> float:
        """Settlement (m) of the top at time factor ``T``: ``(q H - H p0 (1 - U(T))) / m``."""
        return (self.q * self.H - self.H * self.p0 * (1.0 - terzaghi_degree(T))) / self.m_oed

    def problem(self, md: MeshData, disc: Discretisation,
                options: SolverOptions | None = None) -> BiotProblem:
        """The column's problem on the box mesh ``md``."""
        return soil_problem(md, self.soil.material(), disc, box_bcs(),
                            pressure_bcs=[PressureBC(groups.GROUND)],
                            loads=[SurfaceLoad(groups.GROUND, self.q)], options=options)


def _terzaghi_record(col: TerzaghiColumn, times: list[float], rows: list[dict[str, float]],
                     pb: BiotProblem, t: float, stage: str) -> None:
    """Milestone callback: at a compared time, the pressure and settlement errors."""
    for T, tm in zip(TERZAGHI_T_V, times, strict=True):
        if abs(t - tm) <= 1e-9 * tm:
            zq = np.linspace(-col.H, 0.0, 201)
            ph = p_along(pb, zq, 0.5, 0.5)
            pe = terzaghi_series(-zq, col.H, T, col.p0)
            e_p = float(np.sqrt(np.trapezoid((ph - pe) ** 2, zq) / np.trapezoid(pe**2, zq)))
            uz = eval_points(pb.u, np.array([[0.5, 0.5, 0.0]]))
            s_h = -float(np.atleast_1d(uz)[2])
            s_e = col.settlement(T)
            rows.append({"T_v": T, "t_day": t, "err_p": e_p, "settlement_m": s_h,
                         "settlement_ref_m": s_e, "err_s": abs(s_h - s_e) / s_e})


@register("terzaghi")
def terzaghi(size: str = "fast", pair: str = "Q2Q1", nz: int | None = None,
             steps_per_decade: int | None = None, dT_max: float | None = None,
             preset: str = "direct", comm: MPI.Comm | None = None) -> CaseResult:
    """1D consolidation of a column drained at the top (Terzaghi 1925).

    Column 1 x 1 x 10 m, E = 10 MPa, nu = 0.3, k = 1e-3 m/day, n = 0.4; 100 kPa applied
    instantaneously on the top (one undrained step), then consolidation; sides on rollers,
    bottom fixed and impermeable, top drained. The reference is the series solution with
    water compressibility: ``p0 = q/(1 + m S)``, ``c_v = (k/gamma_w)/(S + 1/m)``
    (``m`` oedometric modulus), settlement ``s = (q H - H p0 (1 - U))/m``.

    Error: the largest, over T_v = 0.05, 0.2, 0.5, 1.0, of the relative L2 error of p over
    depth (against the exact profile's L2 norm at that time) and the relative settlement
    error. Tolerance 1 %.
    """
    comm = comm or world()
    t0 = time.perf_counter()
    nz = nz or {"fast": 16, "bench": 32}[size]
    spd = steps_per_decade or {"fast": 16, "bench": 32}[size]
    dT_max = dT_max or {"fast": 2e-3, "bench": 1e-3}[size]
    col = TerzaghiColumn()
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), graded_levels(-col.H, 0.0, nz, ratio=4.0), 1, 1)
    problem = col.problem(md, Discretisation(pair=pair),
                          SolverOptions(preset=preset, prefix=f"terz_{pair}_"))
    times = [T * col.H**2 / col.cv for T in TERZAGHI_T_V]
    t_end = times[-1]
    ts = StepControl(dt0=1e-4 * t_end, dt_min=1e-12, dt_max=dT_max * t_end,
                      grow=10.0 ** (1.0 / spd), hold=1, milestones=tuple(times[:-1]))
    rows: list[dict[str, float]] = []
    log = run_stages(problem, load_then_consolidate(t_end), ts,
                     on_milestone=functools.partial(_terzaghi_record, col, times, rows))
    ok_rows = len(rows) == len(TERZAGHI_T_V)
    err = max(max(r["err_p"], r["err_s"]) for r in rows) if ok_rows else math.inf
    tol = 0.01
    return CaseResult(
        "terzaghi", err, tol, bool(err <= tol), time.perf_counter() - t0, problem.num_dofs,
        log.newton_total, len(log.steps),
        reference="Terzaghi (1925) series; Verruijt (2016) ch. 2",
        details={"pair": pair, "nz": nz, "steps_per_decade": spd, "dT_max": dT_max,
                 "rows": rows,
                 "c_v_m2_per_day": col.cv, "p0_kPa": col.p0, "ranks": comm.size,
                 "timings": problem.timings})


# ---------------------------------------------------------------------------- water table
@dataclass(frozen=True)
class TerzaghiWaterTable(TerzaghiColumn):
    """Terzaghi's column under ``dry`` m of dry soil: the water table ``dry`` m down.

    1 x 1 x (``dry`` + ``H``) m with its weight (``gamma_sat`` below the water table,
    ``gamma_unsat`` above), ``q`` (kPa) on the top; sides on rollers, bottom fixed and
    impermeable. The saturated ``H`` m are drained at the water table (the top of the dry
    soil is not a boundary of the water), the dry soil carries ``q`` down to it.
    """

    dry: float = 2.0
    gamma_sat: float = 20.0
    gamma_unsat: float = 17.0

    def settlement(self, T: float) -> float:
        """Settlement (m) of the top: the dry soil's ``q dry / m`` plus Terzaghi's below it."""
        return self.q * self.dry / self.m_oed + super().settlement(T)

    def problem(self, md: MeshData, disc: Discretisation,
                options: SolverOptions | None = None) -> BiotProblem:
        """The column's problem on the box mesh ``md`` (a node level at the water table)."""
        soil = replace(self.soil.material(), gamma_sat=self.gamma_sat,
                       gamma_unsat=self.gamma_unsat)
        return BiotProblem(md, {groups.soil_layer(1): soil}, disc, displacement_bcs=box_bcs(),
                           pressure_bcs=[PressureBC(None, level=-self.dry)],
                           loads=[SurfaceLoad(groups.GROUND, self.q)], options=options,
                           water_table=-self.dry)


def _water_table_record(col: TerzaghiWaterTable, times: list[float],
                        rows: list[dict[str, float]], pb: BiotProblem, t: float,
                        stage: str) -> None:
    """Milestone callback: pressure (saturated and dry soil) and settlement errors."""
    for T, tm in zip(TERZAGHI_T_V, times, strict=True):
        if abs(t - tm) <= 1e-9 * tm:
            zq = np.linspace(-col.dry - col.H, -col.dry, 201)
            ph = p_along(pb, zq, 0.5, 0.5)
            pe = terzaghi_series(-col.dry - zq, col.H, T, col.p0)
            e_p = float(np.sqrt(np.trapezoid((ph - pe) ** 2, zq) / np.trapezoid(pe**2, zq)))
            p_dry = float(np.abs(p_along(pb, np.linspace(-col.dry, 0.0, 21), 0.5, 0.5)).max())
            s_h = -float(np.atleast_1d(eval_points(pb.u, np.array([[0.5, 0.5, 0.0]])))[2])
            s_e = col.settlement(T)
            rows.append({"T_v": T, "t_day": t, "err_p": e_p, "p_dry_kPa": p_dry,
                         "settlement_m": s_h, "settlement_ref_m": s_e,
                         "err_s": abs(s_h - s_e) / s_e})


@register("terzaghi-water-table")
def terzaghi_water_table(size: str = "fast", pair: str = "Q2Q1", preset: str = "direct",
                         comm: MPI.Comm | None = None) -> CaseResult:
    """Terzaghi's column with the water table 2 m below the loaded top (Terzaghi 1925).

    12 m of soil with its weight (20 kN/m^3 saturated, 17 kN/m^3 above the water table), the
    water table 2 m down, E = 10 MPa, nu = 0.3, k = 1e-3 m/day, n = 0.4: a geostatic stage,
    then 100 kPa on the top at once (one undrained step) and consolidation. The reference is
    :func:`terzaghi`'s series for the 10 m below the water table, drained there, plus the dry
    soil's oedometric compression ``q dry / m``; the dry soil carries no pore pressure.

    Error: the largest, over T_v = 0.05, 0.2, 0.5, 1.0, of the relative L2 error of p over the
    saturated depth, the relative settlement error and the largest |p| in the dry soil over
    ``p0``. Tolerance 1 %.
    """
    comm = comm or world()
    t0 = time.perf_counter()
    nz, spd, dT_max = {"fast": (16, 16, 2e-3), "bench": (32, 32, 1e-3)}[size]
    col = TerzaghiWaterTable()
    levels = np.concatenate([graded_levels(-col.dry - col.H, -col.dry, nz, ratio=4.0)[:-1],
                             np.linspace(-col.dry, 0.0, 3)])
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), levels, 1, 1)
    problem = col.problem(md, Discretisation(pair=pair),
                          SolverOptions(preset=preset, prefix=f"terzwt_{pair}_"))
    times = [T * col.H**2 / col.cv for T in TERZAGHI_T_V]
    ts = StepControl(dt0=1e-4 * times[-1], dt_min=1e-12, dt_max=dT_max * times[-1],
                      grow=10.0 ** (1.0 / spd), hold=1, milestones=tuple(times[:-1]))
    rows: list[dict[str, float]] = []
    log = run_stages(problem, [SolverStage("geostatic", "geostatic"),
                               *load_then_consolidate(times[-1])], ts,
                     on_milestone=functools.partial(_water_table_record, col, times, rows),
                     geostatic_tol=1e-9)
    err = max(max(r["err_p"], r["err_s"], r["p_dry_kPa"] / col.p0) for r in rows) \
        if len(rows) == len(TERZAGHI_T_V) else math.inf
    tol = 0.01
    return CaseResult(
        "terzaghi-water-table", err, tol, bool(err <= tol), time.perf_counter() - t0,
        problem.num_dofs, log.newton_total, len(log.steps),
        reference="Terzaghi (1925) series below the water table, drained there; Verruijt"
                  " (2016) ch. 2; the dry soil's oedometric compression",
        details={"pair": pair, "nz": nz, "rows": rows, "geostatic_max_u_m": log.geostatic_max_u,
                 "c_v_m2_per_day": col.cv, "p0_kPa": col.p0, "ranks": comm.size})


# ---------------------------------------------------------------------------- Mandel
#: Dimensionless times ``c t / a^2`` at which Mandel's centre pressure is compared.
MANDEL_T_STAR = (0.001, 0.003, 0.01, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0)


@dataclass(frozen=True)
class MandelSlab:
    """Quarter of Mandel's specimen: ``x in [0, a]``, ``z in [0, b]``, ``thick`` along y.

    Lengths in m; ``F`` is the plate force per metre of thickness (kN/m). The undrained
    constants include the water compressibility.
    """

    a: float = 1.0
    b: float = 1.0
    thick: float = 0.1
    F: float = 100.0
    soil: ElasticSoil = ElasticSoil(nu=0.25, porosity=0.3)

    def constants(self) -> dict[str, float]:
        """Undrained constants and the consolidation coefficient.

        Keys: Skempton's ``B``, the undrained ``nu_u``, the consolidation coefficient ``c``
        (m^2/day) and the initial centre pressure ``p0 = F B (1 + nu_u) / (3 a)`` (kPa).
        """
        E, nu = self.soil.E, self.soil.nu
        K = E / (3 * (1 - 2 * nu))
        G = E / (2 * (1 + nu))
        Mb = 1.0 / self.soil.material().storage
        Ku = K + Mb
        B = Mb / Ku
        nu_u = (3 * Ku - 2 * G) / (2 * (3 * Ku + G))
        kappa = self.soil.k / GAMMA_W
        c = 2 * kappa * B**2 * G * (1 - nu) * (1 + nu_u) ** 2 / (9 * (1 - nu_u) * (nu_u - nu))
        p0 = self.F * B * (1 + nu_u) / (3 * self.a)
        return {"B": B, "nu_u": nu_u, "c": c, "p0": p0}

    def problem(self, md: MeshData, disc: Discretisation, options: SolverOptions
                ) -> BiotProblem:
        """The slab's problem on the box mesh ``md``.

        Rollers on ``x = 0`` and ``z = 0``, plane strain in y, drained at ``x = a``, the rigid
        frictionless plate on top under force control.
        """
        return soil_problem(
            md, self.soil.material(), disc,
            [DisplacementBC(groups.SIDE_XMIN, 0), DisplacementBC(groups.BOTTOM, 2),
             DisplacementBC(groups.SIDE_YMIN, 1), DisplacementBC(groups.SIDE_YMAX, 1)],
            pressure_bcs=[PressureBC(groups.SIDE_XMAX)],
            plates=[RigidPlate(groups.GROUND, 2, -self.F * self.thick)], options=options)


def _mandel_record(slab: MandelSlab, times: list[float], rows: list[dict[str, float]],
                   pb: BiotProblem, t: float, stage: str) -> None:
    """Milestone callback: the centre pressure against the series at a compared time."""
    cst = slab.constants()
    p0 = cst["p0"]
    centre = np.array([[0.0, 0.5 * slab.thick, 0.5 * slab.b]])
    ph = float(np.atleast_1d(eval_points(pb.p, centre))[0])
    if stage == "load":
        rows.append({"t_star": 0.0, "t_day": 0.0, "p_h": ph, "p_ref": p0,
                     "err": abs(ph - p0) / p0})
        return
    for T, tm in zip(MANDEL_T_STAR, times, strict=True):
        if abs(t - tm) <= 1e-9 * tm:
            pe = float(mandel_centre_pressure(np.array([tm]), slab.F, slab.a, cst["B"],
                                              slab.soil.nu, cst["nu_u"], cst["c"])[0])
            rows.append({"t_star": T, "t_day": t, "p_h": ph, "p_ref": pe,
                         "err": abs(ph - pe) / p0})


@register("mandel")
def mandel(size: str = "fast", pair: str = "Q2Q1", n: int | None = None,
           steps_per_decade: int | None = None, dT_max: float | None = None,
           preset: str = "direct", comm: MPI.Comm | None = None) -> CaseResult:
    """Mandel's problem (Mandel 1953): the Mandel–Cryer rise of the centre pressure.

    Plane strain as a one-cell-thick 3D slab (``u_y = 0`` on both faces), quarter domain by
    symmetry: ``x in [0, a]``, ``z in [0, b]``, ``a = b = 1 m``, rollers on ``x = 0`` and
    ``z = 0``, drained and traction-free at ``x = a``, impermeable elsewhere; a rigid frictionless
    plate on ``z = b`` carries ``F = 100 kN`` per metre of thickness (a :class:`RigidPlate`,
    force control), applied instantaneously (one undrained step), then held.
    E = 10 MPa, nu = 0.25, k = 1e-3 m/day, n = 0.3, water compressibility included
    (Skempton B < 1).

    Reference: Abousleiman, Cheng, Cui, Detournay & Roegiers (1996), Géotechnique 46(2),
    187–195, Eq. 21 (Cheng & Detournay 1988) — see :func:`mandel_centre_pressure`. Error: the
    largest, over the output times ``c t / a^2`` in (0.001 ... 1), of ``|p_h(0) - p(0)| / p0``
    at the centre, ``p0 = F B (1 + nu_u) / (3 a)``. Tolerance 2 %. The details also
    report the peak ``max p(0,t)/p0`` of both (Mandel–Cryer: > 1).
    """
    comm = comm or world()
    t0 = time.perf_counter()
    slab = MandelSlab()
    n = n or {"fast": 8, "bench": 16}[size]
    spd = steps_per_decade or {"fast": 8, "bench": 16}[size]
    dT_max = dT_max or {"fast": 0.02, "bench": 0.01}[size]
    md = build_box(comm, (0.0, slab.a), (0.0, slab.thick), np.linspace(0.0, slab.b, n + 1), n, 1)
    problem = slab.problem(md, Discretisation(pair=pair),
                           SolverOptions(preset=preset, prefix=f"mandel_{pair}_"))
    cst = slab.constants()
    times = [T * slab.a**2 / cst["c"] for T in MANDEL_T_STAR]
    t_end = times[-1]
    ts = StepControl(dt0=1e-5 * t_end, dt_min=1e-14, dt_max=dT_max * t_end,
                      grow=10.0 ** (1.0 / spd), milestones=tuple(times[:-1]))
    rows: list[dict[str, float]] = []
    log = run_stages(problem, load_then_consolidate(t_end), ts,
                     on_milestone=functools.partial(_mandel_record, slab, times, rows))
    ok_rows = len(rows) == len(MANDEL_T_STAR) + 1
    err = max(r["err"] for r in rows) if ok_rows else math.inf
    peak_h = max(r["p_h"] for r in rows) / cst["p0"]
    peak_e = max(r["p_ref"] for r in rows) / cst["p0"]
    tol = 0.02
    passed = bool(err <= tol and peak_h > 1.0)
    return CaseResult(
        "mandel", err, tol, passed, time.perf_counter() - t0, problem.num_dofs,
        log.newton_total, len(log.steps),
        reference="Abousleiman et al. (1996) Geotechnique 46(2) Eq. 21; Cheng & Detournay (1988)",
        details={"pair": pair, "n": n, "steps_per_decade": spd, "dT_max": dT_max, "rows": rows,
                 "peak_ratio_fe": peak_h, "peak_ratio_ref": peak_e, "B": cst["B"],
                 "nu_u": cst["nu_u"], "c_m2_per_day": cst["c"], "p0_kPa": cst["p0"],
                 "ranks": comm.size, "timings": problem.timings})


# ---------------------------------------------------------------------------- first-step check
def oscillation_measure(p: np.ndarray, p0: float) -> float:
    """Spurious-oscillation measure of a pressure profile ordered by increasing depth.

    In 1D consolidation just after loading, the exact excess pressure rises monotonically from
    0 at the drained top to ``p0``. The measure adds the overshoot above ``p0`` and every
    decrease with depth, relative to ``p0``: 0 for a monotone, bounded profile.
    """
    p = np.asarray(p, dtype=float)
    over = max(0.0, float(p.max()) - p0)
    drops = float(np.clip(p[:-1] - p[1:], 0.0, None).sum())
    return (over + drops) / p0


def first_step_oscillation(pair: str = "Q2Q1", stabilise: bool = True, nz: int = 20,
                           T_first: float = 0.0, comm: MPI.Comm | None = None,
                           undrained_first: bool = True, stab_factor: float = 1.0
                           ) -> dict[str, Any]:
    """Pressure profile of the Terzaghi column after the first step; its oscillation measure.

    ``T_first = 0`` is the undrained loading step (``dt = 0``); a small positive ``T_first``
    adds one drained step of that time factor, or, with ``undrained_first = False``, applies
    the load in that one drained step from rest. Uniform mesh of ``nz`` cells, same data as
    :func:`terzaghi`; ``stab_factor`` scales the pressure stabilisation
    (:class:`~pilegroup.solver.Discretisation`). Returns ``{"measure", "profile", "z", "p0",
    "nodes"}``: ``profile`` at vertices and quarter points by increasing depth ``z`` (m,
    negative), ``nodes`` its values at the vertices (the Q1 pressure nodes, top first).
    """
    comm = comm or world()
    col = TerzaghiColumn()
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), np.linspace(-col.H, 0.0, nz + 1), 1, 1)
    pb = col.problem(md, Discretisation(pair=pair, stabilise=stabilise, stab_factor=stab_factor))
    steps = ([0.0] if undrained_first or T_first <= 0 else []) \
        + ([T_first * col.H**2 / col.cv] if T_first > 0 else [])
    for dt in steps:
        info = pb.solve_step(dt, 1.0)
        assert info.converged, info.message
        pb.commit()
    z = np.linspace(0.0, -col.H, 4 * nz + 1)  # by increasing depth (vertices and quarter points)
    prof = p_along(pb, z, 0.0, 0.0)
    return {"measure": oscillation_measure(prof, col.p0), "profile": prof, "z": z, "p0": col.p0,
            "nodes": prof[::4]}
