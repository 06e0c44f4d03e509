"""What the MUMPS factorisations need beyond their options: precision check, out-of-core folder.

* :func:`mumps_single_precision`: whether this PETSc's MUMPS factorises in single precision (a
  1 x 1 trial, once per process).
* :class:`OutOfCoreFolder`: the folder of one rank's out-of-core factor files. With
  ``mat_mumps_icntl_22 = 1`` MUMPS writes the factors to files while it factorises and reads
  them back in every solve, so a rank's resident memory holds only the active fronts (Pier 667,
  full model, h = 0.3 m: 3.4 GB on the larger rank instead of 5.3 GB; docs/benchmarks.md, "Out
  of core when memory is short"). The files of one factorisation take about 4 bytes per entry
  of the factors (5.6 GB there): the folder is made under the temporary directory (``TMPDIR``,
  or ``mat_mumps_ooc_tmpdir`` when the options give one) and removed with everything in it
  when the solver is closed, and at interpreter exit if it was not. After a failure the files
  are emptied at once (:meth:`OutOfCoreFolder.empty`): a failure on one rank ends the job by
  ``MPI_Abort``, which runs no exit handler, and leaves only the empty folder.
"""

from __future__ import annotations

import functools
import logging
import os
import shutil
import tempfile
import weakref
from pathlib import Path

from petsc4py import PETSc

from pilegroup.errors import SolverInputError

log = logging.getLogger(__name__)

#: The option that names MUMPS's out-of-core folder (without prefix).
OOC_FOLDER_OPTION = "mat_mumps_ooc_tmpdir"


@functools.cache
def mumps_single_precision() -> bool:
    """Whether this PETSc's MUMPS factorises in single precision (a 1 x 1 trial, once)."""
    A = PETSc.Mat().createAIJ([1, 1], nnz=1, comm=PETSc.COMM_SELF)
    A.setValue(0, 0, 2.0)
    A.assemble()
    ksp = PETSc.KSP().create(PETSc.COMM_SELF)
    prefix, opts = "pilegroup_precision_trial_", PETSc.Options()
    opts[f"{prefix}pc_precision"] = "single"
    try:
        ksp.setOptionsPrefix(prefix)
        ksp.setOperators(A)
        ksp.setType("preonly")
        ksp.getPC().setType("lu")
        ksp.getPC().setFactorSolverType("mumps")
        ksp.setFromOptions()
        ksp.setUp()
        ok = True
    except PETSc.Error:
        ok = False
        log.warning("this PETSc's MUMPS has no single precision: MUMPS factorisations asked "
                    "for in single precision (direct_reuse, the field splits' LU blocks) are "
                    "made in double (docs/solver.md)")
    finally:
        opts.delValue(f"{prefix}pc_precision")
        ksp.destroy()
        A.destroy()
    return ok


class OutOfCoreFolder:
    """A fresh folder for this rank's out-of-core factor files, removed by :meth:`remove`.

    Args:
        parent: where to make it (``None``: the temporary directory, ``TMPDIR``).

    Raises:
        SolverInputError: ``parent`` is not a writable folder.
    """

    def __init__(self, parent: str | Path | None = None) -> None:
        try:
            self.path = Path(tempfile.mkdtemp(prefix="pilegroup-ooc-", dir=parent))
        except OSError as exc:
            where = parent if parent is not None else tempfile.gettempdir()
            raise SolverInputError(
                f"numerics.solver.options.{OOC_FOLDER_OPTION} = {str(where)!r}: no folder for "
                f"the out-of-core factors can be made there ({exc.strerror}); allowed: a "
                "writable folder with room for the factors (docs/solver.md)") from None
        self._finalizer = weakref.finalize(self, shutil.rmtree, self.path, ignore_errors=True)

    def empty(self) -> None:
        """Cut every file in the folder to zero bytes (their space freed, their names kept)."""
        for f in self.path.iterdir():
            os.truncate(f, 0)

    def remove(self) -> None:
        """Remove the folder and the factor files in it (once; later calls do nothing)."""
        self._finalizer()

    @property
    def removed(self) -> bool:
        """Whether the folder has been removed."""
        return not self._finalizer.alive


__all__ = ["OOC_FOLDER_OPTION", "OutOfCoreFolder", "mumps_single_precision"]
