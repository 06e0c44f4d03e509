"""pilegroup: pile groups in layered soft soil over time (FEniCSx, gmsh, PETSc).

Sub-packages (data flows one way): ``model`` -> ``geometry`` -> ``solver`` (using
``constitutive``) -> ``studies``. Internal units: kN, m, day; tension positive.
"""

import importlib.util as _ilu
import os as _os

# One BLAS thread per process, serial or under MPI, unless OMP_NUM_THREADS (or OpenBLAS's own
# OPENBLAS_NUM_THREADS) says otherwise; set before the PETSc/BLAS libraries load, which size
# their thread pool then. Under MPI every rank is one core's worth of work: threads inside
# each rank oversubscribe the cores (Pier 667 Jacobian, MUMPS LU, 2 ranks on 2 cores: 76.5 s
# with the default pool, 62.8 s with one thread per rank). Serial, Debian's PETSc calls a
# threaded OpenBLAS: single_pile's solves took 13-15 s with one thread against 78-105 s with
# two on a busy two-core machine; the PyPI wheel's PETSc BLAS is single-threaded, and the
# thread count made no difference there (docs/solver.md, "BLAS threads").
_os.environ.setdefault("OMP_NUM_THREADS", "1")

# Without a display, VTK's figures are drawn with EGL (or OSMesa) from the start instead of after
# a failed X try that prints a warning nobody can act on (pilegroup.offscreen).
from pilegroup.offscreen import choose_offscreen_window as _choose_offscreen_window  # noqa: E402

_choose_offscreen_window()

# The PyPI wheel of DOLFINx (dolfinx-solver-real) must be imported before dolfinx/petsc4py:
# it orders mpi4py ahead of the compiled bindings. This is the only place that does it, and
# every pilegroup module is imported after this one. The Debian route has no such module.
if _ilu.find_spec("dolfinx_solver") is not None:
    import dolfinx_solver  # noqa: F401

__version__ = "0.1.0"
