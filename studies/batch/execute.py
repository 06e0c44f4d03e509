"""``pilegroup batch``: the cases of a plan run on groups of MPI ranks, from a shared queue.

The world communicator is split into ``size / ranks_per_case`` groups of consecutive ranks. Each
group runs one case at a time on its own communicator (:func:`run_scenario` with ``comm=group``)
and then takes the next. The queue is the cases in the order of
:func:`~pilegroup.studies.batch.batch_plan.queue_order` (largest estimated mesh first); a group's
first rank claims the next case by creating its numbered file in ``<out>/.queue/<token>/`` with
``O_CREAT | O_EXCL`` (exactly one creator succeeds, on a local or an NFS file system), so no rank
waits for another's MPI progress and nothing can deadlock: a group that finds every number taken is
done. Ranks that are done wait for the others without spinning (``Ibarrier`` polled).

Memory: cases that run side by side share a node, so each case's memory check (and ``auto``'s
turn to the out-of-core LU) gets its ranks' share of the node's memory, not the whole of it
(:func:`~pilegroup.studies.run.memory_check.case_memory_mb`; ``--memory`` sets the node's).

Before anything runs, every case's scenario is validated; a case whose folder already holds a
complete run of the same resolved scenario (:func:`~pilegroup.studies.batch.rows.is_complete`)
is skipped, every other case is run again from an emptied folder (a killed batch resumes).

Failures: an exception in a case is recorded (``batch_case.json``, ``summary.json``) and the
group takes the next case. A case whose folder another run holds
(:mod:`pilegroup.studies.run.folder_lock`) is not run, its folder left alone, and counted as
failed with a warning line naming the holder. On SIGTERM, SIGINT or SIGUSR1 (``pilegroup
batch`` turns them into stop requests, :mod:`pilegroup.studies.run.interrupt`) each running
case stops at its next step boundary with a checkpoint and is recorded ``interrupted``, and no
group takes another case. In a group of several ranks a failure is only
survivable when every rank of the group raised (the solver makes law and convergence failures
collective): the ranks that raised meet in a barrier on a communicator of their own and wait up
to :data:`AGREE_TIMEOUT_S` for the rest of the group. If a rank raised alone, the others are stuck
in a collective operation that will never complete; that rank records the failure, prints one
line naming itself and the case, and aborts the whole MPI job (finished cases stay complete;
running the plan again resumes).

World rank 0 runs cases like every rank and, in a thread of its own that does no MPI, watches
the cases' records: it shows the progress and rewrites ``batch.json`` and ``batch.csv`` whenever
a case starts or ends (:mod:`pilegroup.studies.batch.rows`), every :data:`POLL_S` seconds or
as soon as rank 0's own solve lets the thread run. Each case's peak memory is its own:
the peak resident set of each rank is reset before the case (Linux ``/proc/self/clear_refs``),
and the PETSc options database is restored, so one case's solver options do not carry over.
"""

from __future__ import annotations

import ctypes
import gc
import logging
import os
import platform
import shutil
import sys
import threading
import time
import uuid
from collections.abc import Iterator
from contextlib import contextmanager, nullcontext
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

from mpi4py import MPI
from petsc4py import PETSc
from tqdm import tqdm
from tqdm.contrib.logging import logging_redirect_tqdm

from pilegroup.errors import FolderBusy, PilegroupError, RunInterrupted, ScenarioError
from pilegroup.fileio import proc_kib, write_json_atomic
from pilegroup.studies.batch.batch_plan import BatchPlan, ResolvedCase, queue_order, resolve_cases
from pilegroup.studies.batch.rows import (
    RECORD,
    BatchRow,
    case_row,
    counts,
    is_complete,
    write_tables,
)
from pilegroup.studies.run import interrupt
from pilegroup.studies.run.folder_lock import empty_folder, folder_lock
from pilegroup.studies.run.interrupt import abort_job
from pilegroup.studies.run.job import run_scenario
from pilegroup.studies.run.memory_check import case_memory_mb

log = logging.getLogger(__name__)

#: Seconds the ranks of a group that raised wait for the group's other ranks to raise too.
AGREE_TIMEOUT_S = 60.0
#: Seconds between two looks of rank 0 at the cases' records.
POLL_S = 1.0
#: Environment variable that turns off the per-run progress bar (set inside a batch).
PROGRESS_ENV = "PILEGROUP_PROGRESS"


@dataclass(frozen=True)
class BatchResult:
    """The rows of ``batch.json`` (world rank 0 only; empty elsewhere) and the failed count.

    ``signum``: the stop signal (SIGTERM, SIGINT, SIGUSR1) that ended the batch early, or 0.
    """

    rows: list[BatchRow] = field(default_factory=list)
    failed: int = 0
    signum: int = 0


def release_memory(comm: MPI.Comm) -> None:
    """Give back what an earlier case left (collective).

    Python cycles, PETSc objects whose destruction waits for a collective clean-up, and the C
    heap's free pages (glibc ``malloc_trim``). What stays held (measured on Pier 667: 1-2.5 GB
    more after each case) is recorded as the case's ``rss_at_start_mb``.
    """
    gc.collect()
    PETSc.garbage_cleanup(comm)
    try:
        ctypes.CDLL(None).malloc_trim(0)
    except (OSError, AttributeError):  # not glibc
        pass


def rss_mb() -> float:
    """Resident memory of this process now, MB (Linux; 0 elsewhere)."""
    rss = proc_kib("/proc/self/status", "VmRSS")
    return 0.0 if rss is None else rss / 1024.0


def reset_peak_rss() -> bool:
    """Reset this process's peak resident set to its current size (Linux); False if not."""
    try:
        Path("/proc/self/clear_refs").write_text("5")
    except OSError:
        return False
    return True


def restore_petsc_options(snapshot: dict[str, str]) -> None:
    """Make the PETSc options database equal to ``snapshot`` again."""
    db = PETSc.Options()
    for key in db.getAll():
        if key not in snapshot:
            db.delValue(key)
    for key, value in snapshot.items():
        db.setValue(key, value)


def write_record(run_dir: Path, rc: ResolvedCase, status: str, **fields: Any) -> None:
    """The batch's record of a case in its run folder (``batch_case.json``)."""
    write_json_atomic(run_dir / RECORD, {"name": rc.name, "status": status,
                                         "digest": rc.digest, **fields})


def split_world(comm: MPI.Comm, ranks_per_case: int) -> MPI.Comm:
    """The group communicator of this rank: ``ranks_per_case`` consecutive ranks."""
    if ranks_per_case < 1 or comm.size % ranks_per_case:
        raise ScenarioError("--ranks-per-case", ranks_per_case,
                            f"must divide the number of MPI ranks ({comm.size}) into equal "
                            "groups")
    return comm.Split(comm.rank // ranks_per_case, comm.rank)


class _Queue:
    """The shared queue: case ``order[i]`` is taken by whoever creates file ``i`` first."""

    def __init__(self, folder: Path, order: list[int]) -> None:
        self.folder, self.order, self.cursor = folder, order, 0

    def claim(self) -> int | None:
        """The index of the next free case (now taken), or ``None`` when all are taken."""
        while self.cursor < len(self.order):
            i = self.cursor
            self.cursor += 1
            try:
                fd = os.open(self.folder / str(i), os.O_CREAT | os.O_EXCL | os.O_WRONLY)
            except FileExistsError:
                continue
            os.write(fd, f"{platform.node()} {os.getpid()}\n".encode())
            os.close(fd)
            return self.order[i]
        return None


def _agree(exc: Exception, group: MPI.Comm, err_comm: MPI.Comm, world: MPI.Comm,
           rc: ResolvedCase, run_dir: Path, start: float) -> str:
    """The failure message every rank of the group agrees on; aborts if this rank is alone."""
    text = f"{type(exc).__name__}: {exc}"
    if group.size == 1:
        return text
    req = err_comm.Ibarrier()
    t0 = time.monotonic()
    while not req.Test():
        if time.monotonic() - t0 > AGREE_TIMEOUT_S:
            write_record(run_dir, rc, "failed", start=start, end=time.time(), rank=world.rank,
                         message=f"world rank {world.rank} alone: {text}")
            abort_job(f"pilegroup: rank {world.rank} of {world.size} failed alone in case "
                      f"{rc.name!r}: {text}; the other ranks of its group cannot go on, so the "
                      "batch ends (finished cases stay complete: run the plan again to resume)",
                      1)
        time.sleep(0.05)
    texts = err_comm.allgather((isinstance(exc, PilegroupError), text))
    return next((t for ours, t in texts if ours), texts[0][1])


def _run_case(rc: ResolvedCase, run_dir: Path, group: MPI.Comm, err_comm: MPI.Comm,
              world: MPI.Comm, options: dict[str, str], memory_mb: float) -> bool:
    """Run one case on ``group`` into its locked, emptied ``run_dir``; False if not run.

    The first rank records the case. False (on every rank of the group) when another run holds
    the folder: the case is not run and its folder is left alone.
    """
    try:
        with folder_lock(run_dir, group):
            _run_locked_case(rc, run_dir, group, err_comm, world, options, memory_mb)
    except FolderBusy as exc:
        if group.rank == 0:
            log.warning("case %s not run: %s", rc.name, exc)
        return False
    return True


def _run_locked_case(rc: ResolvedCase, run_dir: Path, group: MPI.Comm, err_comm: MPI.Comm,
                     world: MPI.Comm, options: dict[str, str], memory_mb: float) -> None:
    start = time.time()
    if group.rank == 0:
        empty_folder(run_dir)
        write_record(run_dir, rc, "running", start=start, ranks=group.size)
    group.Barrier()
    release_memory(group)
    rss_at_start = max(group.allgather(rss_mb()))  # what the group still holds
    scope = "case" if reset_peak_rss() else "process"
    restore_petsc_options(options)
    status, message = "complete", None
    try:
        run_scenario(rc.scenario, run_dir, comm=group, memory_mb=memory_mb)
    except RunInterrupted as exc:  # the group's ranks stop together at a step boundary
        status, message = "interrupted", str(exc)
    except Exception as exc:  # noqa: BLE001 - recorded; the batch goes on (or aborts, above)
        log.debug("case %s failed", rc.name, exc_info=True)
        status, message = "failed", _agree(exc, group, err_comm, world, rc, run_dir,
                                           start)
        if group.rank == 0:
            log.warning("case %s failed: %s", rc.name, message)
    if group.rank == 0:
        write_record(run_dir, rc, status, start=start, end=time.time(), ranks=group.size,
                     message=message, peak_rss_scope=scope,
                     rss_at_start_mb=round(rss_at_start, 1))


class _Monitor:
    """World rank 0: keeps the rows, ``batch.json``/``batch.csv`` and the progress current."""

    def __init__(self, cases: tuple[ResolvedCase, ...], out: Path, skipped: list[bool],
                 head: dict[str, Any], progress: bool) -> None:
        self.cases, self.out, self.skipped, self.head = cases, out, skipped, head
        self.rows = [case_row(rc, out / rc.name, s) for rc, s in zip(cases, skipped,
                                                                     strict=True)]
        self._stamps: dict[int, tuple[int, int] | None] = {}
        self._lock = threading.Lock()
        self._stop = threading.Event()
        self.t0 = time.monotonic()
        self.bar = tqdm(total=len(cases), desc="batch", unit="case", disable=not progress,
                        bar_format="{desc}: {n}/{total} cases |{bar}| {elapsed}{postfix}")
        self.refresh()
        self._thread = threading.Thread(target=self._loop, name="batch-monitor", daemon=True)
        self._thread.start()

    def _loop(self) -> None:
        while not self._stop.wait(POLL_S):
            try:
                self.refresh()
            except Exception:  # noqa: BLE001 - the watcher must not end the batch
                log.warning("batch monitor: could not refresh the tables", exc_info=True)

    def _stamp(self, i: int) -> tuple[int, int] | None:
        try:
            st = (self.out / self.cases[i].name / RECORD).stat()
        except OSError:
            return None
        return (st.st_mtime_ns, st.st_ino)

    def refresh(self) -> None:
        """Re-read the cases whose record changed; rewrite the tables if any did."""
        with self._lock:
            changed = False
            for i, rc in enumerate(self.cases):
                stamp = self._stamp(i)
                if i in self._stamps and stamp == self._stamps[i]:
                    continue
                self._stamps[i] = stamp
                old = self.rows[i]["status"]
                self.rows[i] = case_row(rc, self.out / rc.name, self.skipped[i])
                changed = True
                if old != self.rows[i]["status"] and self.rows[i]["status"] in (
                        "complete", "failed", "interrupted"):
                    self._announce(self.rows[i])
            if changed:
                head = {**self.head, "elapsed_s": time.monotonic() - self.t0}
                write_tables(self.out, self.rows, head)
                self._show()

    def _announce(self, row: dict[str, Any]) -> None:
        wall = f" in {row['wall_s']:.1f} s" if row.get("wall_s") is not None else ""
        why = f": {row['message']}" if row["status"] in ("failed", "interrupted") else ""
        self.bar.write(f"batch: case {row['name']} {row['status']}{wall}{why}", file=sys.stderr)

    def _show(self) -> None:
        c = counts(self.rows)
        self.bar.n = c["complete"] + c["failed"]
        todo = [r for r, s in zip(self.rows, self.skipped, strict=True) if not s]
        total = sum(r["estimated_cells"] for r in todo) or 1
        done = sum(r["estimated_cells"] for r in todo if r["status"] in ("complete", "failed"))
        elapsed = time.monotonic() - self.t0
        eta = "?" if done == 0 else tqdm.format_interval(elapsed * (total - done) / done)
        self.bar.set_postfix_str(f"running {c['running']}, failed {c['failed']}, "
                                 f"estimate {eta} left", refresh=True)

    def finish(self) -> list[BatchRow]:
        """Stop watching, refresh once more and close the progress bar; the rows."""
        self._stop.set()
        self._thread.join()
        self._stamps.clear()
        self.refresh()
        self.bar.close()
        return self.rows


@contextmanager
def _quiet_runs() -> Iterator[None]:
    """No progress bar of each run (the batch shows its own); the setting restored after."""
    before = os.environ.get(PROGRESS_ENV)
    os.environ[PROGRESS_ENV] = "0"
    try:
        yield
    finally:
        if before is None:
            os.environ.pop(PROGRESS_ENV, None)
        else:
            os.environ[PROGRESS_ENV] = before


def _wait_for_all(comm: MPI.Comm) -> None:
    """A barrier that sleeps instead of spinning while other groups still run cases."""
    req = comm.Ibarrier()
    while not req.Test():
        time.sleep(0.2)


def _prepare(cases: tuple[ResolvedCase, ...], out: Path, comm: MPI.Comm
             ) -> tuple[list[bool], Path]:
    """Which cases are complete already, and a fresh queue folder (rank 0 decides)."""
    data = None
    if comm.rank == 0:
        skipped = [is_complete(out / rc.name, rc.digest) for rc in cases]
        shutil.rmtree(out / ".queue", ignore_errors=True)
        qdir = out / ".queue" / uuid.uuid4().hex
        qdir.mkdir(parents=True)
        data = (skipped, qdir)
    return comm.bcast(data, root=0)


def run_batch(plan: BatchPlan, out: str | Path, ranks_per_case: int = 1,
              comm: MPI.Comm = MPI.COMM_WORLD, progress: bool = True,
              memory_mb: float | None = None) -> BatchResult:
    """Run every case of ``plan`` not yet complete under ``out``; collective over ``comm``.

    ``memory_mb``: the memory the batch may use on each node (``--memory``; else what the node
    has available when the batch starts), shared among the cases that run side by side
    (:func:`~pilegroup.studies.run.memory_check.case_memory_mb`): each case's memory check,
    and ``auto``'s turn to the out-of-core LU, use that share.

    Raises :class:`~pilegroup.errors.ScenarioError` (on every rank, before anything runs) for
    an invalid case or a ``ranks_per_case`` that does not divide ``comm.size``.
    """
    out = Path(out)
    group = split_world(comm, ranks_per_case)
    cases = resolve_cases(plan)
    skipped, qdir = _prepare(cases, out, comm)
    queue = _Queue(qdir, [i for i in queue_order(cases) if not skipped[i]])
    monitor = None
    if comm.rank == 0:
        head = {"plan": plan.name, "scenario": plan.scenario, "ranks": comm.size,
                "ranks_per_case": ranks_per_case, "groups": comm.size // ranks_per_case,
                "host": platform.node(), "started": time.strftime("%Y-%m-%dT%H:%M:%S"),
                "queue": "largest estimated mesh first"}
        monitor = _Monitor(cases, out, skipped, head, progress)
    case_mb = case_memory_mb(comm, group, memory_mb)
    err_comm = group.Dup()
    options = PETSc.Options().getAll()
    busy = 0  # cases whose folder another run held (counted by each group's first rank)
    with _quiet_runs(), logging_redirect_tqdm() if monitor and progress else nullcontext():
        while (index := group.bcast(queue.claim() if group.rank == 0 and not
                                    interrupt.requested() else None)) is not None:
            if not _run_case(cases[index], out / cases[index].name, group, err_comm, comm,
                             options, case_mb) and group.rank == 0:
                busy += 1
        _wait_for_all(comm)
        rows = monitor.finish() if monitor is not None else []
    if comm.rank == 0:
        shutil.rmtree(qdir.parent, ignore_errors=True)
    failed = comm.bcast(counts(rows)["failed"] if comm.rank == 0 else None, root=0)
    failed += comm.allreduce(busy)
    signum = comm.allreduce(interrupt.requested(), op=MPI.MAX)
    err_comm.Free()
    group.Free()
    return BatchResult(rows, failed, signum)


__all__ = ["AGREE_TIMEOUT_S", "BatchResult", "reset_peak_rss", "restore_petsc_options",
           "run_batch", "split_world", "write_record"]
