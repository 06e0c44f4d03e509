"""Test configuration: import pilegroup before any test module.

So dolfinx_solver is imported before dolfinx/petsc4py, whatever a test module's import order.
"""

import pilegroup  # noqa: F401
