"""The state of a :class:`~pilegroup.solver.problem.BiotProblem` as arrays, and back.

What a checkpoint needs to continue a run exactly (at a step boundary, where every field
equals its committed value): the committed fields of every block, every material group's law
state at its quadrature points, the interface state (law state per point and the committed
jump), the rigid plate's displacement, Newton's residual references of the run, the load
factor, and the linear solver's preset (after a fallback), notes and counters. The arrays are
this rank's local ones (owned and ghost entries), so they fit the same mesh partition only:
:func:`partition_fingerprint` identifies it. A kept LU factorisation (presets that reuse one)
is not part of the state: the first solve after a restore factors the current matrix.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np
from mpi4py import MPI

from pilegroup.errors import SolverInputError

if TYPE_CHECKING:
    from pilegroup.solver.problem import BiotProblem


def problem_state(pb: BiotProblem) -> dict[str, np.ndarray]:
    """The state of ``pb`` on this rank as named arrays (see the module docstring)."""
    out: dict[str, np.ndarray] = {}
    for i, f in enumerate(pb.layout.fields_n):
        out[f"field/{i}"] = f.x.array.copy()
    for b in pb.bodies:
        out.update({f"qp/{b.name}/{k}": v for k, v in b.qp.saved_state().items()})
    if pb.interface is not None:
        out.update({f"interface/{k}": v for k, v in pb.interface.saved_state().items()})
    if pb.plate is not None:
        out["plate"] = np.array([pb.plate.value, pb.plate.committed])
    ls = pb.linear_solver
    out["newton/R_run"] = pb.newton.R_run.copy()
    out["load_factor"] = np.array(pb.load_factor)
    out["linear/preset"] = np.array(ls.preset)
    out["linear/fallbacks"] = np.array(ls.fallbacks, dtype=str)
    out["linear/refactorisations"] = np.array(ls.refactorisations)
    out["timings"] = np.array([pb.timings[k] for k in sorted(pb.timings)])
    return out


def _part(arrays: Mapping[str, np.ndarray], prefix: str) -> dict[str, np.ndarray]:
    """The arrays under ``prefix/``, with the prefix removed."""
    return {k[len(prefix) + 1:]: v for k, v in arrays.items() if k.startswith(prefix + "/")}


def restore_problem_state(pb: BiotProblem, arrays: Mapping[str, np.ndarray]) -> None:
    """Set ``pb`` to the state of :func:`problem_state` (same mesh partition, same ranks).

    Raises :class:`~pilegroup.errors.SolverInputError` when an array does not fit.
    """
    try:
        for i, (f, fn) in enumerate(zip(pb.layout.fields, pb.layout.fields_n, strict=True)):
            a = arrays[f"field/{i}"]
            if a.shape != f.x.array.shape:
                raise ValueError(f"field {i}: {a.size} saved local values, "
                                 f"{f.x.array.size} on this rank")
            f.x.array[:] = a
            fn.x.array[:] = a
        for b in pb.bodies:
            b.qp.restore_state(_part(arrays, f"qp/{b.name}"))
        if pb.interface is not None:
            pb.interface.restore_state(_part(arrays, "interface"))
    except (KeyError, ValueError) as exc:
        raise SolverInputError(f"saved state does not fit this problem on this rank: {exc}") \
            from exc
    if pb.plate is not None:
        pb.plate.set(float(arrays["plate"][0]))
        pb.plate.committed = float(arrays["plate"][1])
    pb.newton.R_run[:] = arrays["newton/R_run"]
    pb.load_factor = float(arrays["load_factor"])
    pb.linear_solver.restore(str(arrays["linear/preset"]),
                             [str(s) for s in arrays["linear/fallbacks"]],
                             int(arrays["linear/refactorisations"]))
    for k, v in zip(sorted(pb.timings), arrays["timings"], strict=True):
        pb.timings[k] = float(v)


def partition_fingerprint(pb: BiotProblem) -> str:
    """SHA-256 of this rank's mesh and dof numbering: geometry, cells, every field's dofmap.

    Equal fingerprints on every rank mean that local arrays of one run fit the other.
    """
    h = hashlib.sha256()
    msh = pb.mesh
    for a in (msh.geometry.x, *msh.geometry.dofmaps):
        h.update(np.ascontiguousarray(a).tobytes())
    for f in pb.layout.fields:
        imap = f.function_space.dofmap.index_map
        h.update(np.array([imap.size_local, imap.num_ghosts, imap.size_global]).tobytes())
        h.update(np.ascontiguousarray(f.function_space.dofmap.list).tobytes())
    return h.hexdigest()


def check_same_partition(pb: BiotProblem, fingerprints: list[str]) -> bool:
    """Whether every rank's :func:`partition_fingerprint` equals ``fingerprints[rank]``.

    Collective; the same answer on every rank.
    """
    comm = pb.comm
    if len(fingerprints) != comm.size:
        raise SolverInputError(f"{len(fingerprints)} saved partitions for {comm.size} ranks")
    ok = partition_fingerprint(pb) == fingerprints[comm.rank]
    return bool(comm.allreduce(ok, op=MPI.LAND))
