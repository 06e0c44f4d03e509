"""Linear-solver option sets as data, and the KSP built from them.

Two presets:

* ``direct``: MUMPS LU (robust, for small and medium problems; the default).
* ``fieldsplit_gamg``: FGMRES preconditioned by a block Gauss–Seidel (``multiplicative``
  field split) of the u–p system. The displacement block is solved by one GAMG V-cycle with the
  rigid-body near-nullspace; the pressure block of the preconditioning matrix carries the
  fixed-stress term ``(alpha^2/K_dr) M`` (Kim, Tchelepi & Juanes 2011; Mikelić & Wheeler 2013;
  as a preconditioner: White, Castelletto & Tchelepi 2016), so the split is the fixed-stress
  iteration used as a preconditioner. The p block (mass + dt * diffusion + fixed-stress mass)
  gets one SOR sweep: GAMG there failed (``KSP_DIVERGED_PC_FAILED``) when every pressure dof
  is fixed (drained analysis: the block is the identity), and SOR needed as few or fewer
  FGMRES iterations than GAMG on the verification cases (Terzaghi 16.6 vs 18.2, Mandel 18.3 vs
  17.2 per Newton step). For diffusion-dominated steps on large meshes override with
  ``fieldsplit_p_pc_type = "gamg"``.

Every problem has its own options prefix; after each solve the converged reason is checked and
a negative reason raises :class:`ConvergenceError`.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import ConvergenceError, SolverInputError


@dataclass(frozen=True)
class Preset:
    """A named option set.

    Attributes:
        name: preset name.
        options: PETSc options (without prefix).
        fieldsplit: the preset needs the u/p index sets and the near-nullspace.
        fixed_stress: the preset needs the fixed-stress preconditioning matrix.
        reuse_factor_its: > 0: keep the factorisation across Newton iterations and steps as
            GMRES's preconditioner; refactor after a solve needing more iterations than this.
    """

    name: str
    options: Mapping[str, Any]
    fieldsplit: bool = False
    fixed_stress: bool = False
    reuse_factor_its: int = 0


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
    # MUMPS LU reused across Newton iterations and steps as the preconditioner of GMRES on the
    # current Jacobian: one factorisation serves many solves while the tangent changes little
    # (consolidation, creep); a stale one (more than 20 iterations) is refactored.
    "direct_reuse": Preset(
        "direct_reuse",
        {
            "ksp_type": "gmres",
            "ksp_rtol": 1e-10,
            "ksp_atol": 1e-14,
            "ksp_max_it": 60,
            "ksp_gmres_restart": 60,
            "pc_type": "lu",
            "pc_factor_mat_solver_type": "mumps",
            "mat_mumps_icntl_14": 80,
        },
        reuse_factor_its=20,
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
    ),
}


def get_preset(name: str) -> Preset:
    """Return the preset ``name`` (error lists the known names)."""
    try:
        return PRESETS[name]
    except KeyError:
        raise SolverInputError(
            f"linear solver preset = {name!r}; allowed: {sorted(PRESETS)}"
        ) from None


def merged_options(name: str, overrides: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Options of preset ``name`` updated by ``overrides`` (keys without prefix)."""
    opts = dict(get_preset(name).options)
    opts.update(dict(overrides or {}))
    return opts


def create_ksp(
    comm: MPI.Comm,
    A: PETSc.Mat,
    P: PETSc.Mat | None,
    prefix: str,
    preset: str,
    overrides: Mapping[str, Any] | None = None,
    is_u: PETSc.IS | None = None,
    is_p: PETSc.IS | None = None,
    near_nullspace: PETSc.NullSpace | None = None,
) -> PETSc.KSP:
    """Create a KSP with operators ``A`` (and preconditioning matrix ``P``) from a preset.

    Args:
        comm: communicator (``mesh.comm``).
        A: system matrix (monolithic blocked PETSc AIJ).
        P: preconditioning matrix or ``None`` (uses ``A``).
        prefix: options prefix of this problem (e.g. ``"biot_"``).
        preset: preset name.
        overrides: extra options.
        is_u: displacement index set (fieldsplit presets).
        is_p: pressure index set (fieldsplit presets).
        near_nullspace: rigid-body modes of the displacement block (fieldsplit presets).
    """
    spec = get_preset(preset)
    opts = PETSc.Options()
    for k, v in merged_options(preset, overrides).items():
        opts[f"{prefix}{k}"] = v
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(A, P if P is not None else A)
    if spec.fieldsplit:
        if is_u is None or is_p is None:
            raise SolverInputError(f"preset {preset!r} needs the u and p index sets")
        if near_nullspace is not None:
            is_u.compose("nearnullspace", near_nullspace)
        pc = ksp.getPC()
        pc.setType("fieldsplit")
        pc.setFieldSplitIS(("u", is_u), ("p", is_p))
    ksp.setFromOptions()
    return ksp


def check_reason(ksp: PETSc.KSP, what: str = "linear solve") -> int:
    """Raise :class:`ConvergenceError` when the KSP diverged; return its iteration count."""
    reason = ksp.getConvergedReason()
    if reason < 0:
        raise ConvergenceError(f"{what}: KSP diverged, reason {reason}")
    return int(ksp.getIterationNumber())


class LinearSolver:
    """The problem's KSP; with a reuse preset, one LU factorisation serves many solves.

    Presets with ``reuse_factor_its`` keep the last LU factorisation as the preconditioner of
    GMRES across Newton iterations and steps (the matrix itself is always the current Jacobian,
    so Newton stays exact); a solve that needs more than ``reuse_factor_its`` iterations, or
    fails, triggers a new factorisation (and a re-solve when it failed). A factorisation made
    under another set of constraints (undrained steps release the drainage conditions) is not
    tried at all: it is refactored at once.
    """

    def __init__(self, ksp: PETSc.KSP, preset: str) -> None:
        self.ksp = ksp
        self.limit = get_preset(preset).reuse_factor_its
        self.refactorisations = 0  # LU factorisations with a reuse preset
        self._reusing = False
        self._factor_undrained: bool | None = None  # constraints of the kept factorisation

    def set_operators(self, A: PETSc.Mat, P: PETSc.Mat | None) -> None:
        """Use ``A`` (and ``P`` to precondition, else ``A``)."""
        self.ksp.setOperators(A, P if P is not None else A)

    def _set_reuse(self, reuse: bool) -> None:
        self.ksp.getPC().setReusePreconditioner(reuse)
        self._reusing = reuse

    def solve(self, rhs: PETSc.Vec, sol: PETSc.Vec, undrained: bool) -> int:
        """Solve ``A sol = rhs``; returns the Krylov iterations (raises when diverged)."""
        limit = self.limit
        if limit and self._reusing and self._factor_undrained != undrained:
            self._set_reuse(False)
        self.ksp.solve(rhs, sol)
        if limit and self.ksp.getConvergedReason() < 0 and self._reusing:
            self._set_reuse(False)  # stale factorisation: refactor and solve again
            self.ksp.solve(rhs, sol)
        its = check_reason(self.ksp, "Newton correction")
        if limit:
            if not self._reusing:
                self.refactorisations += 1
                self._factor_undrained = undrained
            self._set_reuse(its <= limit)
        return its
