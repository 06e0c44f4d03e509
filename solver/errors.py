"""Exceptions raised by :mod:`pilegroup.solver` (defined with all others in model.errors)."""

from pilegroup.errors import ConvergenceError, SolverError, SolverInputError, StepFailure

__all__ = ["ConvergenceError", "SolverError", "SolverInputError", "StepFailure"]
