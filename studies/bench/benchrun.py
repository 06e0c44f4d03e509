"""Benchmarks that run ``pilegroup run`` once per case, each case in its own process group.

Shared by ``pilegroup bench pier`` and ``pilegroup bench stability``: the command of one run (on
N ranks), running it under a timeout (a crash or a hang ends that case, not the benchmark), the
line that says why a run failed, and the table of the cases as Markdown and JSON.
"""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pilegroup.fileio import read_json, write_json_atomic, write_text_atomic

#: Environment variables of an MPI launcher (MPICH's Hydra, Open MPI, PMIx). A run started from
#: a rank of an ``mpirun`` job must not inherit them, or it tries to join that job.
LAUNCHER_PREFIXES = ("PMI_", "HYDRA_", "MPIR_", "MPI_LOCAL", "OMPI_", "PMIX_")


def run_command(scenario: str | Path, out: Path, sets: Sequence[str] = (), ranks: int = 1,
                mesh_size: float | None = None) -> list[str]:
    """``[mpirun -n RANKS] python -m pilegroup run SCENARIO --out OUT [--set KEY=VALUE ...]``."""
    cmd = [sys.executable, "-m", "pilegroup", "run", str(scenario), "--out", str(out)]
    if mesh_size is not None:
        cmd += ["--mesh-size", f"{mesh_size:g}"]
    cmd += [a for kv in sets for a in ("--set", kv)]
    if ranks == 1:
        return cmd
    return [str(Path(sys.executable).parent / "mpirun"), "-n", str(ranks), *cmd]


def launcher_free_env(extra: Mapping[str, str] | None = None) -> dict[str, str]:
    """The environment of the current process without the MPI launcher's variables.

    ``extra``: variables to set on top (e.g. the mesh cache folder).
    """
    env = {k: v for k, v in os.environ.items() if not k.startswith(LAUNCHER_PREFIXES)}
    return {**env, **(extra or {})}


@dataclass(frozen=True)
class Finished:
    """How one process ended: exit code (``None`` when killed at the timeout), output, wall."""

    returncode: int | None
    stdout: str
    stderr: str
    wall_s: float

    @property
    def timed_out(self) -> bool:
        """The process was killed at the timeout."""
        return self.returncode is None


def run_isolated(cmd: Sequence[str], timeout: float | None = None,
                 env: Mapping[str, str] | None = None) -> Finished:
    """Run ``cmd`` in a new session (its own process group) and wait at most ``timeout`` s.

    At the timeout the whole group is killed (``mpirun`` and its ranks alike), so a hung case
    leaves no process behind. ``env``: default :func:`launcher_free_env`.
    """
    t0 = time.perf_counter()
    proc = subprocess.Popen(list(cmd), stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=True, env=dict(env or launcher_free_env()))
    try:
        out, err = proc.communicate(timeout=timeout)
        code: int | None = proc.returncode
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        out, err = proc.communicate()
        code = None
    return Finished(code, out or "", err or "", time.perf_counter() - t0)


def error_line(fin: Finished) -> str:
    """The line that says why a run failed: its last ``pilegroup:`` line, else its last line."""
    lines = [ln.strip() for ln in (fin.stderr + "\n" + fin.stdout).splitlines() if ln.strip()]
    tagged = [ln for ln in lines if ln.startswith("pilegroup:")]
    return (tagged or lines or ["no output"])[-1]



def markdown_table(rows: Sequence[Mapping[str, Any]], columns: Sequence[str]) -> str:
    """The rows as a Markdown table of ``columns`` (a missing value is an empty cell)."""
    head = "| " + " | ".join(columns) + " |\n|" + "---|" * len(columns) + "\n"
    return head + "".join(
        "| " + " | ".join("" if r.get(c) is None else str(r.get(c)).replace("|", "\\|")
                          for c in columns) + " |\n" for r in rows)


def write_table(out: Path, name: str, rows: Sequence[Mapping[str, Any]], columns: Sequence[str],
                header: str) -> str:
    """Write ``NAME.json`` (the rows) and ``NAME.md`` (``header`` and the table) to ``out``.

    Prints the Markdown and returns it.
    """
    write_json_atomic(out / f"{name}.json", list(rows))
    text = header + "\n\n" + markdown_table(rows, columns)
    write_text_atomic(out / f"{name}.md", text)
    print(text, flush=True)
    return text


__all__ = ["LAUNCHER_PREFIXES", "Finished", "error_line", "launcher_free_env", "markdown_table",
           "read_json", "run_command", "run_isolated", "write_table"]
