"""The main job: one scenario through every stage that exists, outputs to one folder."""

from __future__ import annotations

import dataclasses
import logging
import time
from pathlib import Path
from typing import Any

from mpi4py import MPI

from pilegroup.errors import PilegroupError, RunInterrupted, ScenarioError
from pilegroup.fileio import write_json_atomic
from pilegroup.geometry.adapter import ResolvedGeometry, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.output import mesh_outputs
from pilegroup.model import Scenario
from pilegroup.solver.exports import peak_rss_mb
from pilegroup.studies.report.run_report import write_report
from pilegroup.studies.results.records import JobSummary, write_job_summary
from pilegroup.studies.results.rundata import RUN_FILES
from pilegroup.studies.run.checkpoint import check_resume, completed_summary, remove_checkpoint
from pilegroup.studies.run.folder_lock import folder_lock, held_fd
from pilegroup.studies.run.memory_check import memory_check, memory_on_mesh
from pilegroup.studies.run.pipeline import estimate_dofs, run_coupled
from pilegroup.studies.run.watchdog import watched

log = logging.getLogger(__name__)


def run_scenario(sc: Scenario, out: Path, mesh_size: float | None = None,
                 stop_after: str = "solve", comm: MPI.Comm = MPI.COMM_WORLD,
                 resume: bool = False, force: bool = False,
                 memory_mb: float | None = None) -> JobSummary:
    """Run scenario ``sc`` on ``comm`` and write its outputs to ``out``; returns the summary.

    Validate, write the resolved scenario (``scenario.json``), build the mesh once and write
    its outputs (``mesh/``: XDMF with tags, PNG renders, counts and quality), run every stage
    on it (unless ``stop_after = "mesh"``), write ``summary.json`` and the report's plots.
    ``summary.json`` is always written: ``status`` is ``complete``, ``failed`` (with the
    reason) or ``interrupted`` (a stop request; with the time reached and the checkpoint); the
    files of every output time reached stay complete.

    ``resume``: continue from ``out``'s checkpoint (same scenario and rank count, else
    :class:`~pilegroup.errors.ScenarioError`); a run whose ``summary.json`` says complete is
    not run again (its summary is returned). Without it, an older checkpoint in ``out`` is
    removed first.

    The scenario's geometry is resolved first, before the output folder is locked
    (:func:`~pilegroup.geometry.adapter.resolve_geometry`): a layout the mesher cannot take
    is refused there, with the line ``pilegroup scenario validate`` gives, and nothing is
    written. Before anything is written or meshed the run's peak memory per rank is estimated and
    compared with the memory available
    (:func:`~pilegroup.studies.run.memory_check.memory_check`): a run that cannot fit raises
    :class:`~pilegroup.errors.MachineTooSmall` unless ``force``. ``memory_mb``: the memory
    the run may use per node (``--memory``), below what is available; ``auto`` then turns to
    the out-of-core kept LU where the in-core one would not fit.

    The run holds the lock of ``out`` for its life
    (:func:`~pilegroup.studies.run.folder_lock.folder_lock`): while another run holds it,
    :class:`~pilegroup.errors.FolderBusy` is raised before anything is read or written. A
    rank that dies without a Python error (a signal) still leaves ``summary.json`` ``failed``
    and the lock free: :func:`~pilegroup.studies.run.watchdog.watched`.
    """
    t0 = time.perf_counter()
    if mesh_size is not None:
        sc = dataclasses.replace(sc, numerics=dataclasses.replace(
            sc.numerics, mesh=sc.numerics.mesh.with_given(size_m=mesh_size)))
    if resume and stop_after != "solve":
        raise ScenarioError("--stop-after", stop_after, "only 'solve' with --resume")
    # the one resolution of the scenario's geometry in a run; it refuses what the scenario's
    # validation refuses for its geometry, before the output folder is touched
    geo = resolve_geometry(sc)
    with folder_lock(out, comm), watched(out, comm, sc.name, t0, held_fd(out)):
        return _locked_run(sc, geo, out, stop_after, comm, resume, t0, force, memory_mb)


def _locked_run(sc: Scenario, geo: ResolvedGeometry, out: Path, stop_after: str,
                comm: MPI.Comm, resume: bool, t0: float, force: bool = False,
                memory_mb: float | None = None) -> JobSummary:
    """:func:`run_scenario` once the folder is locked."""
    manifest = check_resume(out, sc, comm) if resume else None
    if manifest is not None:
        done = completed_summary(out, comm)
        if done is not None:
            if comm.rank == 0:
                log.info("the run in %s is complete (t = %g day); nothing to resume", out,
                         manifest["t_day"])
            return done
    if comm.rank == 0:
        log.info("discretisation: %s", sc.discretisation_line())
        warning = sc.discretisation_warning()
        if warning:
            log.warning("%s", warning)
    # before anything is written or meshed
    memory = memory_check(sc, geo, comm, force, memory_mb)
    if comm.rank == 0:
        out.mkdir(parents=True, exist_ok=True)
        write_json_atomic(out / "scenario.json", sc)
        if manifest is None:
            remove_checkpoint(out)
    try:
        summary = _run(sc, geo, out, stop_after, comm, t0, manifest, memory)
        if summary["solver"] is not None and sc.outputs.plots:
            _write_plots(out, comm)
    except RunInterrupted as exc:
        _write_interrupted(out, sc, comm, exc, t0)
        raise
    except Exception as exc:
        _write_failure(out, sc, comm, exc, t0)
        if isinstance(exc, PilegroupError) and comm.rank == 0 and sc.outputs.plots:
            _plots_of_what_was_reached(out)
        raise
    return summary


def _run(sc: Scenario, geo: ResolvedGeometry, out: Path, stop_after: str, comm: MPI.Comm,
         t0: float, resume: dict[str, Any] | None, memory: dict[str, Any]) -> JobSummary:
    """Mesh and solve; writes ``summary.json`` with ``status = "complete"``."""
    t_mesh = time.perf_counter()
    md = build_mesh(geo.spec, comm)
    mesh = mesh_outputs(md, geo.spec, out / "mesh", t0=t_mesh)
    solved = None
    if stop_after == "solve":
        memory = memory_on_mesh(sc, geo, estimate_dofs(md, sc.numerics.element), comm, memory)
        solved = run_coupled(sc, geo, md, out, preset=memory["preset"], resume=resume)
    summary: JobSummary = {
        "scenario": sc.name,
        "status": "complete",
        "stages_done": ["validate", "mesh"] + ([st.name for st in sc.stages] if solved else []),
        "solver": solved,
        "mesh": {k: mesh[k] for k in ("h_m", "cells", "vertices", "min_scaled_jacobian",
                                      "shaft_groups", "files")},
        "discretisation": sc.discretisation(),
        "ranks": comm.size,
        "wall_s": time.perf_counter() - t0,
    }
    summary["memory"] = memory | {"peak_rss_mb_per_rank": comm.allgather(peak_rss_mb())}
    if solved is not None and "capacity" in solved:
        summary["capacity"] = solved["capacity"]
    if comm.rank == 0:
        log.info("wrote %s", write_job_summary(out, summary))
    return summary


def _write_plots(out: Path, comm: MPI.Comm) -> None:
    """The report's figures, shared among the ranks (rank 0 lists them all).

    A figure not written fails the run too (an :class:`~pilegroup.errors.OutputError` on the
    rank that wrote it ends every rank).
    """
    comm.Barrier()  # rank 0 has written summary.json, which the figures read
    paths = comm.gather(write_report(out, (comm.rank, comm.size)), root=0)
    if comm.rank == 0:
        for path in sorted(p for part in paths for p in part):
            log.info("wrote %s", path)


def _plots_of_what_was_reached(out: Path) -> None:
    """The report's figures of a run that stopped (e.g. its load–settlement curve).

    None when it stopped before its first output time (nothing to draw, and nothing to warn
    about: the failure is the news).
    """
    if not any((out / name).is_file() for name in RUN_FILES):
        log.info("no plots: the run stopped before its first output")
        return
    try:
        for path in write_report(out):
            log.info("wrote %s", path)
    except (PilegroupError, OSError, ValueError, KeyError) as exc:  # the failure stays the news
        log.warning("no plots of the stopped run: %s", exc)


def _write_interrupted(out: Path, sc: Scenario, comm: MPI.Comm, exc: RunInterrupted,
                       t0: float) -> None:
    """``summary.json`` with ``status = "interrupted"``: the signal, time reached, checkpoint."""
    if comm.rank == 0:
        _write_summary_of_stop(out, {
            "scenario": sc.name, "status": "interrupted", "signal": exc.signal_name,
            "t_day": exc.t, "stage": exc.stage, "checkpoint": exc.checkpoint,
            "resume": "pilegroup run SCENARIO --out OUT --resume (same scenario, --set "
                      "values and rank count)",
            "ranks": comm.size, "wall_s": time.perf_counter() - t0,
            "solver_summary": "summary_solver.json (written up to the last output time)"})


def _write_failure(out: Path, sc: Scenario, comm: MPI.Comm, exc: BaseException,
                   t0: float) -> None:
    """``summary.json`` with ``status = "failed"`` and the reason.

    A :class:`~pilegroup.errors.PilegroupError` is raised on every rank alike (rank 0 writes);
    any other exception may be one rank's alone, so that rank writes.
    """
    collective = isinstance(exc, PilegroupError)
    if collective and comm.rank != 0:
        return
    _write_summary_of_stop(out, {
        "scenario": sc.name, "status": "failed",
        "reason": f"{type(exc).__name__}: {exc}",
        "rank": None if collective else comm.rank, "ranks": comm.size,
        "wall_s": time.perf_counter() - t0,
        "solver_summary": "summary_solver.json (written up to the last output time)"})


def _write_summary_of_stop(out: Path, summary: JobSummary) -> None:
    """``summary.json`` of a run that stopped; a warning if it cannot be written.

    The stop's own error stays the one reported.
    """
    try:
        write_job_summary(out, summary)
    except OSError as exc:
        log.warning("no summary.json of the stopped run: %s", exc)
