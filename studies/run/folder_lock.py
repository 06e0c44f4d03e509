"""One run per output folder: an OS lock on ``OUT/.pilegroup.lock`` for the run's life.

Two runs writing into one folder would interleave their CSV rows, overwrite each other's
checkpoints and leave a ``summary.json`` of either. So a run takes an exclusive, non-blocking
``fcntl.flock`` on the folder's lock file before it reads or writes anything there, holds it
until it ends and then removes the file. The kernel releases the lock of a process that dies,
however it dies (SIGKILL included), so a lock can never be left held by a dead run; the
file's content (JSON: PID, host, start time, command) only names the holder:

* a second run (or batch case) into the folder finds the lock held and stops at once with a
  :class:`~pilegroup.errors.FolderBusy` naming the folder and the holder;
* a lock file whose lock is free was left by a run that was killed; the next run takes it
  over with one warning line naming the run that left it.

Under MPI only rank 0 of the run's communicator takes the lock and broadcasts the outcome, so
every rank raises alike. Re-entry is a no-op: a batch holds its case folder's lock and calls
:func:`~pilegroup.studies.run.job.run_scenario` on the same folder. ``flock`` locks are honoured
by local file systems and, on Linux, by NFS (as ``fcntl`` byte-range locks).
"""

from __future__ import annotations

import fcntl
import json
import logging
import os
import platform
import shutil
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

from mpi4py import MPI

from pilegroup.errors import FolderBusy, ScenarioError
from pilegroup.studies.run.watchdog import LOCK_FILE

log = logging.getLogger(__name__)

#: The folders whose lock this process holds (resolved path -> file descriptor).
_held: dict[Path, int] = {}


def _read(fd: int) -> str:
    """The text of the lock file open as ``fd``."""
    return os.pread(fd, 4096, 0).decode("utf-8", errors="replace")


def holder(text: str) -> str:
    """The run named by a lock file's content, e.g. ``PID 1234 on host n1, started ...``."""
    try:
        who = json.loads(text)
        return f"PID {who['pid']} on host {who['host']}, started {who['started']}"
    except (ValueError, TypeError, KeyError):
        return "a process that has not yet written its name"


def _ended(text: str) -> str:
    """How a lock file's former holder, whose lock is free, is described."""
    try:
        who = json.loads(text)
        pid = int(who["pid"])
        if who["host"] == platform.node() and pid > 0:
            os.kill(pid, 0)  # signal 0: only asks whether the process exists
            return "which no longer holds it (its PID names another process now)"
    except PermissionError:
        return "which no longer holds it (its PID names another process now)"
    except (ProcessLookupError, ValueError, TypeError, KeyError, OverflowError):
        pass
    return "which has ended"


def _acquire(folder: Path) -> tuple[int | None, str]:
    """Lock ``folder``: (descriptor, the content left by a former holder) or (None, holder's).

    A holder that releases removes the file first; if that happened between our ``open`` and
    ``flock``, our descriptor locks a removed file, so we open the path again.
    """
    folder.mkdir(parents=True, exist_ok=True)
    path = folder / LOCK_FILE
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            text = _read(fd)
            os.close(fd)
            return None, text
        try:
            if os.fstat(fd).st_ino == path.stat().st_ino:
                break
        except FileNotFoundError:
            pass
        os.close(fd)
    old = _read(fd)
    me = json.dumps({"pid": os.getpid(), "host": platform.node(),
                     "started": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
                     "command": " ".join(sys.argv)})
    os.ftruncate(fd, 0)
    os.pwrite(fd, me.encode() + b"\n", 0)
    return fd, old


def _release(folder: Path) -> None:
    """Remove the lock file and release the lock (in this order: see :func:`_acquire`)."""
    fd = _held.pop(folder)
    (folder / LOCK_FILE).unlink(missing_ok=True)
    os.close(fd)


def _take(folder: Path) -> tuple[bool, str | None]:
    """Rank 0: (taken by this call, the refusal message or ``None``)."""
    if folder in _held:
        return False, None
    try:
        fd, text = _acquire(folder)
    except OSError as exc:
        return False, f"cannot be locked for this run: {exc.strerror or exc}"
    if fd is None:
        return False, (f"is in use by another run ({holder(text)}); wait for it to end or "
                       "choose another --out")
    _held[folder] = fd
    if text.strip():
        log.warning("taking over the lock of %s left by %s, %s", folder, holder(text),
                    _ended(text))
    return True, None


@contextmanager
def folder_lock(out: Path, comm: MPI.Comm = MPI.COMM_WORLD) -> Iterator[None]:
    """Hold the lock of the output folder ``out`` (created if needed) within the block.

    Collective over ``comm``: rank 0 locks, every rank raises alike
    :class:`~pilegroup.errors.FolderBusy` when another run holds it (or a
    :class:`~pilegroup.errors.ScenarioError` when the folder cannot be made or locked).
    """
    folder = Path(out).resolve()
    taken, refusal = _take(folder) if comm.rank == 0 else (False, None)
    refusal = comm.bcast(refusal, root=0)
    if refusal is not None:
        cls = FolderBusy if refusal.startswith("is in use") else ScenarioError
        raise cls("--out", str(out), refusal)
    try:
        yield
    finally:
        if taken:
            _release(folder)


def held_fd(out: Path) -> int | None:
    """The descriptor of the lock file of ``out`` if this process holds it, else ``None``."""
    return _held.get(Path(out).resolve())


def empty_folder(folder: Path) -> None:
    """Remove everything in ``folder`` except its lock file (a batch case run again)."""
    for entry in Path(folder).iterdir():
        if entry.name == LOCK_FILE:
            continue
        if entry.is_dir() and not entry.is_symlink():
            shutil.rmtree(entry)
        else:
            entry.unlink()
