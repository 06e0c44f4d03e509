"""The linear-solver presets: named PETSc option sets as data (docs/solver.md).

:class:`Preset` describes one; :data:`PRESETS` holds them by name; :func:`merged_options` gives
a preset's options with a scenario's overrides; :func:`missing_packages` names what a preset
needs that this PETSc lacks (the hypre presets need hypre: PyPI's PETSc has none, Debian's and
most clusters' builds have it). :mod:`pilegroup.solver.linsolve` builds the KSP from them.

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
* ``fieldsplit_hypre`` (needs hypre): ``fieldsplit_kept`` with one BoomerAMG V-cycle on the
  pressure and on the soil (systems AMG, unknown by unknown) and a band of two cell layers.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

from petsc4py import PETSc

from pilegroup.errors import PresetUnavailable, SolverInputError
from pilegroup.solver.mumps import mumps_single_precision


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
        band_width_m: the band's width in metres: a run turns it into cell layers at its pile
            mesh size (``SolverOptions.band_layers``), as the iterations of a GAMG soil block
            follow the band's width, not its layer count; ``None``: ``band_layers`` at every
            size.
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
        requires: the PETSc external packages the preset needs (``"hypre"``): a preset this
            PETSc cannot run is refused before meshing (:func:`check_available`) and never
            chosen by ``auto``.
        out_of_core: MUMPS writes the factors to files in a folder of their own per rank
            (:class:`~pilegroup.solver.mumps.OutOfCoreFolder`), removed when the solver closes.
    """

    name: str
    options: Mapping[str, Any]
    fieldsplit: bool = False
    splits: tuple[str, ...] = ("u", "p")
    band_layers: int = 0
    band_width_m: float | None = None
    fixed_stress: bool = False
    reuse_factor_its: int = 0
    fallback: str | None = None
    keep_blocks: tuple[str, ...] = ()
    keep_its: int = 0
    forcing: bool = False
    out_of_core: bool = False
    requires: tuple[str, ...] = ()


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
        band_width_m=2.0,
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


def _boomeramg(block: str, threshold: float) -> dict[str, Any]:
    """One BoomerAMG V-cycle (hypre) as the preconditioner of field-split block ``block``.

    HMIS coarsening with extended+i interpolation and l1-scaled hybrid Gauss–Seidel, the
    combination hypre recommends for 3D problems in parallel; a displacement block (block size
    3) is coarsened unknown by unknown (``nodal_coarsen`` 0: hypre's systems AMG, each
    component interpolated from its own). ``threshold``: strength of connection.
    """
    opts: dict[str, Any] = {
        "ksp_type": "preonly", "pc_type": "hypre", "pc_hypre_type": "boomeramg",
        "pc_hypre_boomeramg_max_iter": 1,
        "pc_hypre_boomeramg_coarsen_type": "HMIS",
        "pc_hypre_boomeramg_interp_type": "ext+i",
        "pc_hypre_boomeramg_strong_threshold": threshold,
        "pc_hypre_boomeramg_relax_type_all": "l1scaled-SOR/Jacobi",
    }
    return {f"fieldsplit_{block}_{k}": v for k, v in opts.items()}


# fieldsplit_kept with BoomerAMG on the pressure and the soil, a band of two cell layers at any
# mesh size (docs/solver.md)
PRESETS["fieldsplit_hypre"] = dataclasses.replace(
    PRESETS["fieldsplit_kept"], name="fieldsplit_hypre", band_width_m=None, requires=("hypre",),
    options={**{k: v for k, v in PRESETS["fieldsplit_kept"].options.items()
                if not k.startswith(("fieldsplit_soil_", "fieldsplit_p_"))},
             **_boomeramg("p", 0.5), **_boomeramg("soil", 0.7)})


@functools.cache
def has_package(package: str) -> bool:
    """Whether this PETSc was built with the external package ``package`` (e.g. hypre)."""
    return bool(PETSc.Sys.hasExternalPackage(package))


def missing_packages(name: str) -> tuple[str, ...]:
    """The packages preset ``name`` needs that this PETSc lacks (empty: it can run here)."""
    return tuple(p for p in get_preset(name).requires if not has_package(p))


def check_available(name: str, key: str = "numerics.solver.preset") -> None:
    """Raise :class:`PresetUnavailable` (one line) when this PETSc cannot run preset ``name``."""
    missing = missing_packages(name)
    if missing:
        version = ".".join(map(str, PETSc.Sys.getVersion()))
        raise PresetUnavailable(key, name, f"a preset this PETSc ({version}) can run: "
                                f"{name!r} needs a PETSc with {', '.join(missing)} (use 'auto', "
                                f"or a PETSc built with it: docs/solver.md, 'Which preset runs "
                                f"where')")


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
