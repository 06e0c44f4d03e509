"""pilegroup.model: the scenario — typed, validated input data, TOML loading, units.

Imports neither dolfinx nor gmsh; from ``pilegroup.constitutive`` only the pure formula of
Eq. 17 (:mod:`pilegroup.constitutive.paper`). The error classes are defined in
:mod:`pilegroup.errors`; the ones users of the model meet are re-exported here.
"""

from pilegroup.errors import ConvergenceError, PilegroupError, ScenarioError
from pilegroup.model.analysis import (
    InterfaceOptions,
    LinearSolver,
    MeshOptions,
    Numerics,
    Outputs,
    Soil,
    Time,
    TimeStepping,
)
from pilegroup.model.loader import BUNDLED, bundled_text, load_scenario, scenario_from_dict
from pilegroup.model.piles import Installation, LayoutPile, Piles
from pilegroup.model.reference import Reference
from pilegroup.model.scenario import Scenario
from pilegroup.model.site import Cap, InterfaceParams, Layer, Site, Structure
from pilegroup.model.stages import Stage

__all__ = [
    "BUNDLED", "Cap", "ConvergenceError", "Installation", "InterfaceOptions", "InterfaceParams",
    "Layer",
    "LayoutPile", "LinearSolver", "MeshOptions", "Numerics", "Outputs", "PilegroupError", "Piles",
    "Reference", "Scenario", "ScenarioError", "Site", "Soil", "Stage", "Structure", "Time",
    "TimeStepping",
    "bundled_text", "load_scenario", "scenario_from_dict",
]
