"""Benchmark of the whole pier job per mesh size and symmetry: cost against size.

Each (size, symmetry) is one ``pilegroup run`` in its own process group (``mpirun -n RANKS``),
so its peak memory is its own. The table: cells, unknowns, linear-solver preset, Newton and
Krylov iterations, LU factorisations, wall time (s) of the whole run (meshing, solve, plots),
peak resident memory of the largest rank and of all ranks (MB, ``getrusage``), and the
settlement at the last output time. Results go to ``bench_pier.json`` and ``bench_pier.md`` in
the output folder; failed runs are rows with their status and the last line of their error.
"""

from __future__ import annotations

import json
import platform
import subprocess
import sys
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pilegroup.fileio import write_json_atomic, write_text_atomic

COLUMNS = ("h_m", "symmetry", "status", "cells", "dofs", "preset", "newton", "krylov",
           "factorisations", "wall_s", "peak_rss_rank_mb", "peak_rss_total_mb",
           "settlement_mm")


def _command(scenario: str, h: float, symmetry: str, ranks: int, out: Path) -> list[str]:
    run = [sys.executable, "-m", "pilegroup", "run", scenario, "--mesh-size", f"{h:g}",
           "--out", str(out)]
    if symmetry != "auto":
        run += ["--set", f"numerics.symmetry='{symmetry}'"]
    if ranks == 1:
        return run
    return [str(Path(sys.executable).parent / "mpirun"), "-n", str(ranks), *run]


def _row(h: float, symmetry: str, out: Path, wall: float, proc: subprocess.CompletedProcess
         ) -> dict[str, Any]:
    row: dict[str, Any] = {"h_m": h, "symmetry": symmetry, "wall_s": round(wall, 1)}
    path = out / "summary.json"
    if proc.returncode != 0 or not path.is_file():
        tail = (proc.stderr or proc.stdout or "").strip().splitlines()
        return {**row, "status": f"failed (exit {proc.returncode}): "
                f"{tail[-1] if tail else 'no output'}"}
    s = json.loads(path.read_text())
    sol = s["solver"]
    rss = sol.get("peak_rss_mb_per_rank", [])
    return {**row, "status": "complete" if sol.get("complete") else "incomplete",
            "symmetry": sol.get("symmetry", symmetry), "cells": s["mesh"]["cells"],
            "dofs": sol["dofs"], "preset": sol["linear_solver"],
            "newton": sol["newton_iterations"], "krylov": sol["ksp_iterations"],
            "factorisations": sol["lu_factorisations"],
            "peak_rss_rank_mb": round(max(rss), 0) if rss else None,
            "peak_rss_total_mb": round(sum(rss), 0) if rss else None,
            "settlement_mm": round(1000.0 * sol["settlement_m"][-1]["settlement_m"], 4)}


def markdown(rows: Sequence[dict[str, Any]], ranks: int) -> str:
    """The rows as a Markdown table with the machine and the date."""
    head = "| " + " | ".join(COLUMNS) + " |\n|" + "---|" * len(COLUMNS) + "\n"
    body = "".join("| " + " | ".join("" if r.get(c) is None else str(r.get(c)) for c in COLUMNS)
                   + " |\n" for r in rows)
    return (f"{time.strftime('%Y-%m-%d')}, {platform.node()} ({platform.machine()}), "
            f"{ranks} MPI ranks\n\n" + head + body)


def bench_pier(scenario: str = "pier667", sizes: Sequence[float] = (1.0,),
               symmetries: Sequence[str] = ("auto",), ranks: int = 2,
               out_dir: str | Path = "out/bench_pier") -> list[dict[str, Any]]:
    """Run the job for every (size, symmetry); print and write the table; returns the rows."""
    out = Path(out_dir)
    rows = []
    for h in sizes:
        for sym in symmetries:
            case = out / f"h{h:g}_{sym}"
            t0 = time.perf_counter()
            proc = subprocess.run(_command(scenario, h, sym, ranks, case), capture_output=True,
                                  text=True)
            rows.append(_row(h, sym, case, time.perf_counter() - t0, proc))
            print(json.dumps(rows[-1]), flush=True)
    write_json_atomic(out / "bench_pier.json", rows)
    text = markdown(rows, ranks)
    write_text_atomic(out / "bench_pier.md", text)
    print(text)
    return rows
