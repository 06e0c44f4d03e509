"""The report of a mesh study: our sizes (beside a published study), GCI, cost, profiles, penalty.

Written by :func:`write_mesh_report` into the study's folder from the batch rows
(:mod:`pilegroup.studies.batch.rows`) and the cases' run folders:

* ``mesh_study.md``: the machine; our cells, unknowns, wall time, peak memory per rank and
  settlement per size; the sizes that did not run and why; the Richardson extrapolation,
  observed order and GCI (:mod:`pilegroup.studies.campaigns.gci`) of the cap settlement and of
  the centre pile's shaft friction (layer means, and the profile interpolated at the gauge
  depths) at the last output time, from the three finest sizes that ran; the penalty check;
* ``mesh_study.csv`` (one row per size) and ``gci.csv`` (one row per quantity);
* ``settlement_vs_h.png``, ``error_vs_time.png``, ``friction_profiles_sizes.png`` and
  ``relative_displacement_profiles_sizes.png``.

A published mesh study appears only where the scenario's ``[reference]`` carries one
(:class:`~pilegroup.model.reference.MeshStudyReference`, :attr:`StudyInfo.published`): its
elements, hours and settlements beside ours in the table and the CSV, its settlements in the
settlement figure and their own extrapolation in the report, its hours in the error figure.
"""

from __future__ import annotations

import csv
import io
import math
import os
import platform
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from pilegroup.errors import ScenarioError
from pilegroup.fileio import atomic_path, write_text_atomic
from pilegroup.model.reference import MeshStudyReference
from pilegroup.studies.batch.rows import BatchRow
from pilegroup.studies.campaigns.gci import GCIResult, gci
from pilegroup.studies.campaigns.mesh_records import PenaltyRow, SizeRow, StudyCase, StudyInfo
from pilegroup.studies.campaigns.mesh_report_md import SETTLEMENT, published_gci, report_markdown
from pilegroup.studies.results.rundata import load_run

FIGURES = ("settlement_vs_h.png", "error_vs_time.png", "friction_profiles_sizes.png",
           "relative_displacement_profiles_sizes.png")
GCI_COLUMNS = ("quantity", "h1_m", "h2_m", "h3_m", "phi1", "phi2", "phi3", "r21", "r32", "p",
               "phi_ext", "e_a21", "e_ext21", "gci_fine21", "note")


def machine_text(info: StudyInfo) -> str:
    """One line naming the machine, its cores and memory, and how the cases were run."""
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (f"{time.strftime('%Y-%m-%d')}, host {platform.node()}: {cpu}, {os.cpu_count()} "
            f"cores, {info.memory_mb / 1024:.1f} GB memory; {info.ranks} MPI ranks, "
            f"{info.ranks_per_case} per case ({info.ranks // info.ranks_per_case} cases at "
            "once; cases running side by side share the machine)")


def profile_at_last(run_dir: Path) -> tuple[float, dict[str, np.ndarray]] | None:
    """Time and the centre pile's profile columns (sorted by depth) at the last output time."""
    try:
        run = load_run(run_dir)
    except ScenarioError:
        return None
    if run.profiles is None:
        return None
    p = run.profiles
    t = float(p["t_day"].max())
    m = p["t_day"] == t
    order = np.argsort(p["depth_m"][m], kind="stable")
    return t, {k: v[m][order] for k, v in p.items()}


def final_quantities(row: dict[str, Any], gauges: Sequence[float]) -> dict[str, float]:
    """Settlement (m) and the centre pile's friction (kPa) at the last output time of a row."""
    out: dict[str, float] = {}
    if row.get("settlement_m"):
        out[SETTLEMENT] = row["settlement_m"][-1]
    for label, values in (row.get("layer_friction_kPa") or {}).items():
        if values and values[-1] is not None:
            out[f"friction_kPa[layer {label}]"] = values[-1]
    prof = profile_at_last(Path(row["run_dir"]))
    if prof is not None:
        z, tau = prof[1]["depth_m"], prof[1]["shaft_friction_kPa"]
        for g in gauges:
            out[f"friction_kPa[gauge {g:g} m]"] = float(np.interp(g, z, tau))
    return {k: v for k, v in out.items() if v is not None and math.isfinite(v)}


def _by_name(rows: Sequence[BatchRow]) -> dict[str, BatchRow]:
    return {r["name"]: r for r in rows}


def size_results(info: StudyInfo, rows: Sequence[BatchRow]
                 ) -> list[tuple[StudyCase, dict[str, Any], dict[str, float]]]:
    """The complete size cases (coarse to fine) with their rows and final quantities."""
    by = _by_name(rows)
    gauges = info.scenario.outputs.gauge_depths_m
    return [(c, by[c.name], final_quantities(by[c.name], gauges)) for c in info.cases
            if c.penalty == 1.0 and by.get(c.name, {}).get("status") == "complete"]


def gci_table(done: Sequence[tuple[StudyCase, dict[str, Any], dict[str, float]]]
              ) -> dict[str, GCIResult]:
    """GCI of every quantity the three finest complete sizes share."""
    if len(done) < 3:
        return {}
    fine = sorted(done, key=lambda d: d[0].h)[:3]
    keys = [k for k in fine[0][2] if all(k in d[2] for d in fine)]
    h = tuple(d[0].h for d in fine)
    return {k: gci(h, tuple(d[2][k] for d in fine)) for k in keys}  # type: ignore[arg-type]


def _fmt(x: Any, spec: str = ".4g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return ""
    return format(x, spec) if isinstance(x, int | float) else str(x)


def gci_csv(table: dict[str, GCIResult]) -> str:
    """``gci.csv``: one row per quantity (full precision)."""
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(GCI_COLUMNS)
    for k, g in table.items():
        w.writerow([k, *g.h, *g.phi, g.r21, g.r32, g.p, g.phi_ext, g.e_a21, g.e_ext21,
                    g.gci_fine21, g.note])
    return buf.getvalue()


def _status(h: float, info: StudyInfo, by: dict[str, dict[str, Any]]) -> tuple[str, dict]:
    check = next((c for c in info.checks if c.h == h), None)
    if check is not None and not check.runnable:
        return f"not run: {check.reason}", {}
    row = by.get(f"h{h:g}")
    if row is None:
        return "not in the study", {}
    if row["status"] == "failed":
        return f"failed: {row.get('message')}", row
    return row["status"], row


def _published_columns(pub: MeshStudyReference, h: float) -> dict[str, Any]:
    """The published study's elements, hours and settlement (cm) at size ``h`` (None: absent)."""
    settle = pub.at(pub.settlements_m, h)
    return {"published_elements": pub.at(pub.elements, h),
            "published_hours": pub.at(pub.hours, h),
            "published_settlement_cm": None if settle is None else round(100.0 * settle, 10)}


def size_table(info: StudyInfo, rows: Sequence[BatchRow]) -> list[SizeRow]:
    """Per size, coarse to fine: our numbers, and the published study's where there is one.

    The sizes are the study's and, with a published study (:attr:`StudyInfo.published`), its
    sizes too; without one the rows have no published columns.
    """
    by = _by_name(rows)
    pub = info.published
    sizes = sorted({c.h for c in info.checks} | set(pub.sizes_m if pub else ()), reverse=True)
    out = []
    for h in sizes:
        status, row = _status(h, info, by)
        settle = (row.get("settlement_m") or [None])[-1] if row else None
        out.append({"h_m": h, **(_published_columns(pub, h) if pub else {}), "status": status,
                    "cells": row.get("cells"), "symmetry": row.get("symmetry"),
                    "unknowns": row.get("unknowns"), "wall_s": row.get("wall_s"),
                    "peak_rss_mb_max": row.get("peak_rss_mb_max"),
                    "t_last_day": (row.get("output_days") or [None])[-1] if row else None,
                    "settlement_cm": None if settle is None else 100.0 * settle})
    return out


def table_csv(table: list[SizeRow]) -> str:
    """``mesh_study.csv``: :func:`size_table` as CSV."""
    buf = io.StringIO()
    w = csv.DictWriter(buf, fieldnames=list(table[0]), lineterminator="\n")
    w.writeheader()
    for r in table:
        w.writerow({k: "" if v is None else v for k, v in r.items()})
    return buf.getvalue()


def penalty_check(info: StudyInfo, rows: Sequence[BatchRow]) -> list[PenaltyRow]:
    """Per penalty case: the relative change of each final quantity against the base size."""
    by = _by_name(rows)
    gauges = info.scenario.outputs.gauge_depths_m
    out = []
    for c in info.cases:
        if c.penalty == 1.0:
            continue
        base, pen = by.get(f"h{c.h:g}"), by.get(c.name)
        if not base or not pen or "complete" != base["status"] or "complete" != pen["status"]:
            out.append({"h_m": c.h, "case": c.name, "status": "not both complete"})
            continue
        qb, qp = final_quantities(base, gauges), final_quantities(pen, gauges)
        change = {k: (qp[k] - qb[k]) / abs(qb[k]) for k in qb if k in qp and qb[k]}
        out.append({"h_m": c.h, "case": c.name, "status": "complete", "base": qb, "penalty": qp,
                    "change": change})
    return out


def _save(fig: Figure, path: Path) -> Path:
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110, bbox_inches="tight")
    return path


def _done_series(done: Sequence[tuple[StudyCase, dict[str, Any], dict[str, float]]]
                 ) -> tuple[np.ndarray, np.ndarray]:
    pts = sorted((c.h, q[SETTLEMENT]) for c, _, q in done if SETTLEMENT in q)
    return np.array([p[0] for p in pts]), np.array([p[1] for p in pts])


def settlement_figure(done: Sequence[tuple[StudyCase, dict[str, Any], dict[str, float]]],
                      g: GCIResult | None, name: str,
                      published: MeshStudyReference | None = None) -> Figure:
    """Settlement at the last output time against h, with its extrapolated value.

    A published study's settlements on a second axis where the scenario carries one.
    """
    fig = Figure(figsize=(7.5, 4.8))
    ax = fig.subplots()
    h, w = _done_series(done)
    ax.plot(h, 100.0 * w, "o-", color="C0", label=f"{name} (ours)")
    if g is not None and g.defined:
        ax.axhline(100.0 * g.phi_ext, color="C0", ls="--", lw=0.9,
                   label=f"ours extrapolated, p = {g.p:.2f}, GCI = {100 * g.gci_fine21:.2g} %")
    ax.set_xlabel("mesh size at the pile surface h (m)")
    handles, labels = ax.get_legend_handles_labels()
    if published is not None:
        ax.set_ylabel("our settlement (cm)", color="C0")
        ax2 = ax.twinx()
        ax2.plot(published.sizes_m, [100.0 * s for s in published.settlements_m], "s:",
                 color="C3", label=published.label)
        ax2.set_ylabel("published settlement (cm)", color="C3")
        more = ax2.get_legend_handles_labels()
        handles, labels = handles + more[0], labels + more[1]
    else:
        ax.set_ylabel("settlement (cm)")
    ax.legend(handles, labels, fontsize="small", loc="best")
    ax.grid(alpha=0.3)
    ax.set_title("Settlement at the last output time against mesh size")
    return fig


def error_figure(done: Sequence[tuple[StudyCase, dict[str, Any], dict[str, float]]],
                 g: GCIResult | None, published: MeshStudyReference | None = None) -> Figure:
    """Relative error against the extrapolated value versus computation time.

    Ours, and a published study's (against its own extrapolation) where it gives its hours.
    """
    fig = Figure(figsize=(7.0, 4.8))
    ax = fig.subplots()
    series = []
    if g is not None and g.defined:
        series.append(("ours (wall time of the run)", "o-", [
            (r["wall_s"] / 3600.0, abs(q[SETTLEMENT] - g.phi_ext) / abs(g.phi_ext), c.h)
            for c, r, q in done if SETTLEMENT in q and r.get("wall_s")]))
    pg = published_gci(published) if published is not None and published.hours else None
    if pg is not None and pg.defined:
        series.append((f"{published.label} (its own extrapolation)", "s:", [
            (hours, abs(w - pg.phi_ext) / abs(pg.phi_ext), h) for h, w, hours in
            zip(published.sizes_m, published.settlements_m, published.hours, strict=True)]))
    for label, style, pts in series:
        pts = sorted(p for p in pts if p[0] > 0 and p[1] > 0)
        if not pts:
            continue
        ax.loglog([p[0] for p in pts], [100 * p[1] for p in pts], style, label=label)
        for x, y, h in pts:
            ax.annotate(f"{h:g} m", (x, 100 * y), fontsize="x-small", xytext=(3, 3),
                        textcoords="offset points")
    ax.set_xlabel("computation time (hours)")
    ax.set_ylabel("|settlement - extrapolated| / extrapolated (%)")
    ax.grid(alpha=0.3, which="both")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")
    ax.set_title("Discretisation error against cost")
    return fig


def profiles_figure(done: Sequence[tuple[StudyCase, dict[str, Any], dict[str, float]]],
                    column: str, scale: float, xlabel: str) -> Figure:
    """One profile of the centre pile per size at the last output time."""
    fig = Figure(figsize=(6.0, 7.0))
    ax = fig.subplots()
    for c, row, _ in done:
        prof = profile_at_last(Path(row["run_dir"]))
        if prof is None:
            continue
        t, p = prof
        ax.plot(scale * p[column], p["depth_m"], marker=".", label=f"h = {c.h:g} m, t = {t:g} d")
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.invert_yaxis()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("depth below ground surface (m)")
    ax.set_title("Centre pile at the last output time, by mesh size")
    ax.grid(alpha=0.3)
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize="small")
    return fig


def write_mesh_report(out: Path, info: StudyInfo, rows: Sequence[BatchRow]) -> list[Path]:
    """Write the report files into ``out``; returns their paths."""
    out.mkdir(parents=True, exist_ok=True)
    done = size_results(info, rows)
    table = gci_table(done)
    g = table.get(SETTLEMENT)
    paths = [
        _save(settlement_figure(done, g, info.scenario.name, info.published), out / FIGURES[0]),
        _save(error_figure(done, g, info.published), out / FIGURES[1]),
        _save(profiles_figure(done, "shaft_friction_kPa", 1.0, "shaft friction (kPa)"),
              out / FIGURES[2]),
        _save(profiles_figure(done, "relative_displacement_m", 1000.0,
                              "pile - soil relative displacement (mm)"), out / FIGURES[3]),
        write_text_atomic(out / "gci.csv", gci_csv(table)),
    ]
    sizes = size_table(info, rows)
    paths.append(write_text_atomic(out / "mesh_study.csv", table_csv(sizes)))
    text = report_markdown(info, sizes, table, penalty_check(info, rows), machine_text(info))
    paths.append(write_text_atomic(out / "mesh_study.md", text))
    return paths


__all__ = ["FIGURES", "error_figure", "final_quantities", "gci_table", "penalty_check",
           "settlement_figure", "size_results", "size_table", "write_mesh_report"]
