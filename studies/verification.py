"""Verification cases: the real pipeline against closed-form solutions.

Each case meshes a column or block with :func:`pilegroup.geometry.box.build_box`, runs
:class:`pilegroup.solver.biot.BiotProblem` through :func:`pilegroup.solver.stepping.run_stages`
and returns a :class:`CaseResult` with its error, the tolerance and the source of the reference.
Run ``python -m pilegroup.studies.verification [CASE ...] [--size fast|bench] [--json]``
(also under ``mpirun -n 2``).
"""

from __future__ import annotations

import argparse
import json as _json
import math
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

import pilegroup  # noqa: F401  (dolfinx_solver before dolfinx)
from pilegroup.fileio import json_default

__all__ = ["CASES", "CaseResult", "bench_markdown", "bench_verification", "main",
           "mandel", "mandel_centre_pressure", "run_cases", "terzaghi", "terzaghi_series",
           "triaxial"]


@dataclass
class CaseResult:
    """Outcome of one verification case (``error`` and ``tolerance`` are relative)."""

    case: str
    error: float
    tolerance: float
    passed: bool
    wall_s: float
    dofs: int
    newton_its: int = 0
    steps: int = 0
    reference: str = ""
    details: dict[str, Any] = field(default_factory=dict)

    def line(self) -> str:
        """One human-readable line."""
        flag = "PASS" if self.passed else "FAIL"
        return (f"{self.case:<10} {flag}  error {self.error:.3e}  tol {self.tolerance:.1e}  "
                f"dofs {self.dofs}  steps {self.steps}  newton {self.newton_its}  "
                f"wall {self.wall_s:.2f} s")


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


# ---------------------------------------------------------------------------- helpers
def _comm() -> Any:
    from mpi4py import MPI

    return MPI.COMM_WORLD


def _p_along(problem: Any, z: np.ndarray, x: float, y: float) -> np.ndarray:
    """Pressure at points ``(x, y, z)`` gathered on every rank (kPa)."""
    return _eval_points(problem.p, np.column_stack([np.full_like(z, x), np.full_like(z, y), z]))


def _eval_points(f: Any, pts: np.ndarray) -> np.ndarray:
    from dolfinx import geometry
    from mpi4py import MPI

    mesh = f.function_space.mesh
    comm = mesh.comm
    tree = geometry.bb_tree(mesh, mesh.topology.dim)
    cand = geometry.compute_collisions_points(tree, pts)
    coll = geometry.compute_colliding_cells(mesh, cand, pts)
    nloc = mesh.topology.index_map(mesh.topology.dim).size_local
    bs = f.function_space.dofmap.bs
    vals = np.zeros((pts.shape[0], bs))
    found = np.zeros(pts.shape[0])
    for i in range(pts.shape[0]):
        cells = coll.links(i)
        cells = cells[cells < nloc]
        if cells.size:
            vals[i] = f.eval(pts[i], cells[:1])
            found[i] = 1.0
    vals = comm.allreduce(vals, op=MPI.SUM)
    found = comm.allreduce(found, op=MPI.SUM)
    return (vals / np.maximum(found, 1.0)[:, None]).squeeze()


# ---------------------------------------------------------------------------- Terzaghi
def terzaghi(size: str = "fast", pair: str = "Q2Q1", nz: int | None = None,
             steps_per_decade: int | None = None, dT_max: float | None = None,
             preset: str = "direct", comm: Any = None) -> CaseResult:
    """1D consolidation of a column drained at the top (Terzaghi 1925).

    Column 1 x 1 x 10 m, E = 10 MPa, nu = 0.3, k = 1e-3 m/day, n = 0.4; 100 kPa applied
    instantaneously on the top (one undrained step), then consolidation; sides on rollers,
    bottom fixed and impermeable, top drained. The reference is the series solution with
    water compressibility: ``p0 = q/(1 + m S)``, ``c_v = (k/gamma_w)/(S + 1/m)``
    (``m`` oedometric modulus), settlement ``s = (q H - H p0 (1 - U))/m``.

    Error: the largest, over T_v = 0.05, 0.2, 0.5, 1.0, of the relative L2 error of p over
    depth (against the exact profile's L2 norm at that time) and the relative settlement
    error. Tolerance 1 % (issue 5).
    """
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.geometry.box import build_box, graded_levels
    from pilegroup.solver import (
        GAMMA_W,
        BiotProblem,
        Discretisation,
        DisplacementBC,
        PressureBC,
        SoilMaterial,
        SolverOptions,
        Stage,
        SurfaceLoad,
        TimeStepping,
        run_stages,
    )

    comm = comm or _comm()
    t0 = time.perf_counter()
    H, E, nu, k, n, q = 10.0, 1.0e4, 0.3, 1.0e-3, 0.4, 100.0
    nz = nz or {"fast": 16, "bench": 32}[size]
    spd = steps_per_decade or {"fast": 16, "bench": 32}[size]
    dT_max = dT_max or {"fast": 2e-3, "bench": 1e-3}[size]
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), graded_levels(-H, 0.0, nz, ratio=4.0), 1, 1)
    mat = SoilMaterial(LinearElastic(E, nu), k_m_per_day=k, porosity=n)
    m_oed = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    S = mat.storage
    p0 = q / (1.0 + m_oed * S)
    cv = (k / GAMMA_W) / (S + 1.0 / m_oed)
    Ts = [0.05, 0.2, 0.5, 1.0]
    times = [T * H**2 / cv for T in Ts]
    problem = BiotProblem(
        md, {"soil_layer_01": mat}, Discretisation(pair=pair),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
                          DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
                          DisplacementBC("bottom", 2)],
        pressure_bcs=[PressureBC("ground_surface")],
        loads=[SurfaceLoad("ground_surface", q)],
        options=SolverOptions(preset=preset, prefix=f"terz_{pair}_"),
        self_weight=False,
    )
    t_end = times[-1]
    dt0 = 1e-4 * t_end
    grow = 10.0 ** (1.0 / spd)
    ts = TimeStepping(dt0=dt0, dt_min=1e-12, dt_max=dT_max * t_end, grow=grow, hold=1,
                      milestones=tuple(times[:-1]))
    zq = np.linspace(-H, 0.0, 201)
    rows: list[dict[str, float]] = []

    def record(pb: Any, t: float, stage: str) -> None:
        for T, tm in zip(Ts, times, strict=True):
            if abs(t - tm) <= 1e-9 * tm:
                ph = _p_along(pb, zq, 0.5, 0.5)
                pe = terzaghi_series(-zq, H, T, p0)
                e_p = float(np.sqrt(np.trapezoid((ph - pe) ** 2, zq) / np.trapezoid(pe**2, zq)))
                uz = _eval_points(pb.u, np.array([[0.5, 0.5, 0.0]]))
                s_h = -float(np.atleast_1d(uz)[2])
                s_e = (q * H - H * p0 * (1.0 - terzaghi_degree(T))) / m_oed
                rows.append({"T_v": T, "t_day": t, "err_p": e_p, "settlement_m": s_h,
                             "settlement_ref_m": s_e, "err_s": abs(s_h - s_e) / s_e})

    log = run_stages(problem, [Stage("load", "load", 0.0, 1.0),
                               Stage("consolidation", "consolidation", t_end)], ts,
                     on_milestone=record)
    err = max(max(r["err_p"], r["err_s"]) for r in rows) if len(rows) == len(Ts) else math.inf
    tol = 0.01
    return CaseResult(
        "terzaghi", err, tol, bool(err <= tol), time.perf_counter() - t0, problem.num_dofs,
        log.newton_total, len(log.steps),
        reference="Terzaghi (1925) series; Verruijt (2016) ch. 2",
        details={"pair": pair, "nz": nz, "steps_per_decade": spd, "dT_max": dT_max,
                 "rows": rows,
                 "c_v_m2_per_day": cv, "p0_kPa": p0, "ranks": comm.size,
                 "timings": problem.timings})


# ---------------------------------------------------------------------------- Mandel
def mandel(size: str = "fast", pair: str = "Q2Q1", n: int | None = None,
           steps_per_decade: int | None = None, dT_max: float | None = None,
           preset: str = "direct", comm: Any = None) -> CaseResult:
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
    at the centre, ``p0 = F B (1 + nu_u) / (3 a)``. Tolerance 2 % (issue 5). The details also
    report the peak ``max p(0,t)/p0`` of both (Mandel–Cryer: > 1).
    """
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.geometry.box import build_box
    from pilegroup.solver import (
        GAMMA_W,
        BiotProblem,
        Discretisation,
        DisplacementBC,
        PressureBC,
        RigidPlate,
        SoilMaterial,
        SolverOptions,
        Stage,
        TimeStepping,
        run_stages,
    )

    comm = comm or _comm()
    t0 = time.perf_counter()
    a = b = 1.0
    thick = 0.1
    E, nu, k, por, F = 1.0e4, 0.25, 1.0e-3, 0.3, 100.0
    n = n or {"fast": 8, "bench": 16}[size]
    spd = steps_per_decade or {"fast": 8, "bench": 16}[size]
    dT_max = dT_max or {"fast": 0.02, "bench": 0.01}[size]
    md = build_box(comm, (0.0, a), (0.0, thick), np.linspace(0.0, b, n + 1), n, 1)
    mat = SoilMaterial(LinearElastic(E, nu), k_m_per_day=k, porosity=por)
    K = E / (3 * (1 - 2 * nu))
    G = E / (2 * (1 + nu))
    Mb = 1.0 / mat.storage
    Ku = K + Mb
    B = Mb / Ku
    nu_u = (3 * Ku - 2 * G) / (2 * (3 * Ku + G))
    kappa = k / GAMMA_W
    c = 2 * kappa * B**2 * G * (1 - nu) * (1 + nu_u) ** 2 / (9 * (1 - nu_u) * (nu_u - nu))
    p0 = F * B * (1 + nu_u) / (3 * a)
    Tstar = [0.001, 0.003, 0.01, 0.03, 0.05, 0.1, 0.2, 0.3, 0.5, 0.7, 1.0]
    times = [T * a**2 / c for T in Tstar]
    problem = BiotProblem(
        md, {"soil_layer_01": mat}, Discretisation(pair=pair),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("bottom", 2),
                          DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1)],
        pressure_bcs=[PressureBC("side_xmax")],
        plates=[RigidPlate("ground_surface", 2, -F * thick)],
        options=SolverOptions(preset=preset, prefix=f"mandel_{pair}_"),
        self_weight=False,
    )
    t_end = times[-1]
    ts = TimeStepping(dt0=1e-5 * t_end, dt_min=1e-14, dt_max=dT_max * t_end,
                      grow=10.0 ** (1.0 / spd), milestones=tuple(times[:-1]))
    centre = np.array([[0.0, 0.5 * thick, 0.5 * b]])
    rows: list[dict[str, float]] = []

    def record(pb: Any, t: float, stage: str) -> None:
        ph = float(np.atleast_1d(_eval_points(pb.p, centre))[0])
        if stage == "load":
            rows.append({"t_star": 0.0, "t_day": 0.0, "p_h": ph, "p_ref": p0,
                         "err": abs(ph - p0) / p0})
            return
        for T, tm in zip(Tstar, times, strict=True):
            if abs(t - tm) <= 1e-9 * tm:
                pe = float(mandel_centre_pressure(np.array([tm]), F, a, B, nu, nu_u, c)[0])
                rows.append({"t_star": T, "t_day": t, "p_h": ph, "p_ref": pe,
                             "err": abs(ph - pe) / p0})

    log = run_stages(problem, [Stage("load", "load", 0.0, 1.0),
                               Stage("consolidation", "consolidation", t_end)], ts,
                     on_milestone=record)
    ok_rows = len(rows) == len(Tstar) + 1
    err = max(r["err"] for r in rows) if ok_rows else math.inf
    peak_h = max(r["p_h"] for r in rows) / p0
    peak_e = max(r["p_ref"] for r in rows) / p0
    tol = 0.02
    passed = bool(err <= tol and peak_h > 1.0)
    return CaseResult(
        "mandel", err, tol, passed, time.perf_counter() - t0, problem.num_dofs,
        log.newton_total, len(log.steps),
        reference="Abousleiman et al. (1996) Geotechnique 46(2) Eq. 21; Cheng & Detournay (1988)",
        details={"pair": pair, "n": n, "steps_per_decade": spd, "dT_max": dT_max, "rows": rows,
                 "peak_ratio_fe": peak_h, "peak_ratio_ref": peak_e, "B": B, "nu_u": nu_u,
                 "c_m2_per_day": c, "p0_kPa": p0, "ranks": comm.size,
                 "timings": problem.timings})


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
                           T_first: float = 0.0, comm: Any = None) -> dict[str, Any]:
    """Pressure profile of the Terzaghi column after the first step; its oscillation measure.

    ``T_first = 0`` is the undrained loading step (``dt = 0``); a small positive ``T_first``
    adds one drained step of that time factor. Uniform mesh of ``nz`` cells, same data as
    :func:`terzaghi`. Returns ``{"measure", "profile", "z", "p0"}``.
    """
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.geometry.box import build_box
    from pilegroup.solver import (
        GAMMA_W,
        BiotProblem,
        Discretisation,
        DisplacementBC,
        PressureBC,
        SoilMaterial,
        SurfaceLoad,
    )

    comm = comm or _comm()
    H, E, nu, k, n, q = 10.0, 1.0e4, 0.3, 1.0e-3, 0.4, 100.0
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), np.linspace(-H, 0.0, nz + 1), 1, 1)
    mat = SoilMaterial(LinearElastic(E, nu), k_m_per_day=k, porosity=n)
    m_oed = E * (1 - nu) / ((1 + nu) * (1 - 2 * nu))
    p0 = q / (1.0 + m_oed * mat.storage)
    cv = (k / GAMMA_W) / (mat.storage + 1.0 / m_oed)
    pb = BiotProblem(
        md, {"soil_layer_01": mat}, Discretisation(pair=pair, stabilise=stabilise),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
                          DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
                          DisplacementBC("bottom", 2)],
        pressure_bcs=[PressureBC("ground_surface")],
        loads=[SurfaceLoad("ground_surface", q)], self_weight=False)
    info = pb.solve_step(0.0, 1.0)
    assert info.converged, info.message
    pb.commit()
    if T_first > 0:
        info = pb.solve_step(T_first * H**2 / cv, 1.0)
        assert info.converged, info.message
        pb.commit()
    z = np.linspace(0.0, -H, 4 * nz + 1)  # by increasing depth (vertices and mid-points)
    prof = _p_along(pb, z, 0.0, 0.0)
    return {"measure": oscillation_measure(prof, p0), "profile": prof, "z": z, "p0": p0}


def _with_footing(md0: Any, width: float) -> Any:
    """Copy of a box MeshData with the top facets at ``x <= width`` re-tagged ``footing``."""
    from dolfinx import mesh as dmesh

    from pilegroup.geometry.meshdata import MeshData

    msh = md0.mesh
    fdim = msh.topology.dim - 1
    z_top = md0.info["z_top"]
    foot = dmesh.locate_entities_boundary(
        msh, fdim, lambda x: np.isclose(x[2], z_top) & (x[0] <= width + 1e-9))
    idx = np.concatenate([md0.facet_tags.indices, foot])
    val = np.concatenate([md0.facet_tags.values, np.full(foot.size, 7, dtype=np.int32)])
    keep = np.ones(idx.size, dtype=bool)
    keep[: md0.facet_tags.indices.size] = ~np.isin(md0.facet_tags.indices, foot)
    order = np.argsort(idx[keep], kind="stable")
    ft = dmesh.meshtags(msh, fdim, idx[keep][order], val[keep][order])
    return MeshData(msh, md0.cell_tags, ft, md0.cell_names, {**md0.facet_names, "footing": 7},
                    md0.info)


def strip_footing(pair: str = "Q2Q1", n: int = 10, comm: Any = None) -> dict[str, Any]:
    """Smooth rigid strip footing on Tresca soil (drained, weightless): a locking check.

    Plane-strain slab (one cell thick), half domain ``[0, 5] x [-5, 0] m`` by symmetry,
    footing half-width 1 m pushed down 5 cm; Mohr–Coulomb with phi = psi = 0, c = 10 kPa
    (isochoric plastic flow). Prandtl's limit pressure is ``(2 + pi) c`` (Prandtl 1920).
    Trilinear hexahedra with full integration lock under isochoric flow (no plateau); Q2 does
    not. Returns the footing pressure over c at 10 displacement levels. Not a pass/fail case:
    the coarse meshes overestimate the limit (the footing edge is singular).
    """
    from pilegroup.constitutive.soil import MohrCoulomb
    from pilegroup.geometry.box import build_box
    from pilegroup.solver import (
        BiotProblem,
        Discretisation,
        DisplacementBC,
        PressureBC,
        SoilMaterial,
        Stage,
        TimeStepping,
        run_stages,
    )

    comm = comm or _comm()
    t0 = time.perf_counter()
    L, thick, b, c = 5.0, 0.25, 1.0, 10.0
    md = _with_footing(build_box(comm, (0.0, L), (0.0, thick), np.linspace(-L, 0.0, n + 1),
                                 n, 1), b)
    mat = SoilMaterial(MohrCoulomb(E=1e4, nu=0.3, c=c, phi_deg=0.0, psi_deg=0.0), 1e-3, 0.4)
    pb = BiotProblem(
        md, {"soil_layer_01": mat}, Discretisation(pair=pair),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
                          DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
                          DisplacementBC("bottom", 2), DisplacementBC("footing", 2, value=-0.05)],
        pressure_bcs=[PressureBC(None)], self_weight=False)
    qc: list[float] = []
    ts = TimeStepping(dt0=0.05, dt_max=0.05, dt_min=1e-5,
                      milestones=tuple(np.round(np.arange(0.1, 1.0, 0.1), 12)))
    log = run_stages(pb, [Stage("push", "load", 1.0, 1.0)], ts,
                     on_milestone=lambda p, t, s: qc.append(-p.reaction("footing", 2)
                                                            / (thick * b * c)))
    return {"pair": pair, "n": n, "dofs": pb.num_dofs, "q_over_c": qc,
            "prandtl": 2 + math.pi, "newton": log.newton_total, "rejected": log.rejected,
            "wall_s": time.perf_counter() - t0}


def footing_undrained_roughness(pair: str = "Q2Q1", stabilise: bool = True, n: int = 12,
                                comm: Any = None) -> dict[str, Any]:
    """Checkerboard measure of the undrained pressure under a strip load (inf-sup check).

    Plane-strain slab ``[0, 4] x [-4, 0] m`` (one cell thick), rollers on sides and bottom,
    100 kPa on ``x < 1`` of the top, one undrained step. Nearly incompressible undrained
    response (water compressibility only), where an unstable pair shows a checkerboard.
    The measure is ``max |p_ij - mean of its 4 neighbours| / max |p|`` over interior vertices
    of the x–z grid: O(h^2) for a smooth field, O(1) for a checkerboard.
    """
    from pilegroup.constitutive.soil import LinearElastic
    from pilegroup.geometry.box import build_box
    from pilegroup.solver import (
        BiotProblem,
        Discretisation,
        DisplacementBC,
        SoilMaterial,
        SurfaceLoad,
    )

    comm = comm or _comm()
    L, thick = 4.0, 0.25
    md0 = build_box(comm, (0.0, L), (0.0, thick), np.linspace(-L, 0.0, n + 1), n, 1)
    md = _with_footing(md0, 0.25 * L)
    mat = SoilMaterial(LinearElastic(1.0e4, 0.3), k_m_per_day=1e-3, porosity=0.4)
    pb = BiotProblem(
        md, {"soil_layer_01": mat}, Discretisation(pair=pair, stabilise=stabilise),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_xmax", 0),
                          DisplacementBC("side_ymin", 1), DisplacementBC("side_ymax", 1),
                          DisplacementBC("bottom", 2), DisplacementBC("bottom", 0)],
        loads=[SurfaceLoad("footing", 100.0)], self_weight=False)
    info = pb.solve_step(0.0, 1.0)
    assert info.converged, info.message
    xs = np.linspace(0.0, L, n + 1)
    zs = np.linspace(-L, 0.0, n + 1)
    X, Z = np.meshgrid(xs, zs, indexing="ij")
    pts = np.column_stack([X.ravel(), np.zeros(X.size), Z.ravel()])
    P = _eval_points(pb.p, pts).reshape(n + 1, n + 1)
    r = P[1:-1, 1:-1] - 0.25 * (P[:-2, 1:-1] + P[2:, 1:-1] + P[1:-1, :-2] + P[1:-1, 2:])
    return {"measure": float(np.abs(r).max() / np.abs(P).max()), "p": P}


# ---------------------------------------------------------------------------- triaxial
def triaxial(size: str = "fast", pair: str = "Q2Q1", n: int | None = None,
             preset: str = "direct", xi: float = 0.02, law: str = "mc",
             comm: Any = None) -> CaseResult:
    """Drained triaxial compression of a Mohr–Coulomb block to failure.

    Block 1 x 1 x 1 m, rollers on ``x = 0``, ``y = 0``, ``z = 0``; initial effective stress
    ``(-sigma_c, -(1 + xi) sigma_c, -sigma_c)`` with ``sigma_c = 100 kPa``, held by the confining
    pressures on ``x = 1`` and ``y = 1``; the top is pushed down by 2 cm (displacement control)
    in ramped steps; the pore pressure is fixed to 0 everywhere (drained). Soil: Mohr–Coulomb
    (``law="mc"``) or Drucker–Prager matched on the compression meridian (``law="dp"``),
    E = 20 MPa, nu = 0.3, c = 10 kPa, phi = 30 deg, psi = 0.

    ``xi = 0.02`` puts the intermediate stress slightly above the minor one, so failure is on a
    face of the Mohr–Coulomb pyramid. With ``xi = 0`` (conventional triaxial) failure is on the
    edge ``sigma_2 = sigma_3``, where the perfectly plastic tangent leaves the split of the
    lateral plastic strain between x and y undetermined: the Jacobian is singular and Newton
    does not converge (measured; the Drucker–Prager cone has no edge and converges with
    ``xi = 0``). Mohr–Coulomb ignores the intermediate stress, so the failure load is the same.

    Reference (closed form): at failure the axial stress is
    ``sigma_1 = sigma_3 N + 2 c sqrt(N)``, ``N = (1 + sin phi)/(1 - sin phi)`` (compression
    positive, ``sigma_3 = sigma_c``), so the top reaction is ``-sigma_1 A`` (e.g. Wood, *Soil
    Behaviour and Critical State Soil Mechanics*, 1990, ch. 4). Error: relative difference of
    the reaction at the last step; tolerance 1e-6 (issue 5). The details give the reaction
    history (plateau).

    Known limit: past the limit load a perfectly plastic body admits non-homogeneous
    zero-stiffness modes; with 4 x 4 x 4 Q2 cells Newton stalls (residual cycling ~1e-6, line
    search does not cure it) at 1.6 % axial strain, measured. Q2 with 2 and 3 cells per side
    and Q1 with 4 converge to 2 %; the bench size uses 3.
    """
    from pilegroup.constitutive.soil import DruckerPrager, MohrCoulomb
    from pilegroup.geometry.box import build_box
    from pilegroup.solver import (
        BiotProblem,
        Discretisation,
        DisplacementBC,
        PressureBC,
        SoilMaterial,
        SolverOptions,
        Stage,
        SurfaceLoad,
        TimeStepping,
        run_stages,
    )

    comm = comm or _comm()
    t0 = time.perf_counter()
    n = n or {"fast": 2, "bench": 3}[size]
    sc, c, phi = 100.0, 10.0, 30.0
    if law == "mc":
        soil = MohrCoulomb(E=2.0e4, nu=0.3, c=c, phi_deg=phi, psi_deg=0.0)
    else:
        soil = DruckerPrager(E=2.0e4, nu=0.3, c=c, phi_deg=phi, psi_deg=0.0)
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), np.linspace(0.0, 1.0, n + 1), n, n)
    mat = SoilMaterial(soil, k_m_per_day=1e-3, porosity=0.4)
    pb = BiotProblem(
        md, {"soil_layer_01": mat}, Discretisation(pair=pair),
        displacement_bcs=[DisplacementBC("side_xmin", 0), DisplacementBC("side_ymin", 1),
                          DisplacementBC("bottom", 2),
                          DisplacementBC("ground_surface", 2, value=-0.02)],
        pressure_bcs=[PressureBC(None)],
        loads=[SurfaceLoad("side_xmax", sc, ramp=False),
               SurfaceLoad("side_ymax", sc * (1 + xi), ramp=False)],
        options=SolverOptions(preset=preset, prefix=f"triax_{pair}_"),
        self_weight=False,
    )
    s0 = np.array([-sc, -sc * (1 + xi), -sc, 0.0, 0.0, 0.0])
    pb.set_initial_stress({"soil_layer_01": s0})
    hist: list[dict[str, float]] = []

    def record(p: Any, t: float, stage: str) -> None:
        hist.append({"t": t, "axial_strain": 0.02 * t, "reaction_kN": p.reaction(
            "ground_surface", 2)})

    ts = TimeStepping(dt0=0.05, dt_min=1e-6, dt_max=0.1, grow=1.5,
                      milestones=tuple(np.round(np.arange(0.1, 1.0, 0.1), 12)))
    log = run_stages(pb, [Stage("shear", "load", 1.0, 1.0)], ts, on_milestone=record)
    N = (1 + math.sin(math.radians(phi))) / (1 - math.sin(math.radians(phi)))
    s1 = sc * N + 2 * c * math.sqrt(N)
    R = hist[-1]["reaction_kN"]
    err = abs(R + s1) / s1
    tol = 1e-6
    return CaseResult(
        "triaxial", err, tol, bool(err <= tol), time.perf_counter() - t0, pb.num_dofs,
        log.newton_total, len(log.steps),
        reference="Mohr-Coulomb failure stress sigma_1 = sigma_3 N + 2 c sqrt(N)",
        details={"pair": pair, "n": n, "failure_load_ref_kN": -s1, "reaction_kN": R,
                 "rows": hist, "rejected": log.rejected, "ranks": comm.size,
                 "newton_per_step": [s.newton_its for s in log.steps],
                 "timings": pb.timings})


# ---------------------------------------------------------------------------- benchmark
BENCH_LEVELS: dict[str, dict[str, Any]] = {
    "terzaghi": {"mesh": [8, 16, 32], "time": [(8, 4e-3), (16, 2e-3), (32, 1e-3)]},
    "mandel": {"mesh": [4, 8, 16], "time": [(4, 0.04), (8, 0.02), (16, 0.01)]},
}


def bench_verification(out_dir: str = "out/bench_verification",
                       cases: Sequence[str] = ("terzaghi", "mandel"),
                       pairs: Sequence[str] = ("Q2Q1", "Q1Q1"),
                       levels: dict[str, dict[str, Any]] | None = None) -> list[dict[str, Any]]:
    """Error against wall time: each case x element pair x 3 meshes x 3 step counts.

    Writes ``bench_verification.json``, ``bench_verification.png`` (error vs wall time, log-log)
    and ``bench_verification.md`` (the table for docs/benchmarks.md, section "Verification: error
    vs wall time") to ``out_dir`` (rank 0), and returns the rows. Wall times are the cases' own
    (mesh, forms, all steps), measured on ``MPI.COMM_WORLD``.
    """
    from pathlib import Path

    comm = _comm()
    levels = levels or BENCH_LEVELS
    rows: list[dict[str, Any]] = []
    for case in cases:
        for pair in pairs:
            for nmesh in levels[case]["mesh"]:
                for spd, dtm in levels[case]["time"]:
                    if case == "terzaghi":
                        r = terzaghi(pair=pair, nz=nmesh, steps_per_decade=spd, dT_max=dtm)
                    else:
                        r = mandel(pair=pair, n=nmesh, steps_per_decade=spd, dT_max=dtm)
                    row = {"case": case, "pair": pair, "mesh": nmesh, "steps": r.steps,
                           "dofs": r.dofs, "newton": r.newton_its, "error": r.error,
                           "tolerance": r.tolerance, "passed": r.passed, "wall_s": r.wall_s,
                           "ranks": comm.size}
                    rows.append(row)
                    if comm.rank == 0:
                        print(f"{case:<9} {pair} mesh {nmesh:>3} steps {r.steps:>5} "
                              f"dofs {r.dofs:>6} error {r.error:.3e} wall {r.wall_s:7.2f} s",
                              flush=True)
    if comm.rank == 0:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        (out / "bench_verification.json").write_text(_json.dumps(rows, indent=1))
        (out / "bench_verification.md").write_text(bench_markdown(rows))
        _bench_plot(rows, out / "bench_verification.png")
    comm.barrier()
    return rows


def bench_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown table of benchmark rows (one line per run)."""
    lines = ["| case | pair | mesh | steps | DOFs | Newton | error | tol | wall (s) |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['pair']} | {r['mesh']} | {r['steps']} | {r['dofs']} "
                     f"| {r['newton']} | {r['error']:.2e} | {r['tolerance']:.0e} "
                     f"| {r['wall_s']:.2f} |")
    return "\n".join(lines) + "\n"


def _bench_plot(rows: Sequence[dict[str, Any]], path: Any) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cases = sorted({r["case"] for r in rows})
    fig, axes = plt.subplots(1, len(cases), figsize=(5.5 * len(cases), 4.2), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        for pair, mk in (("Q2Q1", "o"), ("Q1Q1", "s")):
            for mesh in sorted({r["mesh"] for r in rows if r["case"] == case}):
                sel = [r for r in rows if r["case"] == case and r["pair"] == pair
                       and r["mesh"] == mesh]
                if sel:
                    ax.loglog([r["wall_s"] for r in sel], [r["error"] for r in sel],
                              marker=mk, ls="-" if pair == "Q2Q1" else "--",
                              label=f"{pair} mesh {mesh}")
        tol = next(r["tolerance"] for r in rows if r["case"] == case)
        ax.axhline(tol, color="k", lw=0.8, ls=":")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("relative error")
        ax.set_title(f"{case}: error vs wall time (lines: step counts)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


CASES: dict[str, Callable[..., CaseResult]] = {
    "terzaghi": terzaghi,
    "mandel": mandel,
    "triaxial": triaxial,
}

# interface cases (shaft-capacity, interface-patch, tied-limit): studies/verification_interface.py
from pilegroup.studies.verification_interface import INTERFACE_CASES  # noqa: E402

CASES.update(INTERFACE_CASES)


def run_cases(names: Sequence[str] | None = None, size: str = "fast",
              json: bool = False, out: Any = None, pair: str | None = None,
              preset: str | None = None, quadrature: str | None = None) -> list[CaseResult]:
    """Run the named cases (all when empty); print one line each, or one JSON object each.

    ``pair`` (``"Q2Q1"``/``"Q1Q1"``) and ``preset`` (``"direct"``/``"fieldsplit_gamg"``)
    override the cases' defaults; ``quadrature`` (``"nodal"``/``"gauss"``) the interface
    quadrature of the interface cases. Only rank 0 prints. Returns the results (on every rank).
    """
    comm = _comm()
    out = out or sys.stdout
    names = list(names or CASES)
    unknown = [n for n in names if n not in CASES]
    if unknown:
        raise KeyError(f"unknown verification case(s) {unknown}; known: {sorted(CASES)}")
    results = []
    for name in names:
        kw: dict[str, Any] = {"size": size}
        if pair is not None:
            kw["pair"] = pair
        if preset is not None:
            kw["preset"] = preset
        if quadrature is not None and name in INTERFACE_CASES:
            kw["quadrature"] = quadrature
        res = CASES[name](**kw)
        results.append(res)
        if comm.rank == 0:
            if json:
                print(_json.dumps(asdict(res), default=json_default), file=out, flush=True)
            else:
                print(res.line(), file=out, flush=True)
    return results


def main(argv: Sequence[str] | None = None) -> int:
    """Command line: ``python -m pilegroup.studies.verification [CASE ...] [--json]``."""
    ap = argparse.ArgumentParser(description=__doc__)
    ap.add_argument("cases", nargs="*")
    ap.add_argument("--size", default="fast", choices=["fast", "bench"])
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--pair", choices=["Q2Q1", "Q1Q1"], default=None)
    ap.add_argument("--preset", choices=["direct", "fieldsplit_gamg"], default=None)
    ap.add_argument("--interface-quadrature", choices=["nodal", "gauss"], default=None)
    a = ap.parse_args(argv)
    res = run_cases(a.cases, size=a.size, json=a.json, pair=a.pair, preset=a.preset,
                    quadrature=a.interface_quadrature)
    return 0 if all(r.passed for r in res) else 1


if __name__ == "__main__":
    sys.exit(main())
