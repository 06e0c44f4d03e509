"""The records of a mesh study: each size's check, each case, and what the report states.

Below both the study (:mod:`.mesh_study`, which makes them) and its report (:mod:`.mesh_report`,
:mod:`.mesh_report_md`, which read them).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NotRequired, TypedDict

from pilegroup.model import Scenario
from pilegroup.model.reference import MeshStudyReference

#: The mesh sizes at the pile surfaces (m) a study runs unless told others (``--sizes``).
DEFAULT_SIZES = (1.0, 0.8, 0.6, 0.3, 0.1)


@dataclass(frozen=True)
class SizeCheck:
    """One mesh size: whether it can run here, why not, and the estimates behind it."""

    h: float
    runnable: bool
    reason: str = ""
    estimated_cells: float = math.nan
    estimated_unknowns: float = math.nan
    estimated_memory_mb: float = math.nan


@dataclass(frozen=True)
class StudyCase:
    """A case of the study: its name, mesh size and penalty multiplier (1 = as given)."""

    name: str
    h: float
    penalty: float = 1.0


@dataclass(frozen=True)
class StudyInfo:
    """What the report states besides the rows: scenario, sizes, cases, ranks, memory."""

    scenario: Scenario
    checks: tuple[SizeCheck, ...]
    cases: tuple[StudyCase, ...]
    ranks: int
    ranks_per_case: int
    memory_mb: float
    penalty_factor: float

    @property
    def published(self) -> MeshStudyReference | None:
        """The published mesh study the scenario's ``[reference]`` carries, if any."""
        ref = self.scenario.reference
        return ref.mesh_study if ref is not None else None


class SizeRow(TypedDict):
    """One mesh size of the study (``mesh_study.csv``).

    The published study's values only where the scenario carries one
    (:attr:`StudyInfo.published`).
    """

    h_m: float
    """Element size at the pile surfaces, m."""
    published_elements: NotRequired[int | None]
    published_hours: NotRequired[float | None]
    published_settlement_cm: NotRequired[float | None]
    status: str
    """``complete``, ``failed: ...``, ``not run: ...`` or ``not in the study``."""
    cells: int | None
    symmetry: str | None
    unknowns: int | None
    wall_s: float | None
    peak_rss_mb_max: float | None
    t_last_day: float | None
    """The last output time, day."""
    settlement_cm: float | None
    """Cap settlement at the last output time, cm."""


class PenaltyRow(TypedDict, total=False):
    """A penalty case against its base size: the relative change of each final quantity."""

    h_m: float
    case: str
    status: str
    """``complete`` or ``not both complete``."""
    base: dict[str, float]
    """Final quantities of the base case."""
    penalty: dict[str, float]
    """Final quantities of the penalty case."""
    change: dict[str, float]
    """Relative change of each quantity, penalty against base."""
