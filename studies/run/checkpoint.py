"""Checkpoints of a run: written at step boundaries, read back to resume the run exactly.

A checkpoint is the folder ``OUT/checkpoint`` (format: docs/checkpoint.md):

* ``state-<generation>-rank<r>.npz`` per rank: the problem's local arrays
  (:func:`pilegroup.solver.state.problem_state`: fields, quadrature-point and interface state,
  Newton's references, linear solver);
* ``manifest.json`` (rank 0): format, scenario hash, rank count, mesh cell count and each
  rank's partition fingerprint, the stage loop's state (stage, t, load factor, the stepper's
  ``dt`` and ``easy``, the run log), what every export needs to continue its files, the rank
  files of this generation with their size and SHA-256, and the SHA-256 of the manifest's own
  content.

Every file is written under a temporary name and renamed; the rank files of a new generation
are complete before rank 0 renames the new manifest over the old one, and the files of older
generations are removed only after that, so a run killed at any moment leaves the previous
checkpoint valid. A checkpoint is written at every output time (after the exports), every
``outputs.checkpoint_every_min`` minutes of wall time, and when a stop is requested (SIGTERM,
SIGINT: :mod:`pilegroup.studies.run.interrupt`), at the next step boundary.

Resuming needs the same scenario (its hash) and the same rank count: the local arrays fit the
mesh partition of that rank count only (the fingerprints check it), and intact files: a
manifest cut short or changed, a rank file missing, cut short or changed (its SHA-256) is named
in one line. Anything else is refused with a :class:`~pilegroup.errors.ScenarioError`, raised
on every rank alike (rank 0 reads the manifest and broadcasts it with its verdict; every rank
checks its own file and the verdicts are gathered).
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
FORMAT = 2
FOLDER = "checkpoint"
MANIFEST = "manifest.json"
#: The manifest's key of the SHA-256 of its other keys (canonical JSON: keys sorted).
SEAL = "manifest_sha256"
#: Keys every manifest of :data:`FORMAT` has; one missing means the file is damaged.
MANIFEST_KEYS = ("format", "scenario_sha256", "ranks", "generation", "reason", "written",
                 "t_day", "stage", "cells", "fingerprints", "files", "sha256", "bytes", "state",
                 "exports", SEAL)
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


def _canonical_sha256(data: dict[str, Any]) -> str:
    """SHA-256 of ``data`` as JSON with sorted keys (floats by ``repr``: exact round trip)."""
    return hashlib.sha256(json.dumps(data, sort_keys=True).encode()).hexdigest()


def seal(manifest: dict[str, Any]) -> dict[str, Any]:
    """``manifest`` as JSON reads it back, with :data:`SEAL`: the SHA-256 of its content."""
    body = json.loads(json.dumps(manifest, default=json_default))
    return {**body, SEAL: _canonical_sha256(body)}


def file_sha256(path: Path) -> str:
    """SHA-256 of the file at ``path``."""
    with open(path, "rb") as f:
        return hashlib.file_digest(f, "sha256").hexdigest()


def _manifest_problem(path: Path) -> tuple[dict[str, Any] | None, str | None]:
    """The manifest at ``path`` and what is wrong with it (``None``: nothing, or no file)."""
    if not path.exists():
        return None, None
    try:
        raw = path.read_bytes()
        m = json.loads(raw.decode("utf-8"))
    except OSError as exc:
        return None, f"cannot be read ({exc.strerror})"
    except UnicodeDecodeError as exc:
        return None, f"is damaged (not UTF-8 text at byte {exc.start} of {len(raw)})"
    except json.JSONDecodeError as exc:
        return None, (f"is cut short or damaged (not valid JSON at byte {exc.pos} of "
                      f"{len(raw)})")
    if not isinstance(m, dict):
        return None, "is damaged (not a JSON object)"
    if "format" not in m:
        return None, "is damaged (no 'format')"
    if m["format"] != FORMAT:
        return m, None  # check_resume names the format
    missing = [k for k in MANIFEST_KEYS if k not in m]
    if missing:
        return None, f"is damaged (no {missing[0]!r})"
    if _canonical_sha256({k: v for k, v in m.items() if k != SEAL}) != m[SEAL]:
        return None, f"is damaged (its content does not match its {SEAL})"
    return m, None


def _rank_file_problem(path: Path, sha256: str, size: int) -> str | None:
    """What is wrong with the rank file at ``path`` (size and SHA-256 of the manifest)."""
    try:
        found = path.stat().st_size
        if found != size:
            how = "cut short" if found < size else "damaged"
            return f"is {how} ({found} bytes, the manifest says {size})"
        if file_sha256(path) != sha256:
            return "is damaged (its SHA-256 differs from the manifest's)"
    except FileNotFoundError:
        return "is missing"
    except OSError as exc:
        return f"cannot be read ({exc.strerror})"
    return None


def _refuse(out: Path, what: str) -> ScenarioError:
    """The error of a checkpoint that cannot be resumed from because ``what``."""
    return ScenarioError("--resume", str(out), f"{what}; run without --resume to start again")


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
    checkpoint, it has another format, was written for another scenario or rank count, or a
    file of it is damaged, cut short or missing (the message names the file).
    """
    folder = Path(out) / FOLDER
    m, problem = comm.bcast(_manifest_problem(folder / MANIFEST) if comm.rank == 0 else None,
                            root=0)
    if problem is not None:
        raise _refuse(out, f"checkpoint file {folder / MANIFEST} {problem}")
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
    mine = folder / m["files"][comm.rank]
    problem = _rank_file_problem(mine, m["sha256"][comm.rank], m["bytes"][comm.rank])
    problem = next((p for p in comm.allgather(problem and f"checkpoint file {mine} {problem}")
                    if p), None)
    if problem is not None:
        raise _refuse(out, problem)
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
        name = f"state-{gen:06d}-rank{comm.rank:04d}.npz"
        with atomic_path(self.folder / name) as tmp:
            np.savez(tmp, **problem_state(self.pb))
            sha, size = file_sha256(tmp), tmp.stat().st_size
        files = comm.gather((name, sha, size), root=0)  # each file is complete once gathered
        fingerprints = comm.gather(self.fingerprint, root=0)
        total = comm.reduce(size, op=MPI.SUM, root=0)
        if comm.rank == 0:
            manifest = {
                "format": FORMAT, "scenario_sha256": self.sha, "ranks": comm.size,
                "generation": gen, "reason": reason,
                "written": time.strftime("%Y-%m-%dT%H:%M:%S"),
                "t_day": state.t, "stage": self.stage_names[state.stage],
                "cells": _cells(self.pb),
                "fingerprints": fingerprints, "files": [f[0] for f in files],
                "sha256": [f[1] for f in files], "bytes": [f[2] for f in files],
                "state": dataclasses.asdict(state),
                "exports": {k: e.saved_state() for k, e in self.exports.items()}}
            write_json_atomic(self.folder / MANIFEST, seal(manifest))
            total += (self.folder / MANIFEST).stat().st_size
        comm.barrier()  # the new manifest is in place: older generations can go
        mine = f"state-*-rank{comm.rank:04d}.npz"
        for old in [*self.folder.glob(mine), *self.folder.glob(f".{mine}.*")]:  # + killed temps
            if old.name != name:
                old.unlink(missing_ok=True)
        self.generation, self.last = gen, time.perf_counter()
        self.pb.rebuild_kept()  # go on as a run resumed from here would
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
