"""pilegroup.solver: u–p Biot consolidation with quadrature-point soil state.

Build a :class:`BiotProblem` from a ``MeshData``, materials per cell group, boundary conditions
and loads; run :func:`run_stages` over a list of :class:`SolverStage` with :class:`StepControl`.
Units kN, m, day; tension positive; ``p`` = excess pore pressure (compression positive).
"""

from pilegroup.errors import (
    ConvergenceError,
    LinearSolveError,
    SolverError,
    SolverInputError,
    StepFailure,
)
from pilegroup.solver.exports import (
    Export,
    SummaryWriter,
    XDMFSeries,
    run_summary,
)
from pilegroup.solver.inputs import (
    GAMMA_W,
    K_WATER,
    Discretisation,
    DisplacementBC,
    ElasticSolid,
    FaceAction,
    InstallationExcess,
    InterfaceCoupling,
    NewtonOptions,
    PressureBC,
    RigidPlate,
    SoilMaterial,
    SolverOptions,
    SolverStage,
    StepControl,
    SurfaceLoad,
)
from pilegroup.solver.layout import eps_mandel
from pilegroup.solver.linsolve import PRESETS, Preset, merged_options
from pilegroup.solver.problem import BiotProblem
from pilegroup.solver.runlog import RunLog, StepRecord
from pilegroup.solver.step_protocol import StepInfo
from pilegroup.solver.stepping import AdaptiveStepper, RunState, run_stages

__all__ = [
    "GAMMA_W",
    "K_WATER",
    "PRESETS",
    "AdaptiveStepper",
    "BiotProblem",
    "ConvergenceError",
    "LinearSolveError",
    "Discretisation",
    "DisplacementBC",
    "ElasticSolid",
    "Export",
    "InstallationExcess",
    "InterfaceCoupling",
    "NewtonOptions",
    "Preset",
    "PressureBC",
    "RigidPlate",
    "RunLog",
    "RunState",
    "SoilMaterial",
    "SolverError",
    "SolverInputError",
    "SolverOptions",
    "SolverStage",
    "StepFailure",
    "StepInfo",
    "StepRecord",
    "SummaryWriter",
    "FaceAction", "SurfaceLoad",
    "StepControl",
    "XDMFSeries",
    "eps_mandel",
    "merged_options",
    "run_stages",
    "run_summary",
]
