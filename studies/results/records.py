"""The JSON summaries of a run folder, typed: ``summary_solver.json`` and ``summary.json``.

:class:`RunSummary` is the solver's :class:`~pilegroup.solver.exports.SolverSummary` with what
the scenario adds (written by :func:`pilegroup.studies.run.pipeline.run_coupled`);
:class:`JobSummary` is ``summary.json``, written by :func:`write_job_summary` whatever the
run's end: ``complete``, ``failed`` or ``interrupted`` (and ``failed``, with the same keys, by
the run's watchdog when a rank dies of a signal: :mod:`pilegroup.studies.run.watchdog`). JSON
keys are the field names.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Literal, TypedDict

from pilegroup.fileio import write_json_atomic
from pilegroup.solver.exports import SolverSummary

SUMMARY_JSON = "summary.json"
SOLVER_SUMMARY_JSON = "summary_solver.json"


class SymmetryRecord(TypedDict):
    """Which part of the foundation the mesh holds, and why."""

    model: str
    """``none``, ``quarter``, ``half_x`` or ``half_y``."""
    reason: str


class SettlementRecord(TypedDict):
    """The cap settlement at one output time."""

    t_day: float
    stage: str
    settlement_m: float
    """Down positive."""


class RunSummary(SolverSummary, total=False):
    """``summary_solver.json``: the solver's summary and the run's own keys."""

    complete: bool
    """False while the run is going (rewritten at every output time) or after a failure."""
    centre_pile: int
    """Number of the pile nearest the group's centre (1-based)."""
    interface_mode: str
    symmetry: SymmetryRecord
    element: str
    preset: str
    """The linear-solver preset chosen (``auto`` resolved)."""
    gauge_sections: list[dict[str, Any]] | None
    """Virtual strain-gauge sections (``GaugeProbe.summary``), or None without gauges."""
    neutral_plane: list[dict[str, float]]
    """Every pile's row of ``neutral_plane.csv`` at the last output time (column names)."""
    settlement_m: list[SettlementRecord]
    settlement_sign: str
    resumed_from_day: float | None
    checkpoints: list[dict[str, Any]]
    """The checkpoints written (time, reason, files)."""
    failure: str
    """One line: why the run found no equilibrium (only after a failure)."""
    capacity: dict[str, Any]
    """A run with a capacity stage: the criteria, group and piles
    (``studies.run.capacity_probe.CapacityProbe.result``)."""


class MeshRecord(TypedDict):
    """The mesh of a run (``summary.json``'s ``mesh``)."""

    h_m: float
    cells: int
    vertices: int
    min_scaled_jacobian: float
    shaft_groups: int
    files: dict[str, Any]


class JobSummary(TypedDict, total=False):
    """``summary.json``: how the run ended and where its results are."""

    scenario: str
    status: Literal["complete", "failed", "interrupted"]
    stages_done: list[str]
    """Complete: ``validate``, ``mesh`` and the stages solved."""
    solver: RunSummary | None
    """Complete: the run summary (None when stopped after meshing)."""
    mesh: MeshRecord
    discretisation: dict[str, Any]
    """Complete: the element pair, why, and every mesh size (``automatic``: those chosen
    from the scenario, :meth:`pilegroup.model.scenario.Scenario.discretisation`)."""
    ranks: int
    wall_s: float
    reason: str
    """Failed: the exception's type and message."""
    rank: int | None
    """Failed: the rank that failed alone (None when every rank failed alike)."""
    signal: str
    """Interrupted: the signal's name."""
    t_day: float
    """Interrupted: the time reached, day."""
    stage: str
    """Interrupted: the stage in progress."""
    checkpoint: str | None
    """Interrupted: the checkpoint to resume from."""
    resume: str
    """Interrupted: how to continue."""
    solver_summary: str
    """Failed or interrupted: where the solver's partial summary is."""
    capacity: dict[str, Any]
    """Complete, with a capacity stage: its result (as ``solver.capacity``)."""
    memory: dict[str, Any]
    """Complete: the memory estimate made before meshing, the memory available then and the
    peak resident memory each rank measured (``studies.run.memory_check``)."""


def write_job_summary(out: Path, summary: JobSummary) -> Path:
    """Write ``summary.json`` into the run folder ``out`` (atomically); returns its path."""
    return write_json_atomic(Path(out) / SUMMARY_JSON, summary)
