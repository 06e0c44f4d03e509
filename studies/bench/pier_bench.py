"""Benchmark of the whole pier job per scenario, mesh size and symmetry: cost against size.

Each (scenario, size, symmetry) is one ``pilegroup run`` in its own process group (``mpirun -n
RANKS``), so its peak memory is its own. The table: cells, unknowns, linear-solver preset,
Newton and Krylov iterations (in all, and of the hardest Newton solve), LU factorisations, wall
time (s) of the whole run (meshing, solve, plots), peak resident memory of the largest rank and
of all ranks (MB, ``getrusage``), and the settlement at the last output time. Results go to
``bench_pier.json`` and ``bench_pier.md`` in the output folder; failed runs are rows with their
status and the last line of their error. With several scenarios (e.g. ``pier667`` and
``pier667_soft_soil``) they run one after the other and ``wall_ratio`` is each run's wall time
over the first scenario's at the same size and symmetry: a cost compared within one run of the
benchmark, on the same machine.
"""

from __future__ import annotations

import json
import platform
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pilegroup.studies.bench.benchrun import (
    Finished,
    error_line,
    run_command,
    run_isolated,
    write_table,
)

COLUMNS = ("scenario", "h_m", "symmetry", "status", "cells", "dofs", "preset", "newton",
           "krylov", "krylov_max", "factorisations", "wall_s", "wall_ratio", "peak_rss_rank_mb",
           "peak_rss_total_mb", "settlement_mm")


def _command(scenario: str, h: float, symmetry: str, ranks: int, out: Path,
             sets: Sequence[str] = ()) -> list[str]:
    sym = [] if symmetry == "auto" else [f"numerics.symmetry='{symmetry}'"]
    return run_command(scenario, out, [*sets, *sym], ranks, mesh_size=h)


def _row(h: float, symmetry: str, out: Path, fin: Finished) -> dict[str, Any]:
    row: dict[str, Any] = {"h_m": h, "symmetry": symmetry, "wall_s": round(fin.wall_s, 1)}
    path = out / "summary.json"
    if fin.returncode != 0 or not path.is_file():
        code = "timeout" if fin.timed_out else f"exit {fin.returncode}"
        return {**row, "status": f"failed ({code}): {error_line(fin)}"}
    s = json.loads(path.read_text())
    sol = s["solver"]
    rss = sol.get("peak_rss_mb_per_rank", [])
    return {**row, "status": "complete" if sol.get("complete") else "incomplete",
            "symmetry": (sol.get("symmetry") or {}).get("model", symmetry),
            "cells": s["mesh"]["cells"],
            "dofs": sol["dofs"], "preset": sol["linear_solver"],
            "interface_mode": sol.get("interface_mode"),
            "newton": sol["newton_iterations"], "krylov": sol["ksp_iterations"],
            "krylov_max": sol.get("ksp_iterations_max_per_solve"),
            "factorisations": sol["lu_factorisations"],
            "peak_rss_rank_mb": round(max(rss), 0) if rss else None,
            "peak_rss_total_mb": round(sum(rss), 0) if rss else None,
            "settlement_mm": round(1000.0 * sol["settlement_m"][-1]["settlement_m"], 4)}


def _header(ranks: int, sets: Sequence[str] = ()) -> str:
    """The date, the machine, the ranks and the overrides (the line above the table)."""
    return (f"{time.strftime('%Y-%m-%d')}, {platform.node()} ({platform.machine()}), "
            f"{ranks} MPI ranks" + "".join(f"; --set {kv}" for kv in sets))


def bench_pier(scenarios: str | Sequence[str] = "pier667", sizes: Sequence[float] = (1.0,),
               symmetries: Sequence[str] = ("auto",), ranks: int = 2,
               out_dir: str | Path = "out/bench_pier", timeout: float | None = None,
               sets: Sequence[str] = ()) -> list[dict[str, Any]]:
    """Run the job for every (scenario, size, symmetry); print and write the table.

    ``timeout``: seconds each run may take (``None``: no limit); a run killed at the timeout
    is a row with its status. ``sets``: ``KEY=VALUE`` scenario overrides of every run.
    Returns the rows.
    """
    names = [scenarios] if isinstance(scenarios, str) else list(scenarios)
    out = Path(out_dir)
    rows: list[dict[str, Any]] = []
    first: dict[tuple[float, str], float] = {}
    for name in names:
        for h in sizes:
            for sym in symmetries:
                case = out / (f"h{h:g}_{sym}" if len(names) == 1 else f"{name}_h{h:g}_{sym}")
                fin = run_isolated(_command(name, h, sym, ranks, case, sets), timeout)
                row = {"scenario": name, **_row(h, sym, case, fin)}
                base = first.setdefault((h, sym), row["wall_s"])
                row["wall_ratio"] = round(row["wall_s"] / base, 2) if base else None
                rows.append(row)
                print(json.dumps(row), flush=True)
    write_table(out, "bench_pier", rows, COLUMNS, _header(ranks, sets))
    return rows
