"""A run's watchdog: ``summary.json`` ``failed`` and the folder's lock freed when a rank dies.

A rank killed by a signal (an ``abort()`` or a segmentation fault in a library, the kernel's
out-of-memory kill, ``mpirun`` ending the other ranks after one died) runs no more Python, so
neither :func:`~pilegroup.studies.run.job.run_scenario`'s failure record nor the folder lock's
release runs. So while a run holds its folder (:func:`watched`):

* rank 0 of the run's communicator starts this file as a process of the standard library alone
  (``python -I -S watchdog.py``: no MPI; in a session of its own, so that neither a launcher's
  kill of the rank's process group nor a terminal's Ctrl-C reaches it; the stop signals
  ignored). It shares the folder lock's open file, so the lock stays held until it has
  written, and waits on a pipe that rank 0 never writes to. At the block's end rank 0 kills it
  (SIGKILL) before closing the pipe.
* the pipe's end (or rank 0 no longer its parent) therefore means that rank 0 died. Unless
  ``summary.json`` was rewritten since the block began as ``failed`` or ``interrupted`` (the
  run's own record: a Python error on one rank writes it before ending the job), the watchdog
  writes it ``failed`` with the reason in one line and prints ``pilegroup: run failed:
  REASON`` on its standard error (the rank's); then it removes the lock file and releases the
  lock.
* every rank turns :mod:`faulthandler` on into ``OUT/.pilegroup.rank<R>.fatal``: a fatal
  signal (SIGABRT, SIGSEGV, SIGFPE, SIGBUS, SIGILL) writes its name and the Python stack there
  before the process dies, so the reason names the rank, the signal and the innermost Python
  frame (``rank 1 of 2 died: Fatal Python error: Aborted, in broken (<string>, line 6)`` for
  an ``os.abort()`` in a function ``broken``). A rank killed by SIGKILL (out of memory, or by
  the launcher after another rank died) leaves its file empty, and the reason says that rank 0
  ended without a Python error. The files are removed at the block's end, or by the watchdog.

The cost to a run: one process start (its Python starts in about 0.1 s, beside the run) and
one empty file per rank; nothing while it runs. MPICH's Hydra (the ``mpirun`` of the PyPI
wheels) waits for the watchdog too, whose standard error is the rank's: ``summary.json`` is
written when ``mpirun`` returns. A launcher that returns as soon as the ranks are gone may
return a few milliseconds before; the folder's lock stays held until then.
"""

from __future__ import annotations

import faulthandler
import json
import logging
import os
import select
import signal
import subprocess
import sys
import tempfile
import time
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

log = logging.getLogger(__name__)

SUMMARY = "summary.json"
LOCK_FILE = ".pilegroup.lock"
#: The files faulthandler writes to, innermost block last, after what it wrote to before the
#: outermost block (``sys.__stderr__`` when it was on, e.g. under pytest, else None).
_fatal_files: list[Any] = []
#: Seconds between the watchdog's checks that rank 0 still lives (when the pipe stays open).
POLL_S = 1.0


def fatal_file(out: Path, rank: int) -> Path:
    """The file a rank's fatal signal writes its name and stack to."""
    return Path(out) / f".pilegroup.rank{rank}.fatal"


@contextmanager
def watched(out: Path, comm: Any, scenario: str, t0: float,
            lock_fd: int | None) -> Iterator[None]:
    """Within the block, a rank's death by a signal still leaves ``summary.json`` ``failed``.

    ``comm``: the run's communicator (any object with ``rank`` and ``size``); ``t0``: the run's
    start (``time.perf_counter``); ``lock_fd``: rank 0's descriptor of the folder's lock file
    (``None``: the watchdog writes the summary but frees no lock).
    """
    out = Path(out)
    fatal = _enable_fatal_file(out, comm.rank)
    proc, pipe = None, None
    if comm.rank == 0:
        proc, pipe = _start(out, scenario, comm.size, time.time() - (time.perf_counter() - t0),
                            lock_fd)
    try:
        yield
    finally:
        if pipe is not None:
            _stop(proc, pipe)
        _disable_fatal_file(fatal)


def _enable_fatal_file(out: Path, rank: int) -> Any:
    """Turn :mod:`faulthandler` on into this rank's file; returns the open file, or None."""
    try:
        fh = open(fatal_file(out, rank), "w")  # noqa: SIM115 (open for the block's life)
    except OSError as exc:
        log.warning("no record of a fatal signal on rank %d: %s", rank, exc)
        return None
    if not _fatal_files:
        _fatal_files.append(sys.__stderr__ if faulthandler.is_enabled() else None)
    _fatal_files.append(fh)
    faulthandler.enable(file=fh, all_threads=False)
    return fh


def _disable_fatal_file(fh: Any) -> None:
    """Back to :mod:`faulthandler`'s state before :func:`_enable_fatal_file`; remove the file."""
    if fh is None:
        return
    faulthandler.disable()
    _fatal_files.remove(fh)
    fh.close()
    Path(fh.name).unlink(missing_ok=True)
    previous = _fatal_files[-1]
    if len(_fatal_files) == 1:
        _fatal_files.clear()
    if previous is not None:
        faulthandler.enable(file=previous)


def _start(out: Path, scenario: str, ranks: int, start_epoch: float,
           lock_fd: int | None) -> tuple[subprocess.Popen | None, int | None]:
    """Start the watchdog: (the process, the pipe's write end), or (None, None) if it failed."""
    r, w = os.pipe()
    spec = {"out": str(out.resolve()), "scenario": scenario, "ranks": ranks,
            "start": start_epoch, "pipe": r, "lock": -1 if lock_fd is None else lock_fd,
            "parent": os.getpid(), "summary": _stat(out / SUMMARY)}
    try:
        proc = subprocess.Popen(
            [sys.executable, "-I", "-S", __file__, json.dumps(spec)],
            pass_fds=(r,) if lock_fd is None else (r, lock_fd), stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL, start_new_session=True)
    except OSError as exc:
        os.close(w)
        log.warning("no watchdog for this run (a rank killed by a signal will leave no "
                    "summary.json): %s", exc)
        return None, None
    finally:
        os.close(r)
    return proc, w


def _stop(proc: subprocess.Popen, pipe: int) -> None:
    """End the watchdog of a block that ended normally (before it can see the pipe close)."""
    proc.kill()
    proc.wait()
    os.close(pipe)


# ---- the watchdog process (standard library only: it runs without site-packages) -------------


def _watch(spec: dict[str, Any]) -> int:
    """Wait for rank 0's end; then record the failure and free the lock.

    Rank 0 never writes to the pipe: its end (or rank 0's PID no longer this process's
    parent) means that rank 0 died, since a block that ends normally kills this process first.
    """
    for s in (signal.SIGTERM, signal.SIGINT, signal.SIGUSR1, signal.SIGHUP):
        signal.signal(s, signal.SIG_IGN)
    out = Path(spec["out"])
    while os.getppid() == spec["parent"]:
        ready, _, _ = select.select([spec["pipe"]], [], [], POLL_S)
        if ready and not os.read(spec["pipe"], 64):
            break
    reason, rank = _reason(out, spec["ranks"])
    if _own_record(out / SUMMARY, spec["summary"]):
        reason = None
    else:
        _write_json(out / SUMMARY, {
            "scenario": spec["scenario"], "status": "failed", "reason": reason, "rank": rank,
            "ranks": spec["ranks"], "wall_s": time.time() - spec["start"],
            "solver_summary": "summary_solver.json (written up to the last output time)"})
    for k in range(spec["ranks"]):
        fatal_file(out, k).unlink(missing_ok=True)
    if spec["lock"] >= 0:
        _release(out / LOCK_FILE, spec["lock"])
    if reason is not None:
        _say(f"pilegroup: run failed: {reason}")
    return 0


def _stat(path: Path) -> list[int] | None:
    """[inode, modification time in ns] of ``path`` (as JSON gives it back), or None."""
    try:
        st = path.stat()
    except OSError:
        return None
    return [st.st_ino, st.st_mtime_ns]


def _own_record(summary: Path, before: list[int] | None) -> bool:
    """Whether the run wrote ``summary`` since its start (``before``), as a stop's record."""
    if _stat(summary) in (None, before):
        return False
    try:
        status = json.loads(summary.read_text(encoding="utf-8")).get("status")
    except (OSError, ValueError, AttributeError):
        return False
    return status in ("failed", "interrupted")


def _reason(out: Path, ranks: int) -> tuple[str, int | None]:
    """The failure in one line, and the rank that died of a fatal signal (None if unknown)."""
    for k in range(ranks):
        try:
            text = fatal_file(out, k).read_text(encoding="utf-8", errors="replace")
        except OSError:
            continue
        lines = [ln.strip() for ln in text.splitlines() if ln.strip()]
        if not lines:
            continue
        where = next((ln for ln in lines if ln.startswith("File ")), None)
        said = f", in {_frame(where)}" if where else ""
        who = f"rank {k} of {ranks}" if ranks > 1 else "the run"
        return f"{who} died: {lines[0]}{said}", k
    who = f"rank 0 of {ranks}" if ranks > 1 else "the run"
    return (f"{who} ended without a Python error: killed by a signal (by mpirun after "
            "another rank died, by the kernel when out of memory, or by a user); the "
            "launcher's output names the rank and the signal" if ranks > 1 else
            f"{who} ended without a Python error: killed by a signal (by the kernel when out "
            "of memory, or by a user)"), None


def _frame(line: str) -> str:
    """``File "/a/b.py", line 5 in f`` as ``f (b.py, line 5)``."""
    head, _, func = line.partition(" in ")
    parts = head.split('"')
    name = Path(parts[1]).name if len(parts) > 2 else head
    number = head.rsplit("line", 1)[-1].strip(" ,") if "line" in head else "?"
    return f"{func.strip() or '?'} ({name}, line {number})"


def _write_json(path: Path, data: dict[str, Any]) -> None:
    """``data`` as indented JSON, through a temporary file and a rename (as the run writes)."""
    tmp = None
    try:
        fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=path.suffix, dir=path.parent)
        with os.fdopen(fd, "w", encoding="utf-8") as fh:
            fh.write(json.dumps(data, indent=2) + "\n")
        mask = os.umask(0o022)
        os.umask(mask)
        os.chmod(tmp, 0o666 & ~mask)
        os.replace(tmp, path)
    except OSError as exc:
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
        _say(f"pilegroup: no summary.json of the failed run: {exc}")


def _say(line: str) -> None:
    """``line`` on standard error, if there is one."""
    try:
        print(line, file=sys.stderr, flush=True)
    except (OSError, ValueError, AttributeError):
        pass


def _release(path: Path, fd: int) -> None:
    """Remove the lock file (when it is still the one locked) and release the lock."""
    try:
        if os.fstat(fd).st_ino == path.stat().st_ino:
            path.unlink()
    except OSError:
        pass
    os.close(fd)


if __name__ == "__main__":
    sys.exit(_watch(json.loads(sys.argv[1])))
