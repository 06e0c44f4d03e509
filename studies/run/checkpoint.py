"""Checkpoints of a run: written at step boundaries, read back to resume the run exactly.

A checkpoint is the folder ``OUT/checkpoint`` (format: docs/checkpoint.md):

* ``state-<generation>-rank<r>.npz`` per rank: the problem's local arrays
  (:func:`pilegroup.solver.state.problem_state`: fields, quadrature-point and interface state,
  Newton's references, linear solver);
* ``manifest.json`` (rank 0): format, scenario hash, rank count, mesh cell count and each
  rank's partition fingerprint, the stage loop's state (stage, t, load factor, the stepper's
  ``dt`` and ``easy``, the run log), what every export needs to continue its files, and the
  rank files of this generation.

Every file is written under a temporary name and renamed; the rank files of a new generation
are complete before rank 0 renames the new manifest over the old one, and the files of older
generations are removed only after that, so a run killed at any moment leaves the previous
checkpoint valid. A checkpoint is written at every output time (after the exports), every
``outputs.checkpoint_every_min`` minutes of wall time, and when a stop is requested (SIGTERM,
SIGINT: :mod:`pilegroup.studies.run.interrupt`), at the next step boundary.

Resuming needs the same scenario (its hash) and the same rank count: the local arrays fit the
mesh partition of that rank count only (the fingerprints check it); anything else is refused
with a :class:`~pilegroup.errors.ScenarioError`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import logging
import shutil
import time
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.errors import RunInterrupted, ScenarioError
from pilegroup.fileio import atomic_path, json_default, write_json_atomic
from pilegroup.model import Scenario
from pilegroup.solver import BiotProblem, RunLog, RunState, StepRecord
from pilegroup.solver.state import (
    check_same_partition,
    partition_fingerprint,
    problem_state,
    restore_problem_state,
)
from pilegroup.studies.run import interrupt

log = logging.getLogger(__name__)

#: Version of the checkpoint layout (docs/checkpoint.md); another version is not read.
FORMAT = 1
FOLDER = "checkpoint"
MANIFEST = "manifest.json"
#: Scenario keys that do not change the computed state (left out of the scenario hash).
UNHASHED = (("outputs", "plots"), ("outputs", "checkpoint_every_min"))


def scenario_sha256(sc: Scenario) -> str:
    """SHA-256 of the resolved scenario (as in ``scenario.json``, keys sorted).

    Leaves out :data:`UNHASHED` (plots, checkpoint interval): a run may be resumed with them
    changed.
    """
    data = json.loads(json.dumps(sc, default=json_default))
    for table, key in UNHASHED:
        data.get(table, {}).pop(key, None)
    text = json.dumps(data, sort_keys=True, default=json_default)
    return hashlib.sha256(text.encode()).hexdigest()


def _bcast_json(path: Path, comm: MPI.Comm) -> dict[str, Any] | None:
    """The JSON object in ``path`` read on rank 0 (``None`` when missing or unreadable)."""
    data = None
    if comm.rank == 0 and path.is_file():
        try:
            data = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            data = None
    return comm.bcast(data, root=0)


def check_resume(out: Path, sc: Scenario, comm: MPI.Comm) -> dict[str, Any]:
    """The manifest of ``out``'s checkpoint, if ``sc`` on ``comm`` can resume from it.

    Raises :class:`~pilegroup.errors.ScenarioError` (on every rank alike) when there is no
    checkpoint, it has another format, or was written for another scenario or rank count.
    """
    folder = Path(out) / FOLDER
    m = _bcast_json(folder / MANIFEST, comm)
    if m is None:
        raise ScenarioError("--resume", str(out), f"no checkpoint in {folder} (a run writes "
                            "one at its first output time); run without --resume")
    if m.get("format") != FORMAT:
        raise ScenarioError("--resume", str(out), f"checkpoint format {m.get('format')} in "
                            f"{folder}; this pilegroup reads format {FORMAT}")
    if m["scenario_sha256"] != scenario_sha256(sc):
        raise ScenarioError("--resume", sc.name, f"the checkpoint in {folder} is of another "
                            "scenario or other --set values; resume with the same ones")
    if m["ranks"] != comm.size:
        raise ScenarioError("--resume", f"{comm.size} rank(s)", f"the checkpoint in {folder} "
                            f"was written by {m['ranks']} rank(s) and resumes on as many only "
                            "(its state is saved per rank, for that mesh partition)")
    return m


def completed_summary(out: Path, comm: MPI.Comm) -> dict[str, Any] | None:
    """``out``'s ``summary.json`` when it says the run is complete, else ``None``."""
    s = _bcast_json(Path(out) / "summary.json", comm)
    return s if s is not None and s.get("status") == "complete" else None


def remove_checkpoint(out: Path) -> None:
    """Remove ``out``'s checkpoint (a fresh run in the folder of an older one)."""
    shutil.rmtree(Path(out) / FOLDER, ignore_errors=True)


def _cells(pb: BiotProblem) -> int:
    """Global cell count of the problem's mesh."""
    return pb.mesh.topology.index_map(pb.mesh.topology.dim).size_global


def _run_state(data: dict[str, Any]) -> RunState:
    """A :class:`RunState` from its manifest entry."""
    d = dict(data)
    lg = d.pop("log")
    steps = [StepRecord(**s) for s in lg.pop("steps")]
    return RunState(**d, log=RunLog(steps=steps, **lg))


class Checkpoints:
    """Writes and reads the checkpoints of one run; the step boundary hook of the run.

    As ``boundary(problem, state, output)`` (see :func:`pilegroup.solver.run_stages`): all-
    reduces the stop request and the wall-time rule, writes a checkpoint at output times, when
    the interval has passed, or on a stop request, and then raises
    :class:`~pilegroup.errors.RunInterrupted` on every rank alike.

    Args:
        out: the run folder.
        sc: the scenario (hash, checkpoint interval).
        pb: the problem.
        stage_names: names of the solver stages (for messages).
        exports: the run's exports; those with ``saved_state``/``restore_state`` are saved.
    """

    def __init__(self, out: Path, sc: Scenario, pb: BiotProblem, stage_names: list[str],
                 exports: list[Any]) -> None:
        self.folder = Path(out) / FOLDER
        self.pb, self.comm, self.stage_names = pb, pb.comm, stage_names
        self.sha = scenario_sha256(sc)
        self.every_s = 60.0 * sc.outputs.checkpoint_every_min
        self.exports = {f"{i}:{type(e).__name__}": e for i, e in enumerate(exports)
                        if hasattr(e, "saved_state")}
        self.generation = 0
        self.fingerprint = partition_fingerprint(pb)
        self.last = time.perf_counter()
        self.written: list[dict[str, Any]] = []  # (t, reason, bytes, seconds) of each write

    def __call__(self, pb: BiotProblem, state: RunState, output: bool) -> None:
        """The step boundary: checkpoint when due, stop when asked (collective)."""
        due = self.every_s > 0.0 and time.perf_counter() - self.last >= self.every_s
        flags = np.array([interrupt.requested(), int(due)], dtype=np.int64)
        self.comm.Allreduce(MPI.IN_PLACE, flags, op=MPI.MAX)
        signum, due = int(flags[0]), bool(flags[1])
        if signum:
            self.write(state, interrupt.signal_name(signum))
            raise RunInterrupted(signum, interrupt.signal_name(signum), state.t,
                                 self.stage_names[state.stage], str(self.folder))
        if output or due:
            self.write(state, "output time" if output else "wall time")

    def write(self, state: RunState, reason: str) -> None:
        """Write a checkpoint of the problem, ``state`` and the exports (collective)."""
        t0 = time.perf_counter()
        comm, gen = self.comm, self.generation + 1
        self.folder.mkdir(parents=True, exist_ok=True)
        name = f"state-{gen:06d}-rank{comm.rank:04d}.npz"
        with atomic_path(self.folder / name) as tmp:
            np.savez(tmp, **problem_state(self.pb))
        size = (self.folder / name).stat().st_size
        files = comm.gather(name, root=0)  # every rank's file is complete once gathered
        fingerprints = comm.gather(self.fingerprint, root=0)
        total = comm.reduce(size, op=MPI.SUM, root=0)
        if comm.rank == 0:
            manifest = {
                "format": FORMAT, "scenario_sha256": self.sha, "ranks": comm.size,
                "generation": gen, "reason": reason,
                "written": time.strftime("%Y-%m-%dT%H:%M:%S"),
                "t_day": state.t, "stage": self.stage_names[state.stage],
                "cells": _cells(self.pb),
                "fingerprints": fingerprints, "files": files,
                "state": dataclasses.asdict(state),
                "exports": {k: e.saved_state() for k, e in self.exports.items()}}
            write_json_atomic(self.folder / MANIFEST, manifest)
            total += (self.folder / MANIFEST).stat().st_size
        comm.barrier()  # the new manifest is in place: older generations can go
        mine = f"state-*-rank{comm.rank:04d}.npz"
        for old in [*self.folder.glob(mine), *self.folder.glob(f".{mine}.*")]:  # + killed temps
            if old.name != name:
                old.unlink(missing_ok=True)
        self.generation, self.last = gen, time.perf_counter()
        seconds = comm.allreduce(self.last - t0, op=MPI.MAX)
        self.written.append({"t_day": state.t, "reason": reason, "bytes": total,
                             "seconds": seconds})
        if comm.rank == 0:
            log.debug("checkpoint at t = %.6g day (%s): %.3g MB in %.3g s", state.t, reason,
                     total / 1e6, seconds)

    def restore(self, manifest: dict[str, Any]) -> RunState:
        """Set the problem and the exports to the checkpoint of ``manifest``; its run state.

        Raises :class:`~pilegroup.errors.ScenarioError` (every rank alike) when the mesh or
        its partition differs from the checkpoint's.
        """
        cells = _cells(self.pb)
        if cells != manifest["cells"] or not check_same_partition(
                self.pb, manifest["fingerprints"]):
            raise ScenarioError("--resume", f"{cells} cells", f"the mesh or its partition "
                                f"differs from the checkpoint's ({manifest['cells']} cells) in "
                                f"{self.folder}; resume with the same mesh options and ranks")
        with np.load(self.folder / manifest["files"][self.comm.rank]) as f:
            restore_problem_state(self.pb, {k: f[k] for k in f.files})
        for k, e in self.exports.items():
            e.restore_state(manifest["exports"][k])
        self.generation = manifest["generation"]
        return _run_state(manifest["state"])
