"""pilegroup: pile groups in layered soft soil over time (FEniCSx, gmsh, PETSc).

Sub-packages (data flows one way): ``model`` -> ``geometry`` -> ``solver`` (using
``constitutive``) -> ``studies``. Internal units: kN, m, day; tension positive.
"""

import importlib.util as _ilu

# The PyPI wheel of DOLFINx (dolfinx-solver-real) must be imported before dolfinx/petsc4py:
# it orders mpi4py ahead of the compiled bindings. This is the only place that does it, and
# every pilegroup module is imported after this one. The Debian route has no such module.
if _ilu.find_spec("dolfinx_solver") is not None:
    import dolfinx_solver  # noqa: F401

__version__ = "0.1.0"
