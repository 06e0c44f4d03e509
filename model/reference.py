"""Published values a scenario is compared with: the optional ``[reference]`` table.

A run's figures and report speak of the scenario alone. Only where the scenario carries a
``[reference]`` do they set published values beside the run's: a settlement line, a total load,
the layers and the early period the publication's findings are about, the times and gauge
sections of its figures, a published mesh-size study (``[reference.mesh_study]``, which
``pilegroup study mesh`` sets beside its own). Each value is optional; the ``source`` names where
they are published. The bundled ``pier667`` scenarios carry the values of Li et al. (2019); no
other scenario does, and nothing is drawn or written of a publication without one
(docs/results.md, "Figures and report of a run").
"""

from __future__ import annotations

from dataclasses import dataclass, field

from pilegroup.errors import ScenarioError
from pilegroup.validate import require_finite, require_non_negative, require_positive


@dataclass(frozen=True)
class MeshStudyReference:
    """A published mesh-size study of the same model, set beside ``pilegroup study mesh``'s own.

    The study's table, figures and report show it only where the scenario carries it.
    """

    sizes_m: tuple[float, ...] = field(metadata={"allowed": "each > 0, decreasing"})
    """The element sizes at the pile surfaces (as ``numerics.mesh.size_m``), coarse to fine."""
    settlements_m: tuple[float, ...] = field(metadata={"allowed": "each > 0, one per size"})
    """The published settlement of the cap (down positive) at each size: beside ours in the
    table and the settlement figure; its Richardson extrapolation from the three finest."""
    elements: tuple[int, ...] = field(default=(), metadata={
        "allowed": "each > 0, one per size"})
    """The element count of the published model at each size (not set: not tabulated)."""
    hours: tuple[float, ...] = field(default=(), metadata={
        "unit": "h", "allowed": "each > 0, one per size"})
    """The published computation time at each size (not set: no published series in the
    error-against-time figure)."""
    label: str = "published"
    """How the study's figures name the published values in their legends."""
    note: str = ""
    """Where the study is published (section, table) and what its columns are: the report
    quotes it."""

    def __post_init__(self) -> None:
        n = len(self.sizes_m)
        if n == 0:
            raise ScenarioError("sizes_m", list(self.sizes_m), "must list at least one size")
        for i, h in enumerate(self.sizes_m):
            require_positive(f"sizes_m[{i}]", h, "m")
            if i and h >= self.sizes_m[i - 1]:
                raise ScenarioError(f"sizes_m[{i}]", h, "must be smaller than the size before "
                                    "it (coarse to fine)", "m")
        for key, unit in (("settlements_m", "m"), ("elements", ""), ("hours", "h")):
            values = getattr(self, key)
            if key != "settlements_m" and not values:
                continue
            if len(values) != n:
                raise ScenarioError(key, list(values), f"must give one value per size: {n} "
                                    f"sizes_m, {len(values)} {key}")
            for i, v in enumerate(values):
                require_positive(f"{key}[{i}]", v, unit)
        if not self.label.strip():
            raise ScenarioError("label", self.label, "must name the published values")

    def at(self, values: tuple[float, ...] | tuple[int, ...], h: float) -> float | None:
        """The value of ``values`` (a column of this study) at size ``h``; None if not given."""
        for size, v in zip(self.sizes_m, values, strict=False):
            if abs(size - h) <= 1e-9 * max(abs(h), 1.0):
                return v
        return None


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
    mesh_study: MeshStudyReference | None = None
    """A published mesh-size study of the same model (not set: ``pilegroup study mesh``
    reports its own sizes alone)."""

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


__all__ = ["MeshStudyReference", "Reference", "check_reference"]
