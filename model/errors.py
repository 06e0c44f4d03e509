"""Domain exceptions of pilegroup (the one module that defines them)."""

from __future__ import annotations

import math
from typing import Any


class PilegroupError(Exception):
    """Base class of every error pilegroup raises on purpose."""


class ScenarioError(PilegroupError, ValueError):
    """A scenario file or value is invalid.

    The message always names the key (dotted path as in the TOML file), the value, its unit and
    what is allowed, e.g. ``layers[2].nu = 0.55 (-): must be in (0, 0.5)``.
    """

    def __init__(self, key: str, value: Any, allowed: str, unit: str = "") -> None:
        self.key = key
        self.value = value
        self.allowed = allowed
        self.unit = unit
        shown = repr(value) if isinstance(value, str) else value
        unit_txt = f" ({unit})" if unit else ""
        super().__init__(f"{key} = {shown}{unit_txt}: {allowed}")


def require_finite(key: str, value: Any, unit: str = "") -> None:
    """Raise :class:`ScenarioError` unless ``value`` is a finite real number."""
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ScenarioError(key, value, "must be a finite number", unit)


def require_positive(key: str, value: Any, unit: str = "") -> None:
    """Raise :class:`ScenarioError` unless ``value`` is a finite number > 0."""
    require_finite(key, value, unit)
    if value <= 0.0:
        raise ScenarioError(key, value, "must be a finite number > 0", unit)


def require_non_negative(key: str, value: Any, unit: str = "") -> None:
    """Raise :class:`ScenarioError` unless ``value`` is a finite number >= 0."""
    require_finite(key, value, unit)
    if value < 0.0:
        raise ScenarioError(key, value, "must be a finite number >= 0", unit)


class SolverError(PilegroupError, RuntimeError):
    """Base class of the solver's errors (a run failed: the CLI exits with code 1)."""


class SolverInputError(SolverError, ValueError):
    """An input of the solver is invalid; the message names the field, value, unit and range."""


class ConvergenceError(SolverError):
    """Newton or the linear solver failed (diverged, NaN, iteration limit)."""


class StepFailure(SolverError):
    """The adaptive stepper could not complete a step even at the minimum step size."""
