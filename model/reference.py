"""Published values a scenario is compared with: the optional ``[reference]`` table.

A run's figures and report speak of the scenario alone. Only where the scenario carries a
``[reference]`` do they set published values beside the run's: a settlement line, a total load,
the layers and the early period the publication's findings are about, the times and gauge
sections of its figures. Each value is optional; the ``source`` names where they are published.
The bundled ``pier667`` scenarios carry the values of Li et al. (2019); no other scenario does,
and nothing is drawn or written of a publication without one (docs/results.md, "Figures and
report of a run").
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pilegroup.errors import ScenarioError
from pilegroup.validate import require_finite, require_non_negative, require_positive


@dataclass(frozen=True)
class Reference:
    """Optional published values, and their source, that the figures set beside the run's.

    Without this table the figures and the report draw and write nothing of a publication.
    """

    source: str
    """Where the values are published (authors, year, title; section or table), quoted by the
    figures and the report wherever they use one."""
    settlement_m: float | None = field(default=None, metadata={"allowed": "> 0"})
    """A published settlement of the cap (down positive): a line beside the run's settlement
    curve, and the run's last settlement as a percentage of it."""
    settlement_day: float | None = field(default=None, metadata={"allowed": ">= 0"})
    """The day the published settlement holds at (not set: the publication states no time;
    the line spans the run)."""
    settlement_note: str = ""
    """What the published settlement is, in words (a measurement or a computation, by whom,
    with what): the report quotes it."""
    total_load_kN: float | None = field(default=None, metadata={"allowed": "> 0"})
    """The published total load on the foundation: the report sets the sum of the pile head
    forces beside it."""
    soft_layers: tuple[int, ...] = field(default=(), metadata={
        "allowed": "layer numbers from 1 to the number of layers, increasing"})
    """The layers (numbered from 1, top down) the publication's findings call soft: drawn thick
    in the layer-mean figures; the report asks whether the shaft friction grows with time in
    them."""
    early_day: float | None = field(default=None, metadata={"allowed": "> 0"})
    """The end of the publication's early period: marked in the time figures; the report asks
    whether the relative displacement grows fastest before it."""
    profile_days: tuple[float, ...] = field(default=(), metadata={
        "unit": "day", "allowed": "each >= 0"})
    """The times of the publication's profile figures: the gauge profile figures use the run's
    nearest output times (not set: up to five output times spread over the run)."""
    gauge_sections: tuple[int, ...] = field(default=(), metadata={
        "allowed": "section numbers from 1 to the number of outputs.gauge_depths_m"})
    """The gauge sections (numbered from 1, top down) whose histories the publication draws:
    the gauge history figures show them (not set: up to four sections spread over the pile)."""

    def __post_init__(self) -> None:
        if not self.source.strip():
            raise ScenarioError("source", self.source, "must name where the values are published")
        for key, unit in (("settlement_m", "m"), ("total_load_kN", "kN"), ("early_day", "day")):
            value = getattr(self, key)
            if value is not None:
                require_positive(key, value, unit)
        if self.settlement_day is not None:
            require_non_negative("settlement_day", self.settlement_day, "day")
        for i, t in enumerate(self.profile_days):
            require_finite(f"profile_days[{i}]", t, "day")
            require_non_negative(f"profile_days[{i}]", t, "day")
        for key in ("soft_layers", "gauge_sections"):
            numbers = getattr(self, key)
            for i, n in enumerate(numbers):
                if n < 1 or (i and n <= numbers[i - 1]):
                    raise ScenarioError(f"{key}[{i}]", n, "must be >= 1 and greater than the "
                                        "number before it (numbered from 1, increasing)")


def check_reference(ref: Reference | None, layers: int, sections: int) -> None:
    """The reference's layer and gauge-section numbers exist in the scenario.

    ``layers``: the number of layers; ``sections``: the number of gauge sections.
    """
    if ref is None:
        return
    for key, numbers, count, what in (("soft_layers", ref.soft_layers, layers, "layers"),
                                      ("gauge_sections", ref.gauge_sections, sections,
                                       "gauge sections (outputs.gauge_depths_m)")):
        for i, n in enumerate(numbers):
            if n > count:
                raise ScenarioError(f"reference.{key}[{i}]", n,
                                    f"must be <= {count}: the scenario has {count} {what}")


__all__ = ["Reference", "check_reference"]
