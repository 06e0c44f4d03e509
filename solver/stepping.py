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
  LU factorisation then serves both). A step that fails in the linear solver is solved again
  with the preset's fallback, if it has one (as an instantaneous step).
  When a layer starts with an excess pore pressure (consolidating layers), the check step is
  undrained (no water may flow before the first stage that has a duration).
* ``load``: load factor ramped linearly to the stage's value, and the action amplitudes it
  sets (cap actions) with it; ``duration = 0`` is one instantaneous undrained step.
* ``ground``: the amplitudes of the ground actions (surcharges, water table) ramped linearly to
  the stage's values, the load factor held; ``duration = 0`` is instantaneous.
* ``consolidation``: every action held to the stage end.
* ``capacity``: the load factor ramped as in a load stage until the foundation fails. Load
  control cannot pass the peak of the load–settlement curve: near the limit load Newton stops
  converging, the step is cut back by ``cut`` until it would fall below ``dt_min``, and the
  limit load is then bracketed between the last equilibrium and the load of the last step
  tried. That is the stage's result, not an error: the stage (and the run: nothing follows a
  failed foundation) ends at the last equilibrium, with ``RunLog.capacity_end`` saying how. A
  step callback may end it earlier by raising :class:`~pilegroup.errors.CapacityReached` (e.g.
  once the settlement is past every criterion); reaching the stage's load ends it too.
* ``install``: the structure (piles and cap), held still and free of the soil's shear since
  the start, joins the soil at this instant (``problem.install_structure``); the ground may
  have moved before. No step is solved: the state is in equilibrium as it is.

The analysis starts at ``t_start`` (day, e.g. negative when the ground moves before the piles
are installed at day 0).

A run can be resumed: :class:`RunState` is where the stage loop is (stage, t, load factor) and
what the stepper remembers (``dt``, ``easy``, the run log); :func:`run_stages` starts from a
given one and calls a ``boundary`` hook at every step boundary, where a checkpoint can be
saved or the run stopped (docs/checkpoint.md).
"""

from __future__ import annotations

import logging
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from pilegroup.errors import CapacityReached, SolverError, StepFailure
from pilegroup.solver.exports import Export
from pilegroup.solver.inputs import SolverStage, StepControl
from pilegroup.solver.runlog import RunLog, StepRecord
from pilegroup.solver.step_protocol import StepInfo, StepProblem

log = logging.getLogger(__name__)

Callback = Callable[[StepProblem, float, str], None]


class AdaptiveStepper:
    """Adaptive stepper over a problem with ``solve_step/commit/rollback``.

    When a Krylov solve failed, or before giving up below ``dt_min``, it asks
    ``problem.fall_back_linear_solver(message)`` whether a fallback linear solver can retry the
    step at the same size. Its memory between steps is ``dt`` (the next step size) and ``easy``
    (easy steps in a row at that size); a resumed run sets both from its checkpoint.

    Args:
        ts: step-size rules.
        log: run log to append to.
    """

    def __init__(self, ts: StepControl, log: RunLog | None = None) -> None:
        self.ts = ts
        self.dt = ts.dt0
        self.log = log or RunLog()
        self.easy = 0

    def advance(
        self,
        problem: StepProblem,
        t0: float,
        t1: float,
        load_factor: Callable[[float], float],
        stage: str = "",
        milestones: Sequence[float] = (),
        on_milestone: Callback | None = None,
        on_step: Callback | None = None,
        on_boundary: Callable[[float, bool], None] | None = None,
        ground: Callable[[float], tuple[float, ...]] | None = None,
        dt_max: float | None = None,
    ) -> float:
        """Advance from ``t0`` to ``t1`` (day); returns ``t1``.

        ``load_factor(t)`` gives the load factor at time ``t``, ``ground(t)`` (if given) the
        amplitudes of the ground actions; ``on_milestone(problem, t,
        stage)`` is called after the accepted step that lands on each milestone in
        ``(t0, t1]`` (``t1`` included); ``on_step(problem, t, stage)`` after every accepted step
        (e.g. a progress bar); ``on_boundary(t, output)`` at every step boundary, after the
        step was accepted (and its milestone written: ``output`` true) or rejected: the safe
        points where a run may save a checkpoint or stop. ``dt_max``: a smaller largest step
        than the run's for this advance.
        """
        ts = self.ts
        dt_cap = ts.dt_max if dt_max is None else min(dt_max, ts.dt_max)
        marks = sorted({float(m) for m in (*milestones, *ts.milestones) if t0 < m < t1} | {t1})
        t = t0
        for m in marks:
            landed = False
            while t < m:
                dt = min(self.dt, dt_cap)
                landing = t + dt * (1.0 + 1e-9) >= m or (m - t - dt) < 1e-3 * dt
                if landing:
                    dt = m - t
                t_new = m if landing else t + dt
                if ground is not None:
                    problem.set_ground(ground(t_new))
                info = problem.solve_step(dt, load_factor(t_new))
                if not info.converged:
                    self._reject(problem, info, t, dt, load_factor, stage)
                    if on_boundary is not None:
                        on_boundary(t, False)
                    continue
                problem.commit()
                if info.alternate:
                    self.log.alternate += 1
                    log.info("stage %r: step t = %.6g + %.3g day accepted by the alternate "
                             "tolerance after %d Newton iterations", stage, t, dt,
                             info.newton_its)
                self.log.steps.append(StepRecord(stage, t_new, dt, load_factor(t_new),
                                                 info.newton_its, info.ksp_its, info.seconds,
                                                 info.ksp_max))
                t = t_new
                if on_step is not None:
                    on_step(problem, t, stage)
                if landing:
                    landed = True
                    if on_milestone is not None:
                        on_milestone(problem, t, stage)
                else:
                    self._grow(dt, info.newton_its)
                if on_boundary is not None:
                    on_boundary(t, landing)
            if not landed and on_milestone is not None:  # a mark at t0 (zero duration)
                on_milestone(problem, t, stage)
        return t

    def _reject(self, problem: StepProblem, info: StepInfo, t: float, dt: float,
                load_factor: Callable[[float], float], stage: str) -> None:
        """Roll a failed step back and cut ``dt``, or hand over to a fallback linear solver.

        A failed Krylov solve hands over at once (a smaller step is no cure for a
        preconditioner that does not converge, and an iterative preset failing near its
        iteration limit would otherwise crawl on ever smaller steps); a Newton failure cuts
        ``dt`` and hands over only below ``dt_min``. The step is then tried again unchanged.
        """
        ts = self.ts
        log.info("stage %r: step t = %.6g + %.3g day rejected after %d Newton iterations: %s",
                 stage, t, dt, info.newton_its, info.message)
        problem.rollback()
        self.log.rejected += 1
        self.dt = dt * ts.cut
        self.easy = 0
        if (info.linear_failure or self.dt < ts.dt_min) \
                and problem.fall_back_linear_solver(info.message):
            self.dt = dt  # the same step again with the fallback linear solver
            return
        if self.dt < ts.dt_min:
            raise StepFailure(
                f"stage {stage!r}: step at t = {t:.6g} day failed with dt = "
                f"{dt:.3g} day (< dt_min after cut): {info.message}",
                t, load_factor(t), stage, failed_load_factor=load_factor(t + dt))

    def _grow(self, dt: float, newton_its: int) -> None:
        """After an accepted (non-landing) step of size ``dt``: keep it, or grow it."""
        ts = self.ts
        self.dt = dt
        if newton_its <= ts.easy_newton:
            self.easy += 1
            if self.easy >= ts.hold:
                self.dt = min(dt * ts.grow, ts.dt_max)
                self.easy = 0
        else:
            self.easy = 0


def first_dt(stages: Sequence[SolverStage], ts: StepControl) -> float:
    """Size (day) of the first time step of ``stages``; 0 for an instantaneous load or none."""
    for st in stages:
        if st.kind == "geostatic":
            continue
        if st.kind == "load" and st.duration == 0.0:
            return 0.0
        return min(st.dt0 if st.dt0 is not None else ts.dt0, st.duration, ts.dt_max)
    return 0.0


@dataclass
class RunState:
    """Where the stage loop is and what the stepper remembers: what a checkpoint saves.

    ``stage`` is the index of the stage in progress, ``started`` whether its set-up is done
    (its ``dt0`` applied), ``done`` whether it is complete (its end reached and written);
    ``t`` (day) and ``lam`` (load factor) are those of the last committed step; ``dt`` and
    ``easy`` the stepper's memory (:class:`AdaptiveStepper`); ``log`` the run log so far.
    A fresh run starts from ``RunState()``; a resumed run from the state of its checkpoint.
    """

    stage: int = 0
    started: bool = False
    done: bool = False
    t: float = 0.0
    lam: float = 0.0
    dt: float | None = None
    easy: int = 0
    log: RunLog = field(default_factory=RunLog)


#: ``boundary(problem, state, output)``: called at every step boundary (after an accepted or
#: rejected step; ``output`` true when an output time was just written), collectively.
Boundary = Callable[[StepProblem, RunState, bool], None]


def run_stages(
    problem: StepProblem,
    stages: Sequence[SolverStage],
    ts: StepControl,
    on_milestone: Callback | None = None,
    geostatic_tol: float = 1e-6,
    on_step: Callback | None = None,
    exports: Sequence[Export] = (),
    state: RunState | None = None,
    boundary: Boundary | None = None,
    t_start: float = 0.0,
) -> RunLog:
    """Run the stages in order; returns the :class:`RunLog`.

    Args:
        problem: a :class:`~pilegroup.solver.step_protocol.StepProblem` (e.g. a
            :class:`~pilegroup.solver.problem.BiotProblem`).
        stages: the stages.
        ts: time-stepping rules (milestones in absolute time, day).
        on_milestone: called at stage ends and milestone times, after the exports.
        geostatic_tol: largest displacement (m) accepted by the geostatic equilibrium check.
        on_step: called after every accepted time step (collective; e.g. a progress bar).
        exports: written at stage ends and milestone times; closed at the end of the run.
        state: where to start (a checkpoint's, with the problem's state restored to it); a
            fresh run by default. It is kept up to date during the run.
        boundary: called at every step boundary with the current ``state`` (it may save a
            checkpoint, or raise to stop the run there).
        t_start: the time (day) of the geostatic state, where the first stage starts.
    """

    def milestone(pb: StepProblem, t: float, stage: str) -> None:
        for e in exports:
            e.write(t, stage)
        if on_milestone is not None:
            on_milestone(pb, t, stage)

    run_state = state or RunState(t=t_start)
    try:
        return _Run(problem, stages, ts, run_state, boundary).run(
            milestone, geostatic_tol, on_step, t_start)
    except StepFailure as exc:
        exc.run_log = run_state.log  # what was done up to the failure (the failed run's summary)
        raise
    finally:
        for e in exports:
            e.close()


class _Run:
    """The stage loop of :func:`run_stages`, resumable from a :class:`RunState`."""

    def __init__(self, problem: StepProblem, stages: Sequence[SolverStage], ts: StepControl,
                 state: RunState, boundary: Boundary | None) -> None:
        self.problem, self.stages, self.ts = problem, stages, ts
        self.state, self.boundary = state, boundary
        #: amplitudes of the actions (ground, cap): none when no stage sets them
        self.n_ground = max((len(st.ground) for st in stages), default=0)
        self.stepper = AdaptiveStepper(ts, state.log)
        if state.dt is not None:
            self.stepper.dt = state.dt
        self.stepper.easy = state.easy

    def at_boundary(self, t: float, lam: float, output: bool, done: bool = False) -> None:
        """Record the committed state in ``state`` and call the boundary hook."""
        s = self.state
        s.t, s.lam, s.done = t, lam, done
        s.dt, s.easy = self.stepper.dt, self.stepper.easy
        if self.boundary is not None:
            self.boundary(self.problem, s, output)

    def run(self, on_milestone: Callback, geostatic_tol: float, on_step: Callback | None,
            t_start: float = 0.0) -> RunLog:
        """Every stage not yet complete, in order."""
        s, log = self.state, self.state.log
        t_wall = time.perf_counter() - log.wall_s
        t, lam = t_start, 0.0  # the start of each stage, the same arithmetic in a resumed run
        g = (0.0,) * self.n_ground
        for i, st in enumerate(self.stages):
            t1 = t + st.duration
            lam1 = st.load_factor if st.kind in ("load", "capacity") else lam
            g1 = tuple(st.ground) + g[len(st.ground):] if st.ground else g
            if i < s.stage or (i == s.stage and s.done):
                if st.kind == "install":  # a resumed run's structure is in place again
                    self.problem.install_structure(restored=True)
                t, lam, g = t1, lam1, g1
                continue
            resume = i == s.stage and s.started
            s.stage, s.started, s.done = i, True, False
            if st.kind == "install":
                self.problem.install_structure(restored=False)
                on_milestone(self.problem, t, st.name)
                self.at_boundary(t, lam, True, done=True)
            elif st.kind == "geostatic":
                self._set_ground(g)
                self._geostatic(i, st, t, lam, geostatic_tol, on_milestone)
            elif st.kind in ("load", "ground") and st.duration == 0.0:
                self._set_ground(g1)
                self._instantaneous(st, t, lam, lam1, on_milestone)
            elif st.kind == "capacity":
                if st.dt0 is not None and not resume:
                    self.stepper.dt = st.dt0
                self._capacity(st, (t, t1, lam, lam1), s.t if resume else t, on_milestone,
                               on_step, g)
                break  # nothing follows a failed foundation
            else:
                if st.dt0 is not None and not resume:
                    self.stepper.dt = st.dt0
                self._advance(st, (t, t1, lam, lam1), s.t if resume else t, on_milestone,
                              on_step, (g, g1))
            t, lam, g = t1, lam1, g1
        log.wall_s = time.perf_counter() - t_wall
        return log

    def _capacity(self, st: SolverStage, span: tuple[float, float, float, float], t_from: float,
                  on_milestone: Callback, on_step: Callback | None, g: tuple[float, ...]
                  ) -> None:
        """A capacity stage: a load ramp that ends where the foundation fails (module doc)."""
        t0, t1, lam0, lam1 = span
        end: dict[str, object]
        try:
            self._advance(st, span, t_from, on_milestone, on_step, (g, g))
            end = {"reason": "max load", "t_day": t1, "load_factor": lam1,
                   "failed_load_factor": None, "message": "the stage's largest load carried"}
        except StepFailure as exc:  # rolled back to the last equilibrium
            end = {"reason": "no equilibrium", "t_day": exc.t, "load_factor": exc.load_factor,
                   "failed_load_factor": exc.failed_load_factor, "message": str(exc)}
        except CapacityReached as exc:  # the step was accepted and committed
            end = {"reason": "stopped", "t_day": exc.t, "load_factor": exc.load_factor,
                   "failed_load_factor": None, "message": exc.reason}
        self.state.log.capacity_end = end
        if end["reason"] != "max load":
            t, lam = float(end["t_day"]), float(end["load_factor"])  # type: ignore[arg-type]
            on_milestone(self.problem, t, st.name)
            self.at_boundary(t, lam, True, done=True)

    def _set_ground(self, g: tuple[float, ...]) -> None:
        if self.n_ground:
            self.problem.set_ground(g)

    def _geostatic(self, i: int, st: SolverStage, t: float, lam: float, tol: float,
                   on_milestone: Callback) -> None:
        """K0 stress, one equilibrium check step, displacements reset (see the module doc)."""
        problem, log = self.problem, self.state.log
        problem.set_initial_stress(problem.geostatic_stress())
        problem.set_initial_pressure()
        dt = 0.0 if problem.has_initial_excess else first_dt(self.stages[i + 1:], self.ts)
        info = problem.solve_step(dt, lam)
        if not info.converged and problem.fall_back_linear_solver(info.message):
            problem.rollback()
            info = problem.solve_step(dt, lam)
        if not info.converged:
            raise SolverError(f"geostatic stage {st.name!r} did not converge: {info.message}")
        problem.commit()
        umax = problem.max_displacement()
        log.geostatic_max_u = umax
        if umax > tol:
            raise SolverError(
                f"geostatic stage {st.name!r}: max |u| = {umax:.3e} m > {tol} m; "
                "the initial stress is not in equilibrium with the buoyant weight")
        problem.reset_displacements()
        log.steps.append(StepRecord(st.name, t, 0.0, lam, info.newton_its, info.ksp_its,
                                    info.seconds, info.ksp_max))
        on_milestone(problem, t, st.name)
        self.at_boundary(t, lam, True, done=True)

    def _instantaneous(self, st: SolverStage, t: float, lam: float, lam1: float,
                       on_milestone: Callback) -> None:
        """One undrained step to the stage's load factor."""
        problem = self.problem
        info = problem.solve_step(0.0, lam1)
        if not info.converged and problem.fall_back_linear_solver(info.message):
            problem.rollback()
            info = problem.solve_step(0.0, lam1)
        if not info.converged:
            problem.rollback()
            raise StepFailure(f"instantaneous load stage {st.name!r} failed: {info.message}",
                              t, lam, st.name)
        problem.commit()
        self.state.log.steps.append(StepRecord(st.name, t, 0.0, lam1, info.newton_its,
                                               info.ksp_its, info.seconds, info.ksp_max))
        on_milestone(problem, t, st.name)
        self.at_boundary(t, lam1, True, done=True)

    def _advance(self, st: SolverStage, span: tuple[float, float, float, float], t_from: float,
                 on_milestone: Callback, on_step: Callback | None,
                 ground: tuple[tuple[float, ...], tuple[float, ...]]) -> None:
        """A ramped load or ground stage, or a consolidation stage, from ``t_from`` to its end."""
        t0, t1, lam0, lam1 = span
        g0, g1 = ground

        def frac(tt: float) -> float:
            return 1.0 if t1 <= t0 else min(max((tt - t0) / (t1 - t0), 0.0), 1.0)

        def lam_of(tt: float) -> float:
            return lam0 + (lam1 - lam0) * frac(tt)

        def ground_of(tt: float) -> tuple[float, ...]:
            return tuple(a + (b - a) * frac(tt) for a, b in zip(g0, g1, strict=True))

        def boundary(t: float, output: bool) -> None:
            self.at_boundary(t, lam_of(t), output, done=output and t >= t1)

        self.stepper.advance(self.problem, t_from, t1, lam_of, st.name,
                             on_milestone=on_milestone, on_step=on_step, on_boundary=boundary,
                             ground=ground_of if self.n_ground else None, dt_max=st.dt_max)
        if t1 <= t_from:  # nothing to step (zero duration): the stage end is reached as is
            self.at_boundary(t1, lam1, True, done=True)
