"""Stop requests by SIGTERM, SIGINT and SIGUSR1, honoured by a run at its next step boundary.

SIGUSR1 is the stop request that every ``mpirun`` forwards to the ranks: Open MPI's (PRRTE)
answers SIGTERM and SIGINT by killing the ranks at once, without a grace period, and forwards
SIGUSR1; MPICH's Hydra forwards all three (docs/checkpoint.md, "Signals"). Batch schedulers
send it ahead of a time limit (Slurm's ``--signal=USR1@...``).

The handlers only record the signal (a Python handler runs between bytecodes of the main
thread, so never inside a PETSc call or an MPI collective); the run reads :func:`requested`
at each step boundary, all-reduced over the ranks (:mod:`pilegroup.studies.run.checkpoint`), and
every rank stops there together. A second signal while the first is pending ends the process
at once with the default action (the last checkpoint written stays valid).
"""

from __future__ import annotations

import os
import signal
import sys
import time
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

#: The signals that ask a run to stop and save a checkpoint.
STOP_SIGNALS = (signal.SIGTERM, signal.SIGINT, signal.SIGUSR1)

_pending: list[int] = []


def _handler(signum: int, frame: FrameType | None) -> None:
    """Record ``signum``; on a second signal, restore the default action and re-raise it."""
    if _pending:
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_DFL)
        os.kill(os.getpid(), signum)
        return
    _pending.append(signum)


def requested() -> int:
    """The number of the stop signal received by this process, or 0."""
    return _pending[0] if _pending else 0


@contextmanager
def stop_on_signals() -> Iterator[None]:
    """Within the block, the stop signals request a stop instead of ending the process."""
    _pending.clear()
    previous = {s: signal.signal(s, _handler) for s in STOP_SIGNALS}
    try:
        yield
    finally:
        for s, h in previous.items():
            signal.signal(s, h)
        _pending.clear()


def signal_name(signum: int) -> str:
    """``"SIGTERM"`` for 15, and so on."""
    return signal.Signals(signum).name


#: Seconds the launcher gets to forward a last line before ``MPI_Abort`` kills the job: without
#: the pause, MPICH's hydra sometimes ends the job before the line has left the rank's pipe.
FORWARD_PAUSE_S = 1.0


def abort_job(line: str, code: int) -> None:
    """Print ``line`` on stderr, then end every rank of the job with exit ``code``."""
    from mpi4py import MPI

    print(line, file=sys.stderr, flush=True)
    time.sleep(FORWARD_PAUSE_S)
    MPI.COMM_WORLD.Abort(code)
