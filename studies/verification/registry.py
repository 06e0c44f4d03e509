"""The registry of verification cases and their common result type.

A case is a function ``case(size="fast", **options) -> CaseResult`` that registers itself
with :func:`register` under its command-line name. The package ``__init__`` imports the case
modules, so :data:`CASES` lists every case in the order the modules are imported; this module
imports none of them.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass, field
from typing import Any

__all__ = ["CASES", "CaseResult", "case_names", "register", "run_case"]

#: Options every case accepts as keyword arguments (besides ``size``).
DEFAULT_OPTIONS = ("pair", "preset")
#: Options of the interface cases: also the interface quadrature.
INTERFACE_OPTIONS = (*DEFAULT_OPTIONS, "quadrature")


@dataclass
class CaseResult:
    """Outcome of one verification case (``error`` and ``tolerance`` are relative)."""

    case: str
    error: float
    tolerance: float
    passed: bool
    wall_s: float
    dofs: int
    newton_its: int = 0
    steps: int = 0
    reference: str = ""
    details: dict[str, Any] = field(default_factory=dict)

    def line(self) -> str:
        """One human-readable line."""
        flag = "PASS" if self.passed else "FAIL"
        return (f"{self.case:<10} {flag}  error {self.error:.3e}  tol {self.tolerance:.1e}  "
                f"dofs {self.dofs}  steps {self.steps}  newton {self.newton_its}  "
                f"wall {self.wall_s:.2f} s")


type CaseFunction = Callable[..., CaseResult]

#: Registered cases by name, in registration order.
CASES: dict[str, CaseFunction] = {}
_OPTIONS: dict[str, frozenset[str]] = {}


def register[F: CaseFunction](name: str, options: Iterable[str] = DEFAULT_OPTIONS
                              ) -> Callable[[F], F]:
    """Decorator registering a case function under ``name``.

    ``options`` names the overrides of :func:`run_case` that the case takes as keyword
    arguments (``pair``, ``preset``, ``quadrature``); the others are not passed to it.
    """

    def decorate(fn: F) -> F:
        if name in CASES:
            raise ValueError(f"verification case {name!r} is registered twice")
        CASES[name] = fn
        _OPTIONS[name] = frozenset(options)
        return fn

    return decorate


def case_names(names: Sequence[str] | None = None) -> list[str]:
    """The names to run: ``names``, or every registered case when empty.

    Raises:
        KeyError: a name is not registered (the message lists the known ones).
    """
    names = list(names or CASES)
    unknown = [n for n in names if n not in CASES]
    if unknown:
        raise KeyError(f"unknown verification case(s) {unknown}; known: {sorted(CASES)}")
    return names


def run_case(name: str, size: str = "fast", **overrides: str | None) -> CaseResult:
    """Run case ``name`` with the ``overrides`` it accepts that are not ``None``."""
    accepted = _OPTIONS[name]
    kw = {k: v for k, v in overrides.items() if v is not None and k in accepted}
    return CASES[name](size=size, **kw)
