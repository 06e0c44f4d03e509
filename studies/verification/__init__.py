"""Verification cases: the real pipeline against closed-form solutions.

Each case meshes a column, block or single pile, runs a :class:`~pilegroup.solver.BiotProblem`
through :func:`~pilegroup.solver.run_stages` and returns a :class:`CaseResult` with its error,
the tolerance and the source of the reference. Modules:

* ``registry``: :class:`CaseResult`, the :func:`register` decorator and :data:`CASES`;
* ``common``: communicator, point evaluation, box boundary conditions, small meshes and the
  problem builders the cases share;
* ``consolidation``: ``terzaghi``, ``terzaghi-water-table``, ``mandel`` (with their closed
  forms; the first-step check);
* ``soil``: ``triaxial`` (and the strip-footing measurements);
* ``interface_cases``: ``shaft-capacity``, ``interface-patch``, ``tied-limit``;
* ``ground_cases``: ``consolidation-surcharge`` (ground that moves);
* ``downdrag_cases``: ``downdrag-end-bearing``, ``downdrag-floating`` (the whole run pipeline);
* ``radial_cases``: ``radial-consolidation`` (installation pore pressures, the whole run
  pipeline);
* ``lateral_cases``: ``lateral-single-pile``, ``cap-equilibrium``, ``rigid-cap-moment`` (cap
  actions, the whole run pipeline);
* ``capacity_cases``: ``pile-capacity`` (a capacity stage, shaft plus toe, the whole run
  pipeline);
* ``undrained_cases``: ``undrained-loading`` (a uniform fill, undrained, on the meshes of
  bundled and random layouts, the whole run pipeline);
* ``soft_soil_cases``: ``mcc-undrained-triaxial``, ``mcc-compression-line``, ``ssc-creep``
  (Modified Cam Clay and Soft Soil Creep at one material point against closed forms) and
  ``ssc-oedometer`` (a Soft Soil Creep column through the solver against the 1D reference of
  ``soft_soil_column``);
* ``runner``: :func:`run_cases` and :func:`main`
  (``python -m pilegroup.studies.verification [CASE ...] [--size fast|bench] [--json]``,
  also under ``mpirun -n 2``; ``pilegroup verify``).
"""

# The case modules register their cases when imported: this order is the order in which
# ``pilegroup verify`` runs and lists them.
# isort: off
from pilegroup.studies.verification import (  # noqa: F401
    consolidation,
    soil_cases,
    interface_cases,
    ground_cases,
    downdrag_cases,
    radial_cases,
    lateral_cases,
    capacity_cases,
    undrained_cases,
    soft_soil_cases,
)
# isort: on

from pilegroup.studies.verification.common import eval_points, shaft_profile_oscillation
from pilegroup.studies.verification.consolidation import (
    first_step_oscillation,
    mandel,
    mandel_centre_pressure,
    oscillation_measure,
    terzaghi,
    terzaghi_degree,
    terzaghi_series,
    terzaghi_water_table,
)
from pilegroup.studies.verification.interface_cases import (
    interface_patch,
    shaft_capacity,
    tied_limit,
)
from pilegroup.studies.verification.registry import CASES, CaseResult, register
from pilegroup.studies.verification.runner import main, run_cases
from pilegroup.studies.verification.soil_cases import (
    footing_undrained_roughness,
    strip_footing,
    triaxial,
)

__all__ = ["CASES", "CaseResult", "eval_points", "first_step_oscillation",
           "footing_undrained_roughness", "interface_patch", "main", "mandel",
           "mandel_centre_pressure",
           "oscillation_measure", "register", "run_cases", "shaft_capacity",
           "shaft_profile_oscillation", "strip_footing", "terzaghi", "terzaghi_degree",
           "terzaghi_series", "terzaghi_water_table", "tied_limit", "triaxial"]
