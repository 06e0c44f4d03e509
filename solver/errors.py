"""Exceptions raised by :mod:`pilegroup.solver`."""

from __future__ import annotations


class SolverError(RuntimeError):
    """Base class of the solver's errors."""


class SolverInputError(SolverError, ValueError):
    """An input of the solver is invalid; the message names the field, value, unit and range."""


class ConvergenceError(SolverError):
    """Newton or the linear solver failed (diverged, NaN, iteration limit)."""


class StepFailure(SolverError):
    """The adaptive stepper could not complete a step even at the minimum step size."""
