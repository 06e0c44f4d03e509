"""Soil cases: drained triaxial failure of a block, and the strip-footing checks.

``triaxial`` is a registered case (the Mohr–Coulomb failure load against its closed form).
:func:`strip_footing` (locking under isochoric plastic flow) and
:func:`footing_undrained_roughness` (checkerboard of the undrained pressure) are measurements
for the tests and docs/benchmarks.md, not pass/fail cases.
"""

from __future__ import annotations

import math
import time
from typing import Any

import numpy as np
from dolfinx import mesh as dmesh
from mpi4py import MPI

from pilegroup.constitutive.soil import DruckerPrager, MohrCoulomb
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver import (
    BiotProblem,
    Discretisation,
    DisplacementBC,
    SoilMaterial,
    SolverOptions,
    SolverStage,
    StepControl,
    SurfaceLoad,
    run_stages,
)
from pilegroup.studies.verification.common import (
    DRAINED,
    TENTHS,
    ElasticSoil,
    box_bcs,
    eval_points,
    soil_problem,
    world,
)
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["footing_undrained_roughness", "strip_footing", "triaxial"]


# ---------------------------------------------------------------------------- triaxial
def _triaxial_problem(comm: MPI.Comm, n: int, pair: str, preset: str, xi: float, law: str,
                      sc: float, c: float, phi: float) -> BiotProblem:
    """The block with its confining loads and initial stress (see :func:`triaxial`)."""
    if law == "mc":
        soil = MohrCoulomb(E=2.0e4, nu=0.3, c=c, phi_deg=phi, psi_deg=0.0)
    else:
        soil = DruckerPrager(E=2.0e4, nu=0.3, c=c, phi_deg=phi, psi_deg=0.0)
    md = build_box(comm, (0.0, 1.0), (0.0, 1.0), np.linspace(0.0, 1.0, n + 1), n, n)
    pb = soil_problem(
        md, SoilMaterial(soil, k_m_per_day=1e-3, porosity=0.4), Discretisation(pair=pair),
        [DisplacementBC(groups.SIDE_XMIN, 0), DisplacementBC(groups.SIDE_YMIN, 1),
         DisplacementBC(groups.BOTTOM, 2), DisplacementBC(groups.GROUND, 2, value=-0.02)],
        pressure_bcs=DRAINED,
        loads=[SurfaceLoad(groups.SIDE_XMAX, sc, ramp=False),
               SurfaceLoad(groups.SIDE_YMAX, sc * (1 + xi), ramp=False)],
        options=SolverOptions(preset=preset, prefix=f"triax_{pair}_"))
    stress0 = np.array([-sc, -sc * (1 + xi), -sc, 0.0, 0.0, 0.0])
    pb.set_initial_stress({groups.soil_layer(1): stress0})
    return pb


@register("triaxial")
def triaxial(size: str = "fast", pair: str = "Q2Q1", n: int | None = None,
             preset: str = "direct", xi: float = 0.02, law: str = "mc",
             comm: MPI.Comm | None = None) -> CaseResult:
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
    the reaction at the last step; tolerance 1e-6. The details give the reaction
    history (plateau).

    Known limit: past the limit load a perfectly plastic body admits non-homogeneous
    zero-stiffness modes; with 4 x 4 x 4 Q2 cells Newton stalls (residual cycling ~1e-6, line
    search does not cure it) at 1.6 % axial strain, measured. Q2 with 2 and 3 cells per side
    and Q1 with 4 converge to 2 %; the bench size uses 3.
    """
    comm = comm or world()
    t0 = time.perf_counter()
    n = n or {"fast": 2, "bench": 3}[size]
    sc, c, phi = 100.0, 10.0, 30.0
    pb = _triaxial_problem(comm, n, pair, preset, xi, law, sc, c, phi)
    hist: list[dict[str, float]] = []

    def record(p: BiotProblem, t: float, stage: str) -> None:
        hist.append({"t": t, "axial_strain": 0.02 * t, "reaction_kN": p.reaction(
            groups.GROUND, 2)})

    ts = StepControl(dt0=0.05, dt_min=1e-6, dt_max=0.1, grow=1.5, milestones=TENTHS)
    log = run_stages(pb, [SolverStage("shear", "load", 1.0, 1.0)], ts, on_milestone=record)
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


# ---------------------------------------------------------------------------- strip footing
def _with_footing(md0: MeshData, width: float) -> MeshData:
    """Copy of a box MeshData with the top facets at ``x <= width`` re-tagged ``footing``."""
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


def _footing_slab(comm: MPI.Comm, L: float, thick: float, n: int, width: float) -> MeshData:
    """Plane-strain slab ``[0, L] x [-L, 0] m``, one cell thick, footing on ``x <= width``."""
    return _with_footing(build_box(comm, (0.0, L), (0.0, thick), np.linspace(-L, 0.0, n + 1),
                                   n, 1), width)


def strip_footing(pair: str = "Q2Q1", n: int = 10, comm: MPI.Comm | None = None
                  ) -> dict[str, Any]:
    """Smooth rigid strip footing on Tresca soil (drained, weightless): a locking check.

    Plane-strain slab (one cell thick), half domain ``[0, 5] x [-5, 0] m`` by symmetry,
    footing half-width 1 m pushed down 5 cm; Mohr–Coulomb with phi = psi = 0, c = 10 kPa
    (isochoric plastic flow). Prandtl's limit pressure is ``(2 + pi) c`` (Prandtl 1920).
    Trilinear hexahedra with full integration lock under isochoric flow (no plateau); Q2 does
    not. Returns the footing pressure over c at 10 displacement levels. Not a pass/fail case:
    the coarse meshes overestimate the limit (the footing edge is singular).
    """
    comm = comm or world()
    t0 = time.perf_counter()
    L, thick, b, c = 5.0, 0.25, 1.0, 10.0
    md = _footing_slab(comm, L, thick, n, b)
    mat = SoilMaterial(MohrCoulomb(E=1e4, nu=0.3, c=c, phi_deg=0.0, psi_deg=0.0), 1e-3, 0.4)
    pb = soil_problem(md, mat, Discretisation(pair=pair),
                      box_bcs((2,), DisplacementBC("footing", 2, value=-0.05)),
                      pressure_bcs=DRAINED)
    qc: list[float] = []
    ts = StepControl(dt0=0.05, dt_max=0.05, dt_min=1e-5, milestones=TENTHS)
    log = run_stages(pb, [SolverStage("push", "load", 1.0, 1.0)], ts,
                     on_milestone=lambda p, t, s: qc.append(-p.reaction("footing", 2)
                                                            / (thick * b * c)))
    return {"pair": pair, "n": n, "dofs": pb.num_dofs, "q_over_c": qc,
            "prandtl": 2 + math.pi, "newton": log.newton_total, "rejected": log.rejected,
            "wall_s": time.perf_counter() - t0}


def footing_undrained_roughness(pair: str = "Q2Q1", stabilise: bool = True, n: int = 12,
                                comm: MPI.Comm | None = None) -> dict[str, Any]:
    """Checkerboard measure of the undrained pressure under a strip load (inf-sup check).

    Plane-strain slab ``[0, 4] x [-4, 0] m`` (one cell thick), rollers on sides and bottom,
    100 kPa on ``x < 1`` of the top, one undrained step. Nearly incompressible undrained
    response (water compressibility only), where an unstable pair shows a checkerboard.
    The measure is ``max |p_ij - mean of its 4 neighbours| / max |p|`` over interior vertices
    of the x–z grid: O(h^2) for a smooth field, O(1) for a checkerboard.
    """
    comm = comm or world()
    L, thick = 4.0, 0.25
    md = _footing_slab(comm, L, thick, n, 0.25 * L)
    pb = soil_problem(md, ElasticSoil().material(), Discretisation(pair=pair, stabilise=stabilise),
                      box_bcs((2, 0)), loads=[SurfaceLoad("footing", 100.0)])
    info = pb.solve_step(0.0, 1.0)
    assert info.converged, info.message
    xs = np.linspace(0.0, L, n + 1)
    zs = np.linspace(-L, 0.0, n + 1)
    X, Z = np.meshgrid(xs, zs, indexing="ij")
    pts = np.column_stack([X.ravel(), np.zeros(X.size), Z.ravel()])
    P = eval_points(pb.p, pts).reshape(n + 1, n + 1)
    r = P[1:-1, 1:-1] - 0.25 * (P[:-2, 1:-1] + P[2:, 1:-1] + P[1:-1, :-2] + P[1:-1, 2:])
    return {"measure": float(np.abs(r).max() / np.abs(P).max()), "p": P}
