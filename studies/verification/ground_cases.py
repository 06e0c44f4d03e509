"""Ground that moves: consolidation under a surcharge and of consolidating layers, in 3D.

Each case meshes a soil block with :func:`pilegroup.geometry.box.build_box`, starts from the
geostatic state (the soil's own weight), moves the ground with the solver's ground actions
(:class:`~pilegroup.solver.SurfaceLoad` with ``action``, a ground stage) or with a layer's
initial excess pore pressure, and compares the ground settlement with a closed form.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

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
from pilegroup.solver.probes import eval_points
from pilegroup.studies.verification.common import box_bcs, world
from pilegroup.studies.verification.consolidation import TerzaghiColumn
from pilegroup.studies.verification.registry import CaseResult, register

__all__ = ["SURCHARGE_T_V", "SurchargeBlock", "consolidation_surcharge"]

#: Time factors ``T_v = c_v t / H^2`` at which the ground settlement is compared.
SURCHARGE_T_V = (0.02, 0.05, 0.1, 0.2, 0.5, 1.0)


@dataclass(frozen=True)
class SurchargeBlock(TerzaghiColumn):
    """Terzaghi's column as a ``B`` x ``B`` x ``H`` m block with its weight ``gamma_sat``.

    The wide surcharge ``q`` (kPa) on the drained top; sides on rollers, bottom fixed and
    impermeable. The weight (kN/m^3) makes the run start from the geostatic state; the
    consolidation under ``q`` is the column's (:class:`TerzaghiColumn`).
    """

    B: float = 20.0
    q: float = 50.0
    gamma_sat: float = 18.0

    def material(self) -> SoilMaterial:
        """The soil with its weight."""
        base = self.soil.material()
        return SoilMaterial(base.law, base.k_m_per_day, base.porosity, self.gamma_sat)


@register("consolidation-surcharge")
def consolidation_surcharge(size: str = "fast", pair: str = "Q2Q1", preset: str = "direct",
                            comm: MPI.Comm | None = None) -> CaseResult:
    """A wide surcharge on a 3D block without piles against Terzaghi's 1D consolidation.

    Block 20 x 20 x 10 m (4 x 4 cells in plan), E = 10 MPa, nu = 0.3, k = 1e-3 m/day, n = 0.4,
    gamma_sat = 18 kN/m^3: geostatic stage, then 50 kPa placed at once on the whole ground
    surface as a ground action (one undrained step), then consolidation. Reference: Terzaghi's
    series with water compressibility, settlement ``s = (q H - H p0 (1 - U(T_v))) / m``
    (Terzaghi 1925; Verruijt, *Theory and Problems of Poroelasticity*, 2016, ch. 2), measured
    at the centre of the ground surface from the end of the geostatic stage.

    Error: the largest relative settlement error over ``T_v`` in :data:`SURCHARGE_T_V`.
    Tolerance 2 %.
    """
    comm = comm or world()
    t0 = time.perf_counter()
    nz = {"fast": 16, "bench": 32}[size]
    blk = SurchargeBlock()
    half = blk.B / 2
    md = build_box(comm, (-half, half), (-half, half), graded_levels(-blk.H, 0.0, nz, ratio=4.0),
                   4, 4)
    pb = BiotProblem(md, {groups.soil_layer(1): blk.material()}, Discretisation(pair=pair),
                     displacement_bcs=box_bcs((0, 1, 2)), pressure_bcs=[PressureBC(groups.GROUND)],
                     loads=[SurfaceLoad(groups.GROUND, blk.q, action=0)],
                     options=SolverOptions(preset=preset, prefix=f"surch_{pair}_"))
    times = [T * blk.H**2 / blk.cv for T in SURCHARGE_T_V]
    spd, dT_max = {"fast": (16, 5e-3), "bench": (32, 1e-3)}[size]
    ts = StepControl(dt0=1e-4 * times[-1], dt_min=1e-12, dt_max=dT_max * times[-1],
                     grow=10.0 ** (1.0 / spd), hold=1, milestones=tuple(times[:-1]))
    stages = [SolverStage("geostatic", "geostatic"),
              SolverStage("fill", "ground", 0.0, ground=(1.0,)),
              SolverStage("consolidation", "consolidation", times[-1])]
    rows: list[dict[str, float]] = []

    def record(problem: BiotProblem, t: float, stage: str) -> None:
        for T, tm in zip(SURCHARGE_T_V, times, strict=True):
            if abs(t - tm) <= 1e-9 * tm:
                uz = np.atleast_1d(eval_points(problem.u, np.array([[0.0, 0.0, 0.0]])))
                s_h, s_e = -float(uz[2]), blk.settlement(T)
                rows.append({"T_v": T, "t_day": t, "settlement_m": s_h, "settlement_ref_m": s_e,
                             "err_s": abs(s_h - s_e) / s_e})

    log = run_stages(pb, stages, ts, on_milestone=record, geostatic_tol=1e-6)
    err = max(r["err_s"] for r in rows) if len(rows) == len(times) else math.inf
    tol = 0.02
    return CaseResult(
        "consolidation-surcharge", err, tol, bool(err <= tol), time.perf_counter() - t0,
        pb.num_dofs, log.newton_total, len(log.steps),
        reference="Terzaghi (1925) series; Verruijt (2016) ch. 2",
        details={"pair": pair, "nz": nz, "rows": rows, "c_v_m2_per_day": blk.cv,
                 "p0_kPa": blk.p0, "geostatic_max_u_m": log.geostatic_max_u,
                 "ranks": comm.size})
