"""``pilegroup study mesh``: a batch over the mesh size, with the penalty check, and its report.

For each size ``h`` (``numerics.mesh.size_m``) the scenario is validated and its memory is
estimated as every run estimates its own before meshing
(:func:`pilegroup.studies.run.memory_check.run_estimate`); a size that is invalid or would not fit
the machine's memory is not run and is reported with the reason. The sizes that can run are the
cases ``h<size>`` of a batch (:func:`pilegroup.studies.batch.execute.run_batch`: MPI groups, shared
queue, resume). The interface's normal stiffness is ``normal_stiffness_factor * E / h``
(:func:`pilegroup.studies.run.pipeline.interface_law`), so it grows as the mesh is refined; the
coarsest and the finest sizes are also run with the factor times ``penalty_factor`` (cases
``h<size>_penalty_x<factor>``) to show whether the answer depends on it. World rank 0 then writes
the report (:mod:`pilegroup.studies.campaigns.mesh_report`), with a published mesh study beside
ours only where the scenario's ``[reference]`` carries one.

Memory estimate: the one each run makes of itself before meshing (cells and unknowns of the
model part, the preset it will use, that preset family's fit of measured peaks;
docs/benchmarks.md, "Memory estimate before meshing"), times the ranks of a case. Cases run side
by side share the machine, so a case may use the machine's memory divided by the number of
groups; with that share ``auto`` takes the out-of-core LU for a size whose in-core factors
would not fit, and the batch gives each case the same share for its own memory check.
"""

from __future__ import annotations

import os
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any

from mpi4py import MPI

from pilegroup.errors import ScenarioError
from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.model import Scenario, load_scenario
from pilegroup.studies.batch.batch_plan import BatchCase, BatchPlan
from pilegroup.studies.batch.execute import run_batch
from pilegroup.studies.batch.rows import BatchRow
from pilegroup.studies.campaigns.mesh_records import DEFAULT_SIZES, SizeCheck, StudyCase, StudyInfo
from pilegroup.studies.campaigns.mesh_report import write_mesh_report
from pilegroup.studies.run.memory_check import run_estimate

SIZE_KEY = "numerics.mesh.size_m"
PENALTY_KEY = "interface.normal_stiffness_factor"
ELEMENT_KEY = "numerics.element"
#: The element pair of a study whose scenario leaves it to ``auto``: h is the size of
#: trilinear cells at the pile surface, as in the paper's ABAQUS study (C3D8P, trilinear
#: displacement and pore pressure). Taylor–Hood, the default, spans two such cells per element
#: and would need about a million unknowns in the quarter pier at h = 0.1 m; its own
#: convergence is measured with ``numerics.mesh.scale`` (docs/results.md). A ``--set
#: numerics.element=...`` is kept.
STUDY_ELEMENT = "Q1Q1"

def machine_memory_mb() -> float:
    """Physical memory of this machine, MB."""
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES") / 2 ** 20


def check_size(source: str, sets: Mapping[str, Any], h: float, ranks: int, groups: int,
               memory_mb: float) -> SizeCheck:
    """Whether size ``h`` validates and fits ``memory_mb / groups`` on ``ranks`` ranks.

    With that budget ``auto`` may take the out-of-core LU, as the case's own run will
    (:func:`~pilegroup.studies.run.memory_check.run_estimate`).
    """
    try:
        sc = load_scenario(source, {**sets, SIZE_KEY: h})
    except ScenarioError as exc:
        return SizeCheck(h, False, f"invalid: {exc}")
    budget = memory_mb / groups
    cells, n, _, per_rank = run_estimate(sc, resolve_geometry(sc), ranks, budget / ranks)
    mem = per_rank * ranks
    ok = mem <= budget
    reason = "" if ok else (
        f"needs about {mem / 1024:.1f} GB ({n:,.0f} unknowns estimated) > {budget / 1024:.1f} "
        f"GB per case ({memory_mb / 1024:.1f} GB of memory / {groups} cases at once)")
    return SizeCheck(h, ok, reason, cells, n, mem)


def study_cases(sc: Scenario, checks: Sequence[SizeCheck], penalty_factor: float
                ) -> list[StudyCase]:
    """The size cases (coarse to fine) and the penalty cases of the coarsest and finest."""
    sizes = sorted((c.h for c in checks if c.runnable), reverse=True)
    cases = [StudyCase(f"h{h:g}", h) for h in sizes]
    if sizes and sc.interface.mode != "tied" and penalty_factor != 1.0:
        for h in dict.fromkeys((sizes[0], sizes[-1])):
            cases.append(StudyCase(f"h{h:g}_penalty_x{penalty_factor:g}", h, penalty_factor))
    return cases


def study_plan(source: str, sets: Mapping[str, Any], sc: Scenario,
               cases: Sequence[StudyCase]) -> BatchPlan:
    """The batch plan of ``cases`` (``sets`` first, then the size and the penalty)."""
    factor = sc.interface.normal_stiffness_factor
    out = []
    for c in cases:
        over = [*sets.items(), (SIZE_KEY, c.h)]
        if c.penalty != 1.0:
            over.append((PENALTY_KEY, factor * c.penalty))
        out.append(BatchCase(c.name, tuple(over)))
    return BatchPlan(source, tuple(out), f"mesh_study_{sc.name}")


def run_mesh_study(source: str, sets: Mapping[str, Any], sizes: Sequence[float], out: Path,
                   ranks_per_case: int = 1, penalty_factor: float = 10.0,
                   memory_mb: float | None = None, comm: MPI.Comm = MPI.COMM_WORLD,
                   progress: bool = True) -> int:
    """Run the study and write its report to ``out``; the number of failed cases.

    Collective over ``comm``. Raises :class:`ScenarioError` if the base scenario is invalid.
    """
    sc = load_scenario(source, sets)
    if ELEMENT_KEY not in sets and sc.numerics.element_reason.startswith("auto"):
        sets = {**sets, ELEMENT_KEY: STUDY_ELEMENT}
        sc = load_scenario(source, sets)
    groups = comm.size // max(ranks_per_case, 1)
    memory = memory_mb or machine_memory_mb()
    checks = [check_size(source, sets, h, ranks_per_case, max(groups, 1), memory)
              for h in dict.fromkeys(sizes)]
    cases = study_cases(sc, checks, penalty_factor)
    failed = 0
    rows: list[BatchRow] = []
    if cases:
        result = run_batch(study_plan(source, sets, sc, cases), out, ranks_per_case, comm,
                           progress, memory)
        rows, failed = result.rows, result.failed
    if comm.rank == 0:
        info = StudyInfo(sc, tuple(checks), tuple(cases), comm.size, ranks_per_case, memory,
                         penalty_factor)
        write_mesh_report(out, info, rows)
    return failed


__all__ = ["DEFAULT_SIZES", "STUDY_ELEMENT", "SizeCheck", "StudyCase", "StudyInfo", "check_size",
           "machine_memory_mb", "run_mesh_study",
           "study_cases", "study_plan"]
