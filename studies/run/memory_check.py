"""Will the run fit in this machine's memory? An estimate per rank before meshing.

Before gmsh starts, a run estimates its peak resident memory per rank and compares it with the
memory available to each of its ranks on the node; a run that cannot fit stops with
:class:`~pilegroup.errors.MachineTooSmall` (exit 2, the estimate and the available memory in one
line) unless ``--force`` is given. The estimate is logged for every run and written to
``summary.json`` (``memory``), beside the peak the run measured.

The estimate (docs/benchmarks.md, "Memory estimate before meshing"):

* cells: the graded-mesh integral of :func:`pilegroup.model.mesh_estimate.estimated_cells`
  without its safety factor (the central estimate: 17,325 against the 18,266 hexahedra of the
  quarter Pier 667 at h = 1 m), times the part a symmetry-reduced model keeps;
* unknowns: :func:`pilegroup.model.mesh_estimate.estimated_unknowns` (cells x vertices per
  cell x the unknowns per vertex of the element pair);
* memory per rank: ``BASE_MB + C * unknowns^ALPHA / ranks`` (MB), with ``C`` and ``ALPHA``
  fitted (least squares in log-log) per linear-solver family to the peaks measured on 2 ranks
  in docs/benchmarks.md (:data:`MEASURED_PEAKS`); ``auto`` is the preset it would choose
  (:func:`~pilegroup.studies.run.auto_preset.auto_preset`).

Available memory: ``MemAvailable`` of ``/proc/meminfo`` (the kernel's estimate of what can be
allocated without swapping), divided by the run's ranks on this node; the smallest value over
the nodes decides (every rank decides alike). A memory limit given to the run (``pilegroup run
--memory``, per node) lowers it.

Out of core when memory is short: a run whose preset is ``auto`` and resolves to the kept LU
(``direct_reuse``) turns to the same LU with its factors out of core (``direct_reuse_ooc``:
slower, a third less memory; docs/benchmarks.md, "Out of core when memory is short") when the
in-core estimate exceeds the memory per rank (:func:`preset_within`). The run decides before
meshing with the estimated unknowns, and again once the mesh gives the counted ones.
"""

from __future__ import annotations

import logging
import math
import os
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.errors import MachineTooSmall
from pilegroup.fileio import proc_kib
from pilegroup.geometry.adapter import ResolvedGeometry
from pilegroup.model import Scenario
from pilegroup.model.mesh_estimate import SAFETY, estimated_cells
from pilegroup.model.mesh_estimate import estimated_unknowns as model_unknowns
from pilegroup.studies.run.auto_preset import scenario_preset

log = logging.getLogger(__name__)

#: Peak resident memory of one rank of a tiny run (Python, DOLFINx, PETSc, gmsh loaded), MB:
#: 602 MB measured for the 198-cell single pile of the test suite.
BASE_MB = 600.0

#: (unknowns, peak MB of the largest of 2 ranks) per solver family, docs/benchmarks.md: the
#: double-precision LU (``direct_reuse_double``; quarter pier 1 m and 0.1 m with block
#: low-rank, "Block low-rank factorisations in whole runs"; full pier 1 m and 0.3 m without it,
#: "make run with the quarter model" and "Iterative preconditioners"), the single-precision
#: kept LU (``direct_reuse``: quarter 1 m, full 1 m, 0.3 m and 0.1 m, "Single-precision
#: factorisations"), the field split (``fieldsplit_pier``, quarter 1 m, full 1 m and full
#: 0.3 m with the band of 7 layers; its LU blocks were double precision then, single now, so
#: the fit errs on the large side).
MEASURED_PEAKS: dict[str, tuple[tuple[int, float], ...]] = {
    "lu": ((80_853, 1390.0), (164_679, 2473.0), (274_180, 7000.0), (426_116, 9800.0)),
    "lu_single": ((80_853, 1143.0), (301_772, 4034.0), (426_116, 4828.0), (623_988, 7351.0)),
    "split": ((80_853, 1200.0), (301_772, 4100.0), (426_116, 6600.0)),
    # the kept LU out of core (direct_reuse_ooc): quarter pier 1 m, full pier 1 m, 0.3 m and
    # 0.1 m ("Out of core when memory is short")
    "lu_single_ooc": ((80_853, 970.0), (301_772, 3153.0), (426_116, 3686.0), (623_988, 4309.0)),
    # fieldsplit_hypre in the Docker image ("The hypre preset"): quarter pier 1 m, the full 8 x 8
    # group at 1 m, and the full pier at 0.1 m (Q1-Q1) while the preset ran (its hand-over to
    # the LU came later)
    "hypre": ((69_627, 1502.0), (396_577, 3982.0), (557_967, 5036.0)),
}
#: The family of each preset (``direct`` factors every matrix: the double LU's family).
FAMILY = {"direct": "lu", "direct_reuse": "lu_single", "direct_reuse_double": "lu",
          "fieldsplit_pier": "split", "fieldsplit_kept": "split", "fieldsplit_gamg": "split",
          "fieldsplit_hypre": "hypre",
          "direct_reuse_ooc": "lu_single_ooc",
          # only ever a fallback; its one measured peak (quarter pier 1 m: 1,192 MB) lies below
          # the in-core double LU's, whose fit therefore bounds it from above
          "direct_reuse_ooc_double": "lu"}
#: The out-of-core variant of a preset, for memory budgets its in-core factors exceed.
OUT_OF_CORE = {"direct_reuse": "direct_reuse_ooc"}


def _fit(points: tuple[tuple[int, float], ...], ranks: int = 2) -> tuple[float, float]:
    """``(C, ALPHA)`` of ``ranks x (peak - BASE_MB) = C unknowns^ALPHA`` (least squares)."""
    n = np.log([p[0] for p in points])
    m = np.log([ranks * (p[1] - BASE_MB) for p in points])
    alpha, logc = np.polyfit(n, m, 1)
    return float(math.exp(logc)), float(alpha)


#: ``(C, ALPHA)`` per family.
FITS = {k: _fit(v) for k, v in MEASURED_PEAKS.items()}


def estimated_unknowns(sc: Scenario, geo: ResolvedGeometry) -> tuple[float, float]:
    """``(cells, unknowns)`` of the model ``geo`` holds, before meshing (central estimates)."""
    return (estimated_cells(sc) / SAFETY * geo.kept_fraction,
            model_unknowns(sc, geo.kept_fraction))


def estimated_peak_mb(unknowns: float, preset: str, ranks: int) -> float:
    """Peak resident memory per rank (MB) of a run of ``unknowns`` with ``preset``."""
    c, alpha = FITS[FAMILY.get(preset, "lu")]
    return BASE_MB + c * unknowns ** alpha / ranks


def preset_within(sc: Scenario, preset: str, unknowns: float, ranks: int,
                  budget_mb: float | None) -> str:
    """``preset``, or its out-of-core variant where ``auto`` chose it and it exceeds the budget.

    ``budget_mb``: memory per rank (``None``: no limit). A preset the scenario names itself is
    kept (the memory check then reports what does not fit).
    """
    ooc = OUT_OF_CORE.get(preset)
    if (ooc is None or budget_mb is None or sc.numerics.solver.preset != "auto"
            or estimated_peak_mb(unknowns, preset, ranks) <= budget_mb):
        return preset
    return ooc


def run_estimate(sc: Scenario, geo: ResolvedGeometry, ranks: int,
                 budget_mb: float | None = None) -> tuple[float, float, str, float]:
    """``(cells, unknowns, preset, peak MB per rank)`` of a run of ``sc`` on ``ranks`` ranks.

    Before meshing: the central cell and unknown estimates of the model ``geo`` holds, the
    preset the run will use (``auto`` resolved by its table and, with a memory budget per rank
    ``budget_mb``, by :func:`preset_within`) and that preset family's fit.
    """
    cells, unknowns = estimated_unknowns(sc, geo)
    return cells, unknowns, *_preset_and_need(sc, geo, unknowns, ranks, budget_mb)


def _preset_and_need(sc: Scenario, geo: ResolvedGeometry, unknowns: float, ranks: int,
                     budget_mb: float | None) -> tuple[str, float]:
    """``(preset, peak MB per rank)`` of ``unknowns``: ``auto`` resolved, then budgeted."""
    preset = preset_within(sc, scenario_preset(sc, geo.symmetry, int(unknowns)), unknowns,
                           ranks, budget_mb)
    return preset, estimated_peak_mb(unknowns, preset, ranks)


def ranks_on_node(comm: MPI.Comm) -> int:
    """The ranks of ``comm`` on this rank's node (collective)."""
    node = comm.Split_type(MPI.COMM_TYPE_SHARED)
    try:
        return node.size
    finally:
        node.Free()


def available_mb_per_rank(comm: MPI.Comm) -> tuple[float, int]:
    """``(MB available per rank, ranks on this node)``; the smallest over the nodes (collective)."""
    local = ranks_on_node(comm)
    per_rank = available_mb() / local
    return comm.allreduce(per_rank, op=MPI.MIN), local


def case_memory_mb(world: MPI.Comm, group: MPI.Comm, memory_mb: float | None = None) -> float:
    """The memory (MB per node) a batch case run on ``group`` may use, for its memory check.

    A node's memory (``memory_mb``, else what it has available when the batch starts) is
    shared among the batch's ranks on it (``world``; the smallest share over the nodes), and a
    case gets the share of each of its ranks on the node: cases that run side by side never
    plan on the same memory (collective over ``world``, then ``group``).
    """
    share = (available_mb() if memory_mb is None else memory_mb) / ranks_on_node(world)
    return world.allreduce(share, op=MPI.MIN) * ranks_on_node(group)


def available_mb() -> float:
    """Memory that can be allocated without swapping, MB (``MemAvailable``, else free pages)."""
    avail = proc_kib("/proc/meminfo", "MemAvailable")
    if avail is not None:
        return avail / 1024.0
    return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES") / 2 ** 20


def memory_check(sc: Scenario, geo: ResolvedGeometry, comm: MPI.Comm, force: bool = False,
                 limit_mb: float | None = None) -> dict[str, Any]:
    """Estimate, log and check the run's memory; returns the record for ``summary.json``.

    ``limit_mb``: the memory the run may use per node (``pilegroup run --memory``); the
    memory per rank is the smaller of its share and the available memory's
    (``budget_mb_per_rank`` of the record).

    Raises:
        MachineTooSmall: the estimate per rank exceeds the memory per rank (not with
            ``force``, which logs a warning instead). Every rank raises alike.
    """
    avail, local = available_mb_per_rank(comm)
    budget = avail if limit_mb is None else min(avail, limit_mb / local)
    cells, unknowns, preset, need = run_estimate(sc, geo, comm.size, budget)
    record = {"estimate_mb_per_rank": round(need, 1), "available_mb_per_rank": round(avail, 1),
              "budget_mb_per_rank": round(budget, 1), "limit_mb": limit_mb,
              "estimated_cells": round(cells), "estimated_unknowns": round(unknowns),
              "preset": preset, "ranks": comm.size, "ranks_on_node": local, "forced": force}
    limit = "" if limit_mb is None else f"; --memory {limit_mb:.0f} MB per node"
    text = (f"{need:.0f} MB per rank estimated (about {cells:.3g} cells, {unknowns:.3g} "
            f"unknowns, preset {preset}, {comm.size} rank(s)); {avail:.0f} MB available per"
            f" rank ({local} rank(s) on this node){limit}")
    if comm.rank == 0:
        log.info("memory: %s", text)
    if need > budget:
        if not force:
            raise MachineTooSmall("memory", f"{need:.0f} MB per rank",
                                  f"the run does not fit: {text}; {_what_to_change(sc)}, use"
                                  " more ranks or machines, or give --force to run anyway", "")
        if comm.rank == 0:
            log.warning("memory: the run may not fit (--force): %s", text)
    return record


def _what_to_change(sc: Scenario) -> str:
    """What in the scenario would make it smaller: the element pair, the mesh keys given."""
    num = sc.numerics
    given = [k for k in num.mesh.given() if k not in num.mesh.automatic and k != "scale"]
    parts = []
    if num.element == "Q2Q1":
        parts.append("numerics.element = 'Q2Q1' holds 6 times the unknowns of 'Q1Q1' on the "
                     "same mesh")
    if given:
        parts.append("remove " + ", ".join(f"numerics.mesh.{k}" for k in given)
                     + " (the automatic sizes fit a 24 GB machine)")
    parts.append(f"raise numerics.mesh.scale (now {num.mesh.scale:g}) to coarsen every "
                 "automatic size")
    return "; ".join(parts)


def memory_on_mesh(sc: Scenario, geo: ResolvedGeometry, unknowns: int, comm: MPI.Comm,
                   record: dict[str, Any]) -> dict[str, Any]:
    """The memory record with the preset and estimate for the ``unknowns`` counted on the mesh.

    Before meshing the unknowns are an estimate; ``auto`` is resolved again with the counted
    ones and the record's budget (:func:`preset_within`), with one line when the preset changes.
    """
    preset, need = _preset_and_need(sc, geo, unknowns, comm.size, record["budget_mb_per_rank"])
    if preset != record["preset"] and comm.rank == 0:
        log.info("memory: %d unknowns on the mesh: preset %s, %.0f MB per rank estimated (%.0f "
                 "MB per rank allowed)", unknowns, preset, need, record["budget_mb_per_rank"])
    return record | {"preset": preset, "counted_unknowns": unknowns,
                     "estimate_on_mesh_mb_per_rank": round(need, 1)}


__all__ = ["BASE_MB", "FITS", "MEASURED_PEAKS", "OUT_OF_CORE", "available_mb",
           "available_mb_per_rank", "case_memory_mb", "estimated_peak_mb", "estimated_unknowns",
           "memory_check", "memory_on_mesh", "preset_within", "ranks_on_node"]
