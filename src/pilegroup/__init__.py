"""pilegroup: pile groups in layered soft soil over time (FEniCSx, gmsh, PETSc).

Sub-packages (data flows one way): ``model`` -> ``geometry`` -> ``solver`` (using
``constitutive``) -> ``studies``. Internal units: kN, m, day; tension positive.
"""

import importlib.util as _ilu
import os as _os

# Under MPI every rank is one core's worth of work: BLAS threads inside each rank (OpenBLAS
# starts a pool at load time) would oversubscribe the cores. Measured on the Pier 667 Jacobian
# (274,180 unknowns, MUMPS LU, 2 ranks on 2 cores): 76.5 s with the default pool, 62.8 s with
# one thread per rank. Set before the PETSc/BLAS libraries load; an explicit value is kept.
if int(_os.environ.get("PMI_SIZE") or _os.environ.get("OMPI_COMM_WORLD_SIZE") or 1) > 1:
    _os.environ.setdefault("OMP_NUM_THREADS", "1")

# The PyPI wheel of DOLFINx (dolfinx-solver-real) must be imported before dolfinx/petsc4py:
# it orders mpi4py ahead of the compiled bindings. This is the only place that does it, and
# every pilegroup module is imported after this one. The Debian route has no such module.
if _ilu.find_spec("dolfinx_solver") is not None:
    import dolfinx_solver  # noqa: F401

__version__ = "0.1.0"
