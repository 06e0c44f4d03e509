"""Linear-solver option sets as data, and the KSP built from them.

Presets (docs/solver.md, "Linear solvers"; measured in docs/benchmarks.md):

* ``direct``: MUMPS LU (robust, for small and medium problems; the default).
* ``direct_reuse``: FGMRES on the current Jacobian preconditioned by a kept block low-rank
  MUMPS LU in single precision; ``direct_reuse_double``: the same LU in double precision (the
  fallback of ``direct_reuse``); ``direct_reuse_ooc`` and its fallback
  ``direct_reuse_ooc_double``: the same two with the factors out of core.
* ``fieldsplit_gamg``: FGMRES preconditioned by a block Gauss–Seidel of the u–p system: one
  GAMG V-cycle with the rigid-body near-nullspace on u, one SOR sweep on the pressure block of
  the fixed-stress matrix ``(alpha^2/K_dr) M`` (Kim, Tchelepi & Juanes 2011; White,
  Castelletto & Tchelepi 2016); GAMG on p failed when every pressure dof is fixed.
* ``fieldsplit_pier``: FGMRES preconditioned by a three-way block Gauss–Seidel in the order
  pressure (MUMPS LU of the fixed-stress block), structure (piles and cap with the soil at the
  interface nodes and a band of about 2 m of soil, ``SolverOptions.band_layers``, by MUMPS LU:
  the stiff springs and the 10^4 stiffness contrast stay in one block), other soil (one GAMG
  V-cycle, unsmoothed aggregation, Chebyshev(4) of two SOR sweeps); both LUs in single
  precision; the displacement blocks overlap on the band (multiplicative Schwarz there).
* ``fieldsplit_kept``: ``fieldsplit_pier`` whose structure block keeps its LU across new
  Jacobians (``Preset.keep_blocks``) until a solve needs more than 60 iterations.

Every problem has its own options prefix; after each solve the converged reason is checked and
a negative reason raises :class:`LinearSolveError` (a :class:`ConvergenceError`).
"""

from __future__ import annotations

import dataclasses
import logging
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from typing import Any

from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import LinearSolveError, SolverInputError
from pilegroup.solver.mumps import OOC_FOLDER_OPTION, OutOfCoreFolder, mumps_single_precision

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Preset:
    """A named option set.

    Attributes:
        name: preset name.
        options: PETSc options (without prefix).
        fieldsplit: the preset is a field split over the index sets named by ``splits``.
        splits: the field-split blocks in order: ``"u"`` (every displacement), ``"p"``
            (pressure), ``"structure"`` (the structure's displacement with the soil's at the
            interface nodes), ``"soil"`` (the rest of the soil displacement). The options
            prefix of a block is ``fieldsplit_<name>_``; the displacement block solved by AMG
            (``"u"`` or ``"soil"``) carries its rigid-body modes as near-nullspace.
        band_layers: the ``"structure"`` block also holds the soil nodes within this many cell
            layers of the interface nodes, which stay in the ``"soil"`` block too: the two
            blocks overlap there (multiplicative Schwarz between them); a problem's
            ``SolverOptions.band_layers`` replaces it.
        fixed_stress: the preset needs the fixed-stress preconditioning matrix.
        reuse_factor_its: > 0: keep the LU across Newton iterations and steps as FGMRES's
            preconditioner; refactor after a solve needing this many iterations more than the
            LU's first solve (a fresh block low-rank LU is itself inexact); see
            :class:`KSPSolver`.
        fallback: the preset that takes over (with one warning line) when a solve with this
            one fails; ``None``: the failure is the step's.
        keep_blocks: field-split blocks whose preconditioner (e.g. an LU factorisation) is
            kept when the matrix changes, the other blocks being set up anew; all are set up
            anew after a solve needing more than ``keep_its`` iterations, or a failed one
            (which is then solved again).
        keep_its: the iteration count that refreshes the kept blocks.
        forcing: the Krylov solve may stop at a residual given block by block (inexact Newton,
            ``NewtonOptions.krylov_forcing``): the rows are weighted by the inverse of their
            block's allowed residual and the solve stops when the weighted residual's norm is
            below 1. Needs a right-preconditioned Krylov method (its residual norm is the true
            one) and a preconditioner built from the weighted matrix itself (not a field split,
            whose blocks come from the fixed-stress matrix).
        out_of_core: MUMPS writes the factors to files in a folder of their own per rank
            (:class:`~pilegroup.solver.mumps.OutOfCoreFolder`), removed when the solver closes.
    """

    name: str
    options: Mapping[str, Any]
    fieldsplit: bool = False
    splits: tuple[str, ...] = ("u", "p")
    band_layers: int = 0
    fixed_stress: bool = False
    reuse_factor_its: int = 0
    fallback: str | None = None
    keep_blocks: tuple[str, ...] = ()
    keep_its: int = 0
    forcing: bool = False
    out_of_core: bool = False


PRESETS: dict[str, Preset] = {
    "direct": Preset(
        "direct",
        {
            "ksp_type": "preonly",
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
            "mat_mumps_icntl_14": 80,  # workspace increase, percent
        },
    ),
    # MUMPS LU kept across Newton iterations and steps as FGMRES's preconditioner; block
    # low-rank and single precision (docs/solver.md, "Linear solvers"; docs/benchmarks.md).
    "direct_reuse": Preset(
        "direct_reuse",
        {
            "ksp_type": "fgmres",  # right-preconditioned: the true residual (inexact Newton)
            "ksp_rtol": 1e-10,
            "ksp_atol": 1e-14,
            "ksp_max_it": 60,
            "ksp_gmres_restart": 60,
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
            "mat_mumps_icntl_14": 80,
            "mat_mumps_icntl_35": 2,  # BLR factorisation, compressed factors used in the solve
            "mat_mumps_cntl_7": 1e-6,  # BLR dropping tolerance (relative)
            "mat_mumps_icntl_37": 0,  # contribution blocks not compressed (faster)
            "pc_precision": "single",  # MUMPS factorises and solves in single precision
        },
        reuse_factor_its=20,
        fallback="direct_reuse_double",
        forcing=True,
    ),
    "fieldsplit_gamg": Preset(
        "fieldsplit_gamg",
        {
            "ksp_type": "fgmres",
            "ksp_rtol": 1e-10,
            "ksp_atol": 1e-14,
            "ksp_max_it": 400,
            "ksp_gmres_restart": 100,
            "pc_type": "fieldsplit",
            "pc_fieldsplit_type": "multiplicative",
            "fieldsplit_u_ksp_type": "preonly",
            "fieldsplit_u_pc_type": "gamg",
            "fieldsplit_u_pc_gamg_threshold": 0.02,
            "fieldsplit_u_pc_gamg_square_graph": 1,
            "fieldsplit_u_mg_levels_ksp_type": "chebyshev",
            "fieldsplit_u_mg_levels_pc_type": "jacobi",
            "fieldsplit_u_mg_levels_ksp_max_it": 3,
            "fieldsplit_p_ksp_type": "preonly",
            "fieldsplit_p_pc_type": "sor",
        },
        fieldsplit=True,
        fixed_stress=True,
        fallback="direct_reuse",
    ),
    "fieldsplit_pier": Preset(
        "fieldsplit_pier",
        {
            "ksp_type": "fgmres",
            "ksp_rtol": 1e-8,
            "ksp_atol": 1e-14,
            "ksp_max_it": 150,
            "ksp_gmres_restart": 150,
            "pc_type": "fieldsplit",
            "pc_fieldsplit_type": "multiplicative",
            **{f"fieldsplit_{b}_{k}": v for b in ("p", "structure") for k, v in (
                ("ksp_type", "preonly"), ("pc_type", "lu"),
                ("pc_factor_mat_solver_type", "mumps"), ("mat_mumps_icntl_14", 80),
                ("pc_precision", "single"))},
            "fieldsplit_soil_ksp_type": "preonly",
            "fieldsplit_soil_pc_type": "gamg",
            "fieldsplit_soil_pc_gamg_threshold": 0.02,
            "fieldsplit_soil_pc_gamg_agg_nsmooths": 0,
            "fieldsplit_soil_mg_levels_ksp_type": "chebyshev",
            "fieldsplit_soil_mg_levels_pc_type": "sor",
            "fieldsplit_soil_mg_levels_ksp_max_it": 4,
            "fieldsplit_soil_mg_levels_pc_sor_its": 2,  # two sweeps per smoothing step
        },
        fieldsplit=True,
        splits=("p", "structure", "soil"),
        band_layers=2,
        fixed_stress=True,
        fallback="direct_reuse",
    ),
}
# the kept LU with its factors written uncompressed to files (icntl_35 = 3; compressed, MUMPS
# kept them in memory), read back by every solve: docs/solver.md, docs/benchmarks.md
PRESETS["direct_reuse_ooc"] = dataclasses.replace(
    PRESETS["direct_reuse"], name="direct_reuse_ooc", fallback="direct_reuse_ooc_double",
    out_of_core=True, options={**PRESETS["direct_reuse"].options, "mat_mumps_icntl_22": 1,
                               "mat_mumps_icntl_35": 3})
for _lu in ("direct_reuse", "direct_reuse_ooc"):  # their fallbacks: the same LU in double
    PRESETS[f"{_lu}_double"] = dataclasses.replace(
        PRESETS[_lu], name=f"{_lu}_double", fallback=None,
        options={**PRESETS[_lu].options, "pc_precision": "double"})
PRESETS["fieldsplit_kept"] = dataclasses.replace(
    PRESETS["fieldsplit_pier"], name="fieldsplit_kept", keep_blocks=("structure",), keep_its=60)

#: A step whose dt differs from the kept LU's by this factor (either way) refactors at its
#: first solve: the Jacobian's flow block scales with dt (docs/solver.md, "Linear solvers").
REFACTOR_DT_RATIO = 8.0


def dt_ratio(a: float, b: float) -> float:
    """``max(a / b, b / a)`` of two step sizes (1 when either is 0)."""
    return 1.0 if a <= 0.0 or b <= 0.0 else max(a / b, b / a)


#: ``(name, index set, near-nullspace or None)`` of every block of a field split.
Splits = list[tuple[str, PETSc.IS, PETSc.NullSpace | None]]


def get_preset(name: str) -> Preset:
    """Return the preset ``name`` (error lists the known names)."""
    try:
        return PRESETS[name]
    except KeyError:
        raise SolverInputError(
            f"linear solver preset = {name!r}; allowed: {sorted(PRESETS)}"
        ) from None


def merged_options(name: str, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Options of preset ``name`` updated by ``overrides`` (keys without prefix).

    Single-precision MUMPS factorisations (``[<block>_]pc_precision = single``) become double
    ones, with one warning line, where the PETSc build's MUMPS has no single precision.
    """
    opts = dict(get_preset(name).options)
    opts.update(dict(overrides or {}))
    single = [k for k in opts if k.endswith("pc_precision") and f"{opts[k]}".lower() == "single"]
    if single and not mumps_single_precision():
        opts.update(dict.fromkeys(single, "double"))
    return opts


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
    opts = PETSc.Options()
    # a clean slate: options an earlier problem of this process left under the prefix (another
    # preset's blocks, its overrides) must not reach this one
    for key in list(opts.getAll()):
        if key.startswith(prefix):
            opts.delValue(key)
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
