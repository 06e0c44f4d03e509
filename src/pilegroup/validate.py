"""The one set of value checks shared by the scenario, the geometry, the laws and the solver.

Every check raises ``error.invalid(key, value, allowed, unit)`` (see
:meth:`pilegroup.errors.PilegroupError.invalid`), so the message has one form everywhere,
``key = value (unit): allowed``, and the class tells who rejected the value: ``ScenarioError``
(the default: scenario and geometry inputs), ``ConstitutiveError`` (law parameters) or
``SolverInputError`` (solver inputs).
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from numbers import Real

from pilegroup.errors import PilegroupError, ScenarioError

ErrorClass = type[PilegroupError]


def is_finite_number(value: object) -> bool:
    """True for a finite real number (``bool`` is not a number here)."""
    return isinstance(value, Real) and not isinstance(value, bool) and math.isfinite(value)


def require_finite(key: str, value: object, unit: str = "", *,
                   error: ErrorClass = ScenarioError) -> None:
    """Raise ``error`` unless ``value`` is a finite real number."""
    if not is_finite_number(value):
        raise error.invalid(key, value, "must be a finite number", unit)


def require_positive(key: str, value: object, unit: str = "", *,
                     error: ErrorClass = ScenarioError) -> None:
    """Raise ``error`` unless ``value`` is a finite number > 0."""
    require_finite(key, value, unit, error=error)
    if value <= 0.0:  # type: ignore[operator]
        raise error.invalid(key, value, "must be a finite number > 0", unit)


def require_non_negative(key: str, value: object, unit: str = "", *,
                         error: ErrorClass = ScenarioError) -> None:
    """Raise ``error`` unless ``value`` is a finite number >= 0."""
    require_finite(key, value, unit, error=error)
    if value < 0.0:  # type: ignore[operator]
        raise error.invalid(key, value, "must be a finite number >= 0", unit)


def require_in_range(key: str, value: object, lo: float, hi: float, unit: str = "", *,
                     lo_open: bool = False, hi_open: bool = False, why: str = "",
                     error: ErrorClass = ScenarioError) -> None:
    """Raise ``error`` unless ``value`` is a finite number in the interval from lo to hi.

    The bounds are closed unless ``lo_open`` / ``hi_open``; the message shows the interval in
    the usual notation, e.g. ``must be in [0, 60)``, followed by ``why`` (the source of the
    bounds) in parentheses when given.
    """
    ok = is_finite_number(value)
    if ok:
        ok = (value > lo if lo_open else value >= lo)  # type: ignore[operator]
        ok = ok and (value < hi if hi_open else value <= hi)  # type: ignore[operator]
    if not ok:
        interval = f"{'(' if lo_open else '['}{lo:g}, {hi:g}{')' if hi_open else ']'}"
        reason = f" ({why})" if why else ""
        raise error.invalid(key, value, f"must be in {interval}{reason}", unit)


def require_one_of(key: str, value: object, choices: Iterable[object], *,
                   error: ErrorClass = ScenarioError) -> None:
    """Raise ``error`` unless ``value`` is one of ``choices`` (listed in the message)."""
    allowed = tuple(choices)
    if value not in allowed:
        raise error.invalid(key, value, "must be one of " + ", ".join(map(repr, allowed)))


__all__ = [
    "ErrorClass", "is_finite_number", "require_finite", "require_in_range",
    "require_non_negative", "require_one_of", "require_positive",
]
