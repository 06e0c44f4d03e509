"""pilegroup.model: the scenario — typed, validated input data, TOML loading, units.

Imports neither dolfinx nor gmsh.
"""

from pilegroup.model.errors import ConvergenceError, PilegroupError, ScenarioError
from pilegroup.model.loader import BUNDLED, bundled_text, load_scenario, scenario_from_dict
from pilegroup.model.scenario import (
    Cap,
    InterfaceOptions,
    InterfaceParams,
    Layer,
    LinearSolver,
    MeshOptions,
    Numerics,
    Outputs,
    Piles,
    Scenario,
    Site,
    Soil,
    Stage,
    Structure,
    Time,
    TimeStepping,
)

__all__ = [
    "BUNDLED", "Cap", "ConvergenceError", "InterfaceOptions", "InterfaceParams", "Layer",
    "LinearSolver", "MeshOptions", "Numerics", "Outputs", "PilegroupError", "Piles", "Scenario",
    "ScenarioError", "Site", "Soil", "Stage", "Structure", "Time", "TimeStepping",
    "bundled_text", "load_scenario", "scenario_from_dict",
]
