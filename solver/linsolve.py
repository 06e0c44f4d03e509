"""The KSP built from a linear-solver preset (:mod:`pilegroup.solver.presets`), and its reuse.

Every problem has its own options prefix; after each solve the converged reason is checked and
a negative reason raises :class:`LinearSolveError` (a :class:`ConvergenceError`).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from typing import Any

from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import LinearSolveError, SolverInputError
from pilegroup.solver.mumps import OOC_FOLDER_OPTION, OutOfCoreFolder
from pilegroup.solver.presets import PRESETS, Preset, get_preset, merged_options

__all__ = ["PRESETS", "REFACTOR_DT_RATIO", "KSPSolver", "Preset", "check_reason",
           "clear_options", "create_ksp", "dt_ratio", "get_preset", "merged_options"]

log = logging.getLogger(__name__)


#: A step whose dt differs from the kept LU's by this factor (either way) refactors at its
#: first solve: the Jacobian's flow block scales with dt (docs/solver.md, "Linear solvers").
REFACTOR_DT_RATIO = 8.0


def dt_ratio(a: float, b: float) -> float:
    """``max(a / b, b / a)`` of two step sizes (1 when either is 0)."""
    return 1.0 if a <= 0.0 or b <= 0.0 else max(a / b, b / a)


#: ``(name, index set, near-nullspace or None)`` of every block of a field split.
Splits = list[tuple[str, PETSc.IS, PETSc.NullSpace | None]]


def create_ksp(
    comm: MPI.Comm,
    A: PETSc.Mat,
    P: PETSc.Mat | None,
    prefix: str,
    preset: str,
    overrides: Mapping[str, Any] | None = None,
    splits: Splits | None = None,
) -> PETSc.KSP:
    """Create a KSP with operators ``A`` (and preconditioning matrix ``P``) from a preset.

    Args:
        comm: communicator (``mesh.comm``).
        A: system matrix (monolithic blocked PETSc AIJ).
        P: preconditioning matrix or ``None`` (uses ``A``).
        prefix: options prefix of this problem (e.g. ``"biot_"``).
        preset: preset name.
        overrides: extra options.
        splits: the blocks of a fieldsplit preset, in the preset's order (``Preset.splits``).
    """
    spec = get_preset(preset)
    # a clean slate: options an earlier problem of this process left under the prefix (another
    # preset's blocks, its overrides) must not reach this one
    clear_options(prefix)
    opts = PETSc.Options()
    for k, v in merged_options(preset, overrides).items():
        opts[f"{prefix}{k}"] = v
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A, P if P is not None else A)
    if spec.fieldsplit:
        if splits is None or [s[0] for s in splits] != list(spec.splits):
            raise SolverInputError(f"preset {preset!r} needs the index sets {spec.splits}")
        for _, is_, nns in splits:
            if nns is not None:
                is_.compose("nearnullspace", nns)
        pc = ksp.getPC()
        pc.setType("fieldsplit")
        pc.setFieldSplitIS(*[(name, is_) for name, is_, _ in splits])
    ksp.setFromOptions()
    return ksp


def clear_options(prefix: str) -> None:
    """Remove every option under ``prefix`` from PETSc's options database."""
    opts = PETSc.Options()
    for key in list(opts.getAll()):
        if key.startswith(prefix):
            opts.delValue(key)


def check_reason(ksp: PETSc.KSP, what: str = "linear solve") -> int:
    """Raise :class:`LinearSolveError` when the KSP diverged; return its iteration count."""
    reason = ksp.getConvergedReason()
    if reason < 0:
        raise LinearSolveError(f"{what}: KSP diverged, reason {reason}")
    return int(ksp.getIterationNumber())


class KSPSolver:
    """The problem's KSP from a preset, with factorisation reuse and a fallback preset.

    Presets with ``reuse_factor_its`` keep the last LU as FGMRES's preconditioner across
    Newton iterations and steps (the matrix is the current Jacobian: Newton stays exact); a
    solve needing more than ``reuse_factor_its`` iterations beyond the LU's first solve, or
    failing, refactors (and re-solves when it failed); for a step's first solve
    (:meth:`new_step`) the step's next decides. An LU made under other constraints (undrained
    steps) or for a step :data:`REFACTOR_DT_RATIO` times shorter or longer is refactored at
    once. When a Krylov solve of a preset that has a
    ``fallback`` fails (or a step fails with it at the stepper's minimum step),
    :meth:`fall_back` replaces the preset for the rest of the run (one warning line;
    :attr:`fallbacks` records it).

    Args:
        comm: communicator of the problem.
        A: the system matrix (its values change, the object stays).
        prefix: options prefix of the problem.
        preset: preset name; overrides: extra options of that preset.
        fieldsplit_data: ``(preset) -> splits``: the index sets (and near-nullspaces) of the
            blocks of a fieldsplit preset (:data:`Splits`).
    """

    def __init__(self, comm: MPI.Comm, A: PETSc.Mat, prefix: str, preset: str,
                 overrides: Mapping[str, Any] | None,
                 fieldsplit_data: Callable[[Preset], Splits]) -> None:
        self.comm, self.prefix, self.A = comm, prefix, A
        self.P: PETSc.Mat | None = None
        self._fieldsplit_data = fieldsplit_data
        self.refactorisations = 0  # LU factorisations; preconditioner set-ups (field splits)
        self._new_matrix = True
        self.fallbacks: list[str] = []
        # the weighted right-hand side of a forced solve, and the inverse weights
        self._rhs_w: PETSc.Vec | None = None
        self._w_inv: PETSc.Vec | None = None
        self.ksp: PETSc.KSP | None = None
        self._folder: OutOfCoreFolder | None = None  # out-of-core presets' factor files
        self._use(preset, overrides)

    def _use(self, preset: str, overrides: Mapping[str, Any] | None) -> None:
        """Build the KSP of ``preset`` (the previous preset's options are removed)."""
        spec = get_preset(preset)
        self.close()
        overrides = dict(overrides or {})
        if spec.out_of_core:  # a folder of this solver's own: MUMPS's files never mix
            self._folder = OutOfCoreFolder(overrides.get(OOC_FOLDER_OPTION))
            overrides[OOC_FOLDER_OPTION] = str(self._folder.path)
        splits = self._fieldsplit_data(spec) if spec.fieldsplit else None
        self.preset, self._overrides, self.spec = preset, overrides, spec
        self.ksp = create_ksp(self.comm, self.A, self._preconditioning(), self.prefix, preset,
                              overrides, splits)
        self._reusing = False
        self._fresh_its = 0  # iterations of the first solve with the kept factorisation
        self._step_start = False  # the next solve is the first of a step
        self._doubtful = False  # a step's first solve exceeded the limit on the kept one
        self._kept = False  # the blocks of keep_blocks keep their set-up at the next one
        self._stale = False  # their set-up is older than the current matrix
        self._factor_undrained: bool | None = None  # constraints of the kept factorisation
        self._dt = self._factor_dt = 0.0  # the step's dt and that of the kept factorisation

    def close(self) -> None:
        """Destroy the KSP (collective) and remove the out-of-core folder."""
        if self.ksp is not None:
            db = PETSc.Options()
            for k in merged_options(self.preset, self._overrides):
                db.delValue(f"{self.prefix}{k}")
            self.ksp.destroy()
            self.ksp = None
        if self._folder is not None:
            self._folder.remove()
            self._folder = None

    def abandon(self) -> None:
        """After a failure: empty this rank's out-of-core files (not collective).

        Destroying the KSP is, and other ranks may be elsewhere; MUMPS removes the empty files.
        """
        if self._folder is not None:
            self._folder.empty()

    def _preconditioning(self) -> PETSc.Mat | None:
        return self.P if self.spec.fixed_stress else None

    @property
    def uses_preconditioning_matrix(self) -> bool:
        """Whether the preset preconditions with the fixed-stress matrix ``P``."""
        return self.spec.fixed_stress

    def set_operators(self, A: PETSc.Mat, P: PETSc.Mat | None) -> None:
        """Use ``A`` (and ``P`` to precondition when the preset asks for it)."""
        self.A, self.P = A, P
        self._new_matrix = True
        pre = self._preconditioning()
        self.ksp.setOperators(A, pre if pre is not None else A)

    def new_step(self, dt: float = 0.0) -> None:
        """The next solve is the first of a step of ``dt`` days (see :meth:`_solve`)."""
        self._step_start, self._dt = True, dt

    def _set_reuse(self, reuse: bool) -> None:
        self.ksp.getPC().setReusePreconditioner(reuse)
        self._reusing = reuse

    @property
    def forcing(self) -> bool:
        """Whether a solve may stop at a residual given block by block (``Preset.forcing``)."""
        return self.spec.forcing

    def solve(self, rhs: PETSc.Vec, sol: PETSc.Vec, undrained: bool,
              weights: PETSc.Vec | None = None) -> int:
        """Solve ``A sol = rhs``; returns the Krylov iterations (raises when it fails).

        ``weights`` (presets with ``forcing``): row weights; the solve runs on the weighted
        system ``W A sol = W rhs`` and stops when ``|W (rhs - A sol)| <= 1`` (or at the
        preset's relative tolerance). ``A`` is weighted in place and restored after.
        """
        if weights is None or not self.spec.forcing:
            return self._solve(rhs, sol, undrained)
        if self._rhs_w is None:
            self._rhs_w, self._w_inv = rhs.duplicate(), rhs.duplicate()
        self._rhs_w.pointwiseMult(rhs, weights)
        self.A.diagonalScale(L=weights)
        rtol, atol, dtol, max_it = self.ksp.getTolerances()
        self.ksp.setTolerances(atol=1.0)
        try:
            return self._solve(self._rhs_w, sol, undrained)
        finally:
            self.ksp.setTolerances(rtol=rtol, atol=atol, divtol=dtol, max_it=max_it)
            weights.copy(self._w_inv)
            self._w_inv.reciprocal()
            self.A.diagonalScale(L=self._w_inv)

    def fall_back(self, reason: str) -> bool:
        """Hand over to the preset's fallback (one warning line); ``False`` if it has none."""
        fallback = self.spec.fallback
        if fallback is None:
            return False
        note = f"linear solver preset {self.preset!r} failed ({reason}); continuing with " \
            f"{fallback!r}"
        self.fallbacks.append(note)
        if self.comm.rank == 0:
            log.warning(note)
        self._use(fallback, None)
        return True

    def restore(self, preset: str, fallbacks: list[str], refactorisations: int) -> None:
        """Continue a saved run: its preset (after a fallback), notes and factorisation count.

        A kept factorisation is not saved: the next solve factors the current matrix anew.
        """
        if preset != self.preset:
            self._use(preset, None)
        self.fallbacks = list(fallbacks)
        self.refactorisations = int(refactorisations)

    def _keep_blocks(self, keep: bool) -> None:
        """Whether the blocks of ``keep_blocks`` keep their preconditioner at the next set-up.

        If not, the next application sets them up with the current matrix.
        """
        subs = self.ksp.getPC().getFieldSplitSubKSP()
        for name, sub in zip(self.spec.splits, subs, strict=True):
            if name in self.spec.keep_blocks:
                sub.getPC().setReusePreconditioner(keep)
        self._kept = keep

    def _solve_keeping_blocks(self, rhs: PETSc.Vec, sol: PETSc.Vec) -> int:
        """Solve with the kept blocks' preconditioners (refreshed after a failed solve)."""
        if self._new_matrix and self._kept:
            self._stale = True  # the kept set-up is older than the matrix
        if not self._kept and (self._new_matrix or self._stale):
            self.refactorisations += 1  # this solve sets the kept blocks up
            self._stale = False
        self._new_matrix = False
        self.ksp.solve(rhs, sol)
        if self._kept and self.ksp.getConvergedReason() < 0:
            self._keep_blocks(False)  # stale blocks: set them up anew and solve again
            self.refactorisations += 1
            self._stale = False
            self.ksp.solve(rhs, sol)
        its = check_reason(self.ksp, "Newton correction")
        self._keep_blocks(its <= self.spec.keep_its)
        return its

    def _solve(self, rhs: PETSc.Vec, sol: PETSc.Vec, undrained: bool) -> int:
        if self.spec.keep_blocks:
            return self._solve_keeping_blocks(rhs, sol)
        limit = self.spec.reuse_factor_its
        first, self._step_start = self._step_start, False
        if limit and self._reusing and (self._factor_undrained != undrained or (first and (
                self._doubtful or dt_ratio(self._dt, self._factor_dt) >= REFACTOR_DT_RATIO))):
            self._set_reuse(False)
        self.ksp.solve(rhs, sol)
        if limit and self.ksp.getConvergedReason() < 0 and self._reusing:
            self._set_reuse(False)  # stale factorisation: refactor and solve again
            self.ksp.solve(rhs, sol)
        its = check_reason(self.ksp, "Newton correction")
        if not limit and self._new_matrix and (self.spec.fieldsplit
                                               or self.spec.options.get("pc_type") == "lu"):
            self.refactorisations += 1  # LU (of the blocks) and AMG set up once per matrix
        self._new_matrix = False
        log.debug("linear solve: %d iterations, %s factorisation", its,
                  "kept" if self._reusing else "new")
        if limit:
            kept = self._reusing
            if not kept:
                self.refactorisations += 1
                self._factor_undrained, self._factor_dt = undrained, self._dt
                self._fresh_its = its
            within = its <= self._fresh_its + limit
            # a step's first matrix is unlike its next ones: the next solve decides
            self._doubtful = first and kept and not within
            self._set_reuse(within or self._doubtful)
        return its
