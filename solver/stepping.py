"""Adaptive backward-Euler time stepping and the staged analysis.

The stepper grows the step after easy Newton convergence, cuts it back and retries (with the
quadrature state and fields rolled back) after a failure or NaN, never accepts a non-converged
step, and lands exactly on milestone times (stage ends, output times).

Stages (docs/model.md):

* ``geostatic``: the law states get the K0 effective stress (``SoilMaterial.k0``), the water is
  hydrostatic (excess pressure 0); one step under the buoyant weight checks the equilibrium
  (largest displacement below ``geostatic_tol`` m, else :class:`SolverError`); then
  displacements are reset to zero, keeping the stresses. The step has the size and drainage
  conditions of the first step that follows (:func:`first_dt`): in equilibrium no water flows,
  so the answer is that of an undrained check, and its Jacobian is the next step's (a reused
  LU factorisation then serves both).
* ``load``: load factor ramped linearly to the stage's value; ``duration = 0`` is one
  instantaneous undrained step.
* ``consolidation``: constant load to the stage end.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from pilegroup.errors import SolverError, StepFailure
from pilegroup.solver.exports import Export
from pilegroup.solver.inputs import Stage, TimeStepping

if TYPE_CHECKING:
    from pilegroup.solver.problem import BiotProblem


@dataclass
class StepRecord:
    """One accepted step."""

    stage: str
    t: float
    dt: float
    load_factor: float
    newton_its: int
    ksp_its: int
    seconds: float


@dataclass
class RunLog:
    """Everything the stepper did: accepted steps and rejected attempts."""

    steps: list[StepRecord] = field(default_factory=list)
    rejected: int = 0
    geostatic_max_u: float | None = None
    wall_s: float = 0.0

    @property
    def newton_total(self) -> int:
        """Newton iterations of the accepted steps."""
        return sum(s.newton_its for s in self.steps)


Callback = Callable[["BiotProblem", float, str], None]


class AdaptiveStepper:
    """Adaptive stepper over a problem with ``solve_step/commit/rollback``.

    Before giving up below ``dt_min`` it asks ``problem.fall_back_linear_solver(message)``
    whether a fallback linear solver can retry the step.

    Args:
        ts: step-size rules.
        log: run log to append to.
    """

    def __init__(self, ts: TimeStepping, log: RunLog | None = None) -> None:
        self.ts = ts
        self.dt = ts.dt0
        self.log = log or RunLog()
        self._easy = 0

    def advance(
        self,
        problem: BiotProblem,
        t0: float,
        t1: float,
        load_factor: Callable[[float], float],
        stage: str = "",
        milestones: Sequence[float] = (),
        on_milestone: Callback | None = None,
        on_step: Callback | None = None,
    ) -> float:
        """Advance from ``t0`` to ``t1`` (day); returns ``t1``.

        ``load_factor(t)`` gives the load factor at time ``t``; ``on_milestone(problem, t,
        stage)`` is called after the accepted step that lands on each milestone in
        ``(t0, t1]`` (``t1`` included); ``on_step(problem, t, stage)`` after every accepted step
        (e.g. a progress bar).
        """
        ts = self.ts
        marks = sorted({float(m) for m in (*milestones, *ts.milestones) if t0 < m < t1} | {t1})
        t = t0
        for m in marks:
            while t < m:
                dt = min(self.dt, ts.dt_max)
                landing = t + dt * (1.0 + 1e-9) >= m or (m - t - dt) < 1e-3 * dt
                if landing:
                    dt = m - t
                t_new = m if landing else t + dt
                info = problem.solve_step(dt, load_factor(t_new))
                if not info.converged:
                    problem.rollback()
                    self.log.rejected += 1
                    self.dt = dt * ts.cut
                    self._easy = 0
                    if self.dt < ts.dt_min and problem.fall_back_linear_solver(info.message):
                        self.dt = dt  # the same step again with the fallback linear solver
                        continue
                    if self.dt < ts.dt_min:
                        raise StepFailure(
                            f"stage {stage!r}: step at t = {t:.6g} day failed with dt = "
                            f"{dt:.3g} day (< dt_min after cut): {info.message}",
                            t, load_factor(t), stage)
                    continue
                problem.commit()
                self.log.steps.append(StepRecord(stage, t_new, dt, load_factor(t_new),
                                                 info.newton_its, info.ksp_its, info.seconds))
                t = t_new
                if on_step is not None:
                    on_step(problem, t, stage)
                if landing:
                    continue
                self.dt = dt
                if info.newton_its <= ts.easy_newton:
                    self._easy += 1
                    if self._easy >= ts.hold:
                        self.dt = min(dt * ts.grow, ts.dt_max)
                        self._easy = 0
                else:
                    self._easy = 0
            if on_milestone is not None:
                on_milestone(problem, t, stage)
        return t


def first_dt(stages: Sequence[Stage], ts: TimeStepping) -> float:
    """Size (day) of the first time step of ``stages``; 0 for an instantaneous load or none."""
    for st in stages:
        if st.kind == "geostatic":
            continue
        if st.kind == "load" and st.duration == 0.0:
            return 0.0
        return min(st.dt0 if st.dt0 is not None else ts.dt0, st.duration, ts.dt_max)
    return 0.0


def run_stages(
    problem: BiotProblem,
    stages: Sequence[Stage],
    ts: TimeStepping,
    on_milestone: Callback | None = None,
    geostatic_tol: float = 1e-6,
    on_step: Callback | None = None,
    exports: Sequence[Export] = (),
) -> RunLog:
    """Run the stages in order; returns the :class:`RunLog`.

    Args:
        problem: a :class:`~pilegroup.solver.problem.BiotProblem`.
        stages: the stages.
        ts: time-stepping rules (milestones in absolute time, day).
        on_milestone: called at stage ends and milestone times, after the exports.
        geostatic_tol: largest displacement (m) accepted by the geostatic equilibrium check.
        on_step: called after every accepted time step (collective; e.g. a progress bar).
        exports: written at stage ends and milestone times; closed at the end of the run.
    """

    def milestone(pb: BiotProblem, t: float, stage: str) -> None:
        for e in exports:
            e.write(t, stage)
        if on_milestone is not None:
            on_milestone(pb, t, stage)

    log = RunLog()
    t_wall = time.perf_counter()
    try:
        return _run(problem, stages, ts, milestone, geostatic_tol, on_step, log)
    except StepFailure as exc:
        exc.run_log = log  # what was done up to the failure (the failed run's summary)
        raise
    finally:
        log.wall_s = time.perf_counter() - t_wall
        for e in exports:
            e.close()


def _run(problem: BiotProblem, stages: Sequence[Stage], ts: TimeStepping,
         on_milestone: Callback, geostatic_tol: float, on_step: Callback | None,
         log: RunLog) -> RunLog:
    """The stage loop of :func:`run_stages`, recording into ``log``."""
    stepper = AdaptiveStepper(ts, log)
    t = 0.0
    lam = 0.0
    for i, st in enumerate(stages):
        if st.kind == "geostatic":
            problem.set_initial_stress(problem.geostatic_stress())
            info = problem.solve_step(first_dt(stages[i + 1:], ts), lam)
            if not info.converged:
                raise SolverError(f"geostatic stage {st.name!r} did not converge: "
                                  f"{info.message}")
            problem.commit()
            umax = problem.max_displacement()
            log.geostatic_max_u = umax
            if umax > geostatic_tol:
                raise SolverError(
                    f"geostatic stage {st.name!r}: max |u| = {umax:.3e} m > {geostatic_tol} m; "
                    "the initial stress is not in equilibrium with the buoyant weight")
            problem.reset_displacements()
            log.steps.append(StepRecord(st.name, t, 0.0, lam, info.newton_its, info.ksp_its,
                                        info.seconds))
            on_milestone(problem, t, st.name)
            continue
        lam0, lam1, t0, t1 = lam, st.load_factor if st.kind == "load" else lam, t, t + st.duration
        if st.kind == "load" and st.duration == 0.0:
            info = problem.solve_step(0.0, lam1)
            if not info.converged and problem.fall_back_linear_solver(info.message):
                problem.rollback()
                info = problem.solve_step(0.0, lam1)
            if not info.converged:
                problem.rollback()
                raise StepFailure(f"instantaneous load stage {st.name!r} failed: {info.message}",
                                  t, lam, st.name)
            problem.commit()
            log.steps.append(StepRecord(st.name, t, 0.0, lam1, info.newton_its, info.ksp_its,
                                        info.seconds))
            lam = lam1
            on_milestone(problem, t, st.name)
            continue
        if st.dt0 is not None:
            stepper.dt = st.dt0

        def lam_of(tt: float, lam0: float = lam0, lam1: float = lam1, t0: float = t0,
                   t1: float = t1) -> float:
            if t1 <= t0:
                return lam1
            return lam0 + (lam1 - lam0) * min(max((tt - t0) / (t1 - t0), 0.0), 1.0)

        t = stepper.advance(problem, t0, t1, lam_of, st.name, on_milestone=on_milestone,
                            on_step=on_step)
        lam = lam1
    return log
