"""What the stepper did: the accepted steps and the rejected attempts of a run.

Data only, below the stepper (:mod:`pilegroup.solver.stepping`, which writes it) and the exports
(:mod:`pilegroup.solver.exports`, whose run summary reads it).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any


@dataclass
class StepRecord:
    """One accepted step."""

    stage: str
    t: float
    dt: float
    load_factor: float
    newton_its: int
    ksp_its: int
    seconds: float
    ksp_max: int = 0  # Krylov iterations of the step's hardest Newton solve


@dataclass
class RunLog:
    """Everything the stepper did: accepted steps and rejected attempts."""

    steps: list[StepRecord] = field(default_factory=list)
    rejected: int = 0
    alternate: int = 0
    """Steps accepted by Newton's alternate tolerance (``solver.newton``)."""
    geostatic_max_u: float | None = None
    wall_s: float = 0.0
    capacity_end: dict[str, Any] | None = None
    """How a capacity stage ended (``solver.stepping``): ``reason`` (``no equilibrium``,
    ``stopped`` or ``max load``), ``t_day``, ``load_factor`` of the last equilibrium,
    ``failed_load_factor`` (the step that found none, when the stepper gave up) and ``message``."""

    @property
    def newton_total(self) -> int:
        """Newton iterations of the accepted steps."""
        return sum(s.newton_its for s in self.steps)
