"""The cap's 6 x 6 stiffness matrix about the action point, probed at the run's final state.

With ``outputs.cap_stiffness`` the run models the whole foundation with a face action for
every component (:mod:`~pilegroup.studies.run.cap_loads`); after its last stage each of the
six actions about the action point is increased in turn by a small amount, one undrained step
(``dt = 0``: the short-term response, as for traffic and braking) is solved from the
committed state, the face's motion at the point is read (:class:`~pilegroup.studies.run.
section_probe.CapMotion`) and the step is rolled back. The six motions per unit action are the
flexibility matrix's columns; its inverse is the tangent stiffness matrix ``K`` (kN/m, kN/rad,
kN m/m, kN m/rad) that a superstructure model takes as the foundation's spring. Without a cap it
is the single pile head's matrix.

``cap_stiffness.csv``: ``action,ux_m,uy_m,uz_m,rx_rad,ry_rad,rz_rad``: row ``Fx`` .. ``Mz``
holds the actions per unit motion, ``K[i, j] = dF_i / du_j``.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from pilegroup.errors import ScenarioError, SolverError
from pilegroup.fileio import write_text_atomic
from pilegroup.model import Scenario
from pilegroup.model.actions import COMPONENTS, transfer
from pilegroup.solver import BiotProblem, SolverStage
from pilegroup.studies.results.tables import STIFFNESS_COLUMNS
from pilegroup.studies.run.cap_loads import first_slot
from pilegroup.studies.run.section_probe import CapMotion

#: Probe size: this fraction of the vertical load (at least 1 kN); moments times the face size.
PROBE_FRACTION = 1e-2


def scenario_until(sc: Scenario, day: float) -> Scenario:
    """``sc`` ended at ``day``: the matrix of the state then (``pilegroup stiffness --day``).

    ``day`` must close a stage or fall in a consolidation stage (whose end moves to it); the
    stages after it are dropped and the output times after it too, ``day`` added. Inside a
    load, surcharge or groundwater stage the actions would not be the stage's: an error
    naming ``--day``.
    """
    kept = []
    for st, t0, t1 in sc.stage_times():
        if t0 >= day and kept and st.kind not in ("geostatic", "installation"):
            break
        if t0 <= day < t1 and st.kind != "consolidation":
            raise ScenarioError("--day", day, f"falls inside the {st.kind} stage {st.name!r} "
                                f"(day {t0:g} .. {t1:g}); allowed: a stage's end or a day in a "
                                "consolidation stage")
        kept.append(dataclasses.replace(st, until_day=day) if st.kind == "consolidation"
                    and t0 <= day < t1 else st)
    if not sc.time.start_day < day <= sc.time.end_day:
        raise ScenarioError("--day", day, f"must be in ({sc.time.start_day:g}, "
                            f"{sc.time.end_day:g}], the analysis's days", "day")
    days = tuple(sorted({t for t in sc.time.output_days if t < day} | {day}))
    time = dataclasses.replace(sc.time, end_day=day, output_days=days)
    return dataclasses.replace(sc, stages=tuple(kept), time=time)


def probe_sizes(sc: Scenario) -> np.ndarray:
    """The six probe increments (kN, kN m)."""
    force = max(PROBE_FRACTION * sc.total_cap_load(), 1.0)
    lever = max(sc.cap.size_x_m, sc.cap.size_y_m) if sc.cap is not None \
        else max(sc.piles.diameters)
    return np.array([force] * 3 + [force * lever] * 3)


def cap_stiffness(sc: Scenario, pb: BiotProblem, motion: CapMotion,
                  stages: Sequence[SolverStage]) -> np.ndarray:
    """``K`` (6 x 6) about the action point at ``pb``'s committed state (collective)."""
    g = np.array(next((st.ground for st in reversed(stages) if st.ground), ()), dtype=float)
    slot, lam = first_slot(sc), pb.load_factor
    P, C = sc.action_point(), sc.load_centre()
    m0 = motion()
    flex = np.zeros((6, 6))
    for k, size in enumerate(probe_sizes(sc)):
        probe = g.copy()
        probe[slot: slot + 6] += transfer(np.eye(6)[k] * size, P, C)
        pb.set_ground(probe)
        info = pb.solve_step(0.0, lam)
        if not info.converged:
            pb.rollback()
            raise SolverError(f"cap stiffness: the {COMPONENTS[k]} probe of {size:g} did not "
                              f"converge: {info.message}")
        flex[:, k] = (motion() - m0) / size
        pb.rollback()
    pb.set_ground(tuple(g))
    return np.linalg.inv(flex)


def write_cap_stiffness(path: Path, K: np.ndarray) -> None:
    """``cap_stiffness.csv`` (module docstring); call on one rank."""
    head = STIFFNESS_COLUMNS
    rows = [f"{c}," + ",".join(f"{v:.9g}" for v in row) for c, row in zip(COMPONENTS, K,
                                                                          strict=True)]
    write_text_atomic(path, "\n".join([head, *rows]) + "\n")


__all__ = ["cap_stiffness", "probe_sizes", "scenario_until",
           "write_cap_stiffness"]
