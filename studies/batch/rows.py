"""The table of a batch: one row per case, read from the case's run folder and its record.

Each case's run folder (``<batch out>/<case>``) holds the files of ``pilegroup run``
(:mod:`pilegroup.studies.results.tables`, ``summary.json``, ``scenario.json``) and the batch's
record of the case, ``batch_case.json`` (status, start and end wall-clock times, message, ranks),
written by the rank that ran it. :func:`case_row` reads both; :func:`write_tables` writes every row
to ``batch.json`` (nested) and ``batch.csv`` (flat, one column per quantity and output time),
atomically.

Per case: the overrides, status, wall time, peak memory per rank, cells and unknowns, Newton and
Krylov iterations, and at every output time (``settlement.csv``): the cap settlement, each
pile's head force (``pile_loads.csv``) and the centre pile's layer-mean shaft friction and
relative displacement (``layer_history.csv``,
:func:`pilegroup.studies.results.rundata.layer_series`).
"""

from __future__ import annotations

import csv
import io
import json
import math
import time
from pathlib import Path
from typing import Any, TypedDict

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.fileio import read_json, write_json_atomic, write_text_atomic
from pilegroup.studies.batch.batch_plan import ResolvedCase, scenario_digest
from pilegroup.studies.results.rundata import layer_label, layer_series, load_run

RECORD = "batch_case.json"
BATCH_JSON = "batch.json"
BATCH_CSV = "batch.csv"
#: Columns of ``batch.csv`` before the overrides and the per-time columns.
HEAD = ("name", "status", "skipped", "message", "start", "end", "wall_s", "estimated_cells",
        "cells", "unknowns", "symmetry", "newton", "krylov", "peak_rss_mb_max",
        "peak_rss_mb_per_rank", "rss_at_start_mb")
#: The per-time quantities of a row: key -> CSV column stem.
SERIES = {"head_force_kN": "head_force_kN[pile {}]",
          "layer_friction_kPa": "shaft_friction_kPa[{}]",
          "layer_relative_displacement_m": "relative_displacement_m[{}]"}



class BatchRow(TypedDict, total=False):
    """One case of a batch (``batch.json``'s ``cases``; ``batch.csv`` flattens it)."""

    name: str
    status: str
    """``pending``, ``running``, ``complete``, ``failed`` or ``interrupted`` (stopped by
    SIGTERM, SIGINT or SIGUSR1 with a checkpoint; run again from the start by the next batch)."""
    skipped: bool
    """Complete before this batch started (not run again)."""
    message: str | None
    """Failed: why, one line."""
    overrides: dict[str, Any]
    """The case's scenario keys (dotted) and values."""
    run_dir: str
    start: float | None
    """Wall-clock start, seconds since the epoch."""
    end: float | None
    ranks: int | None
    peak_rss_scope: str | None
    """What the memory numbers cover (the case's own process group, or the batch's ranks)."""
    rss_at_start_mb: list[float] | None
    estimated_cells: int
    digest: str
    """Digest of the case's resolved scenario."""
    wall_s: float | None
    cells: int | None
    unknowns: int | None
    symmetry: str | None
    newton: int | None
    krylov: int | None
    peak_rss_mb_per_rank: list[float] | None
    peak_rss_mb_max: float | None
    run_wall_s: float | None
    reason: str | None
    output_days: list[float]
    settlement_m: list[float | None]
    """Cap settlement at each output day, m."""
    centre_pile: int
    head_force_kN: dict[str, list[float | None]]
    """Per pile (number as text): head force at each output day."""
    layer_friction_kPa: dict[str, list[float | None]]
    """Per layer (``"j name"``): the centre pile's mean shaft friction at each output day."""
    layer_relative_displacement_m: dict[str, list[float | None]]


def is_complete(run_dir: Path, digest: str) -> bool:
    """Whether ``run_dir`` holds a complete run of the scenario with this digest."""
    summary = read_json(run_dir / "summary.json")
    if summary is None or summary.get("status") != "complete":
        return False
    if (summary.get("solver") or {}).get("complete") is False:
        return False
    stored = read_json(run_dir / "scenario.json")
    return stored is not None and scenario_digest(stored) == digest


def _number(x: Any) -> float | None:
    return None if x is None or not math.isfinite(float(x)) else float(x)


def _at(times: np.ndarray, t: np.ndarray, v: np.ndarray) -> list[float | None]:
    """``v`` (given at ``t``) at each of ``times``; ``None`` where ``t`` has no such time."""
    out: list[float | None] = []
    for s in times:
        hit = np.flatnonzero(np.isclose(t, s, rtol=1e-9, atol=1e-12))
        out.append(_number(v[hit[-1]]) if hit.size else None)
    return out


def _results(run_dir: Path) -> dict[str, Any]:
    """Output times and the per-time quantities of a run folder (empty if it has none)."""
    try:
        run = load_run(run_dir)
    except ScenarioError:
        return {}
    if run.settlement is None:
        return {}
    times = run.settlement["t_day"]
    out: dict[str, Any] = {"output_days": [float(t) for t in times],
                           "settlement_m": [_number(w) for w in run.settlement["settlement_m"]],
                           "centre_pile": run.centre_pile}
    loads = run.loads
    out["head_force_kN"] = {} if loads is None else {
        str(int(p)): _at(times, loads["t_day"][loads["pile"] == p],
                         loads["head_force_kN"][loads["pile"] == p])
        for p in np.unique(loads["pile"])}
    for key, column in (("layer_friction_kPa", "shaft_friction_kPa"),
                        ("layer_relative_displacement_m", "relative_displacement_m")):
        out[key] = {layer_label(run, j): _at(times, t, v)
                    for j, (t, v) in layer_series(run, column).items()}
    return out


def _solver_numbers(run_dir: Path) -> dict[str, Any]:
    """Cells, unknowns, counts and memory from ``summary.json`` (or the partial solver one)."""
    summary = read_json(run_dir / "summary.json") or {}
    solver = summary.get("solver") or read_json(run_dir / "summary_solver.json") or {}
    rss = solver.get("peak_rss_mb_per_rank")
    sym = solver.get("symmetry")
    return {"cells": (summary.get("mesh") or {}).get("cells"), "unknowns": solver.get("dofs"),
            "symmetry": sym.get("model") if isinstance(sym, dict) else sym,
            "newton": solver.get("newton_iterations"), "krylov": solver.get("ksp_iterations"),
            "peak_rss_mb_per_rank": rss, "peak_rss_mb_max": max(rss) if rss else None,
            "run_wall_s": summary.get("wall_s"), "reason": summary.get("reason")}


def case_row(rc: ResolvedCase, run_dir: Path, skipped: bool = False) -> BatchRow:
    """The row of case ``rc``: its record (or ``pending``), solver numbers and results."""
    record = read_json(run_dir / RECORD) or {}
    status = record.get("status", "pending")
    if record.get("digest") not in (None, rc.digest):
        status = "pending"  # a record of another scenario under the same name
    if skipped:
        status = "complete"
    row: BatchRow = {"name": rc.name, "status": status, "skipped": skipped,
                           "message": record.get("message"), "overrides": rc.case.override_dict(),
                           "run_dir": str(run_dir), "start": record.get("start"),
                           "end": record.get("end"), "ranks": record.get("ranks"),
                           "peak_rss_scope": record.get("peak_rss_scope"),
                           "rss_at_start_mb": record.get("rss_at_start_mb"),
                           "estimated_cells": round(rc.cost), "digest": rc.digest}
    start, end = row["start"], row["end"]
    row["wall_s"] = None if start is None or end is None else end - start
    if status in ("complete", "failed", "interrupted"):
        row.update(_solver_numbers(run_dir))  # type: ignore[typeddict-item]
        row.update(_results(run_dir))  # type: ignore[typeddict-item]
        if row["wall_s"] is None:
            row["wall_s"] = row.get("run_wall_s")
        if status == "failed" and not row["message"]:
            row["message"] = row.get("reason")
    return row


def _flat(row: BatchRow, override_keys: list[str]) -> dict[str, Any]:
    out = {k: row.get(k) for k in HEAD}
    rss = row.get("peak_rss_mb_per_rank")
    out["peak_rss_mb_per_rank"] = ";".join(f"{x:.0f}" for x in rss) if rss else None
    for k in override_keys:
        v = row["overrides"].get(k)
        out[k] = json.dumps(v) if isinstance(v, list | dict) else v
    days = row.get("output_days") or []
    for i, t in enumerate(days):
        out[f"settlement_m@{t:g}d"] = row["settlement_m"][i]
    for key, stem in SERIES.items():
        for label, values in (row.get(key) or {}).items():
            for t, v in zip(days, values, strict=True):
                out[f"{stem.format(label)}@{t:g}d"] = v
    return out


def csv_text(rows: list[BatchRow]) -> str:
    """``batch.csv``: one row per case; the union of every row's columns, in first-seen order."""
    keys: list[str] = []
    for r in rows:
        keys += [k for k in r["overrides"] if k not in keys]
    flat = [_flat(r, keys) for r in rows]
    columns: list[str] = []
    for f in flat:
        columns += [c for c in f if c not in columns]
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=columns, lineterminator="\n")
    w.writeheader()
    for f in flat:
        w.writerow({c: "" if f.get(c) is None else f[c] for c in columns})
    return buf.getvalue()


def counts(rows: list[BatchRow]) -> dict[str, int]:
    """How many cases are in each status."""
    out = {s: 0 for s in ("complete", "failed", "interrupted", "running", "pending")}
    for r in rows:
        out[r["status"]] = out.get(r["status"], 0) + 1
    return out


def write_tables(out: Path, rows: list[BatchRow], head: dict[str, Any]) -> None:
    """Write ``batch.json`` (``head`` plus the rows) and ``batch.csv``, each atomically."""
    doc = {**head, "updated": time.strftime("%Y-%m-%dT%H:%M:%S"), "counts": counts(rows),
           "cases": rows}
    write_json_atomic(out / BATCH_JSON, doc)
    write_text_atomic(out / BATCH_CSV, csv_text(rows))


__all__ = ["BATCH_CSV", "BATCH_JSON", "RECORD", "BatchRow", "case_row", "counts", "csv_text",
           "is_complete", "read_json", "write_tables"]
