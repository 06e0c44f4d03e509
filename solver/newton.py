"""Newton's method with a backtracking line search, over the step protocol.

The driver knows nothing of forms or meshes: it uses a problem only through
:class:`~pilegroup.solver.step_protocol.StepProblem` (``set_step``, ``residual_state`` (laws
and residual ``b``; raises ``ConvergenceError`` on NaN), ``assemble_jacobian``,
``solve_linear``, ``force_scales``, the block vectors ``x``, ``b``, ``dx`` with
``block_norms`` and ``x_to_fields``, and the rigid ``plate`` with its ``plate_block``).

Convergence (every block): ``|r_i| <= rtol * ref_i + atol``, with ``ref_i`` the largest
residual norm of the block seen at the start of a step so far in the run; the displacement
blocks share one force reference (kN): the largest of their internal forces (the current stress,
geostatic state included), the plate force and those residuals, because the bodies exchange
their forces through the interface, whose imbalance shows in both (as ABAQUS takes one
time-averaged force per field). Or: the increment is below ``stol`` times the solution, block
by block. A step never accepts a non-converged state.

A step whose iterations alternate between two states above the tolerance (:func:`cycling`) is
given up before the iteration limit: the stepper cuts it as any failed step.

Alternate tolerance (ABAQUS's ``R_P`` after ``I_P`` iterations): from iteration ``alt_after``
on, a residual within ``alt_factor`` times the tolerance is accepted (``StepInfo.alternate``).
A law with a kink (an interface point at its yield) makes Newton chatter a few times above the
tolerance without converging, and where in that band an iteration lands differs from machine to
machine; measured on Pier 667 at h = 0.1 m: 5.9e6, 860, 523, 746, 22.9, 41.7, 22.6, 22.8, 3.55,
28, 26.8, 3.48, 57.5, 3.56, 28.5, 3.44 times the tolerance, and the step cut (docs/solver.md).

Inexact Newton: each correction's linear solve may stop once every block's linear residual is
below ``krylov_forcing`` times that block's tolerance (``NewtonOptions.krylov_forcing``).
"""

from __future__ import annotations

import time

import numpy as np
from petsc4py import PETSc

from pilegroup.errors import ConvergenceError, LinearSolveError
from pilegroup.solver.inputs import NewtonOptions
from pilegroup.solver.step_protocol import StepInfo, StepProblem


def cycling(ratios: list[float], close: float = 0.05, apart: float = 1.2) -> bool:
    """Whether Newton alternates between two states above the tolerance (a 2-cycle).

    ``ratios``: the largest residual over its tolerance at each iteration so far. A cycle:
    each of the last two values within ``close`` (relative) of the value two iterations before,
    the two at least ``apart`` times each other, both above 1. Newton is deterministic, so it
    goes on alternating (a point of a law with a kink in its tangent flips between two
    branches) until the iteration limit; the step is better cut at once. A monotone slow
    decrease is not a cycle.
    """
    if len(ratios) < 5:
        return False
    a, b, c, d = ratios[-4:]
    return (abs(d - b) <= close * b and abs(c - a) <= close * a
            and max(c, d) >= apart * min(c, d) and min(c, d) > 1.0)


class NewtonSolver:
    """Newton iterations of one step; keeps the run's residual references between steps."""

    def __init__(self, problem: StepProblem, options: NewtonOptions) -> None:
        self.problem = problem
        self.options = options
        self.R_run = np.zeros(problem.block_count)

    def solve(self, dt: float, load_factor: float) -> StepInfo:
        """Solve one step; never raises on non-convergence (``converged = False``)."""
        t_start = time.perf_counter()
        pb, nw = self.problem, self.options
        pb.set_step(dt, load_factor)
        info = StepInfo(converged=False)
        ok_inc = False
        try:
            rn, gap = pb.residual_state(load_factor)
            ref = self._reference(rn, load_factor)
            ratios: list[float] = []  # largest residual / tolerance over the blocks
            for it in range(nw.max_it + 1):
                info.residuals.append(tuple(float(r) for r in rn))
                ratios.append(float(np.max(rn / (nw.rtol * ref + nw.atol))))
                if it >= 1 and (self._small(rn, gap, ref, load_factor) or ok_inc):
                    info.converged = True
                    break
                if it >= nw.alt_after and self._small(rn, gap, ref, load_factor,
                                                      nw.alt_factor):
                    info.converged = info.alternate = True
                    break
                if it == nw.max_it:
                    info.message = (f"no convergence in {nw.max_it} iterations; |r| = {rn}; "
                                    "largest residual / tolerance by iteration: "
                                    + ", ".join(f"{r:.3g}" for r in ratios))
                    break
                if cycling(ratios):
                    info.message = (f"Newton cycles between two states after {it} iterations "
                                    f"(residual {ratios[-2]:.3g} and {ratios[-1]:.3g} times "
                                    "the tolerance, in turn)")
                    break
                pb.assemble_jacobian()
                its = pb.solve_linear(pb.b, pb.dx, self._linear_tolerance(ref))
                info.ksp_its += its
                info.ksp_max = max(info.ksp_max, its)
                dU = pb.plate.border(pb, load_factor) if pb.plate is not None else 0.0
                dxn = pb.block_norms(pb.dx)
                if not np.all(np.isfinite(dxn)):
                    raise ConvergenceError("NaN Newton increment")
                xn = pb.block_norms(pb.x)
                ok_inc = bool(np.all(dxn <= nw.stol * np.maximum(xn, 1e-300)))
                info.newton_its = it + 1
                rn, gap = self._line_search(rn, gap, ref, dU, load_factor)
        except ConvergenceError as exc:
            info.converged = False
            info.linear_failure = isinstance(exc, LinearSolveError)
            info.message = str(exc)
        except PETSc.Error as exc:  # pragma: no cover - PETSc failures are reported, not hidden
            info.converged = False
            info.message = f"PETSc error {exc}"
        info.seconds = time.perf_counter() - t_start
        return info

    def _reference(self, rn: np.ndarray, load_factor: float) -> np.ndarray:
        """Residual references of the step (see the module docstring); updates the run's."""
        pb = self.problem
        ref = np.maximum(self.R_run, rn)
        u_blocks = pb.u_blocks
        for i, fn in zip(u_blocks, pb.force_scales(), strict=True):
            ref[i] = max(ref[i], fn)
        if pb.plate is not None and pb.plate_block is not None:
            ib = pb.plate_block
            ref[ib] = max(ref[ib], abs(pb.plate.target(load_factor)))
        ref[u_blocks] = np.max(ref[u_blocks])
        self.R_run = np.maximum(self.R_run, ref)
        return ref

    def _linear_tolerance(self, ref: np.ndarray) -> np.ndarray | None:
        """Largest linear residual of each block a correction may leave (inexact Newton).

        ``krylov_forcing`` times the block's Newton tolerance; ``None`` (solve to the
        preset's own tolerance) without forcing or with a force-controlled plate, whose
        force test sums the residual over the plate's dofs.
        """
        nw = self.options
        if nw.krylov_forcing <= 0.0 or self.problem.plate is not None:
            return None
        return nw.krylov_forcing * (nw.rtol * ref + nw.atol)

    def _small(self, rn: np.ndarray, gap: float, ref: np.ndarray, load_factor: float,
               factor: float = 1.0) -> bool:
        """Residual test of every block (and of the plate force), ``factor`` x the tolerance."""
        nw, plate = self.options, self.problem.plate
        ok = bool(np.all(rn <= factor * (nw.rtol * ref + nw.atol)))
        if plate is not None:
            fscale = max(abs(plate.target(load_factor)), 1e-30)
            ok = ok and abs(gap) <= factor * (nw.rtol * fscale + nw.atol)
        return ok

    def _line_search(self, rn: np.ndarray, gap: float, ref: np.ndarray, dU: float,
                     load_factor: float) -> tuple[np.ndarray, float]:
        """Backtracking on the scaled residual (only acts when it grows); updates ``x``.

        A block counts with the excess of its residual over its convergence tolerance
        (``rtol * ref + atol``): what lies below the tolerance does not decide the step.
        Otherwise the round-off of an iterative linear solve in a block whose reference is
        still zero (the pressure of the geostatic step, scaled by ``atol``) outweighs the
        decrease of the others, and the search cuts every full step to its shortest.
        """
        pb, nw, plate = self.problem, self.options, self.problem.plate
        scale = np.maximum(ref, nw.atol)
        floor = nw.rtol * ref + nw.atol
        gscale = max(abs(plate.target(load_factor)), nw.atol) if plate is not None else 1.0

        def merit(r: np.ndarray, g: float) -> float:
            return float(np.sum(np.maximum(r - floor, 0.0) / scale)) + abs(g) / gscale

        m0 = merit(rn, gap)
        x_old = pb.x.copy()
        U_old = plate.value - dU if plate is not None else 0.0
        alpha = 1.0
        for ls in range(nw.line_search + 1):
            pb.x.array[:] = x_old.array_r
            pb.x.axpy(-alpha, pb.dx)
            if plate is not None:
                plate.set(U_old + alpha * dU)
            pb.x_to_fields(pb.x)
            try:
                rn, gap = pb.residual_state(load_factor)
                m1 = merit(rn, gap)
            except ConvergenceError:
                if ls == nw.line_search:
                    raise
                m1 = np.inf
            if m1 <= (1.0 - 1e-4 * alpha) * m0 or ls == nw.line_search:
                break
            alpha *= 0.5
        x_old.destroy()
        return rn, gap
