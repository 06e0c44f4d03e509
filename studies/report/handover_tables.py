"""The tables of the report an engineer hands on (``report.md``), from a run folder's files.

How the run ended (at the top), the cap's motion at every output time (``settlement.csv``,
``cap_motion.csv``), each pile's head actions and largest moment (``pile_heads.csv``,
``pile_max_moment.csv``) with the piles named by place, the load shares, the neutral plane and
dragload where the ground moves (``neutral_plane.csv``) and the run's mesh, element, solver and
wall time (``summary.json``). Each section says so when its file is missing.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from pilegroup.studies.report.run_report import applied_vertical_load
from pilegroup.studies.report.scenario_table import key_value, moves_ground, number
from pilegroup.studies.results.rundata import RunData, select
from pilegroup.studies.results.tables import (
    CAP_MOTION_CSV,
    MAX_MOMENT_CSV,
    SETTLEMENT_CSV,
    Table,
    read_csv,
)

#: Pile head columns of ``pile_heads.csv`` and their headings.
HEAD_COLUMNS = (("N_kN", "N (kN)"), ("Vx_kN", "Vx (kN)"), ("Vy_kN", "Vy (kN)"),
                ("Mx_kNm", "Mx (kN m)"), ("My_kNm", "My (kN m)"), ("T_kNm", "T (kN m)"))


def run_status(summary: dict[str, Any]) -> str:
    """``complete``, ``failed``, ``interrupted`` or ``unknown`` (summary.json)."""
    status = summary.get("status")
    if status in ("complete", "failed", "interrupted"):
        return str(status)
    for d in (summary, summary.get("solver") or {}):
        if isinstance(d, dict) and "complete" in d:
            return "complete" if d["complete"] else "interrupted"
    return "unknown"


def status_lines(summary: dict[str, Any]) -> list[str]:
    """The report's first words: whether the run is complete, and if not why and where."""
    status = run_status(summary)
    if status == "complete":
        return ["**Run complete.**", ""]
    if status == "failed":
        why = summary.get("reason") or "no reason recorded"
        return [f"> **INCOMPLETE RUN: the run failed** ({why}). The tables below hold the "
                "output times reached before the failure.", ""]
    if status == "interrupted":
        t = summary.get("t_day")
        where = f" at t = {number(t)} day" if t is not None else ""
        stage = f" in stage `{summary['stage']}`" if summary.get("stage") else ""
        sig = f" by {summary['signal']}" if summary.get("signal") else ""
        return [f"> **INCOMPLETE RUN: the run was stopped{sig}{where}{stage}.** The tables "
                "below hold the output times reached; resume with "
                "`pilegroup run SCENARIO --out OUT --resume`.", ""]
    return ["> **Run status unknown**: `summary.json` is missing or says neither complete, "
            "failed nor interrupted; the run may be incomplete.", ""]


def _table(header: list[str], rows: list[list[str]], left: int = 1) -> list[str]:
    """A Markdown table, the first ``left`` columns left-aligned, the others right-aligned."""
    rule = "|" + " --- |" * left + " ---: |" * (len(header) - left)
    return ["| " + " | ".join(header) + " |", rule,
            *("| " + " | ".join(r) + " |" for r in rows), ""]


def _fmt(x: float, spec: str = ".2f") -> str:
    return "-" if x is None or not np.isfinite(x) else format(x, spec)


def _row_at(table: Table | None, t: float) -> int | None:
    if table is None:
        return None
    hit = np.flatnonzero(np.abs(table["t_day"] - t) <= 1e-9 * max(1.0, abs(t)))
    return int(hit[0]) if hit.size else None


def cap_motion_section(run: RunData) -> list[str]:
    """Cap settlement, horizontal motion and rotations at every output time."""
    lines = ["## Cap motion at every output time", ""]
    s, m = read_csv(run.out_dir / SETTLEMENT_CSV), read_csv(run.out_dir / CAP_MOTION_CSV)
    if s is None and m is None:
        return lines + ["No `settlement.csv` or `cap_motion.csv`: no cap motion data.", ""]
    times = sorted({float(t) for tab in (s, m) if tab is not None for t in tab["t_day"]})
    lines += ["Settlement down positive (`settlement.csv`); horizontal motion and rotations of "
              "the cap (or the single pile's head) at the action point, global axes "
              "(`cap_motion.csv`).", ""]
    rows = []
    for t in times:
        i, k = _row_at(s, t), _row_at(m, t)
        stage = str(s["stage"][i]) if i is not None else "-"
        w = 1000 * float(s["settlement_m"][i]) if i is not None else \
            (-1000 * float(m["uz_m"][k]) if k is not None else np.nan)
        motion = [np.nan] * 5 if k is None else \
            [1000 * float(m["ux_m"][k]), 1000 * float(m["uy_m"][k]),
             *(1000 * float(m[c][k]) for c in ("rx_rad", "ry_rad", "rz_rad"))]
        rows.append([number(t), stage, _fmt(w, ".3f"), *(_fmt(v, ".3f") for v in motion)])
    return lines + _table(["t (day)", "stage", "settlement (mm)", "ux (mm)", "uy (mm)",
                           "rx (mrad)", "ry (mrad)", "rz (mrad)"], rows)


def _last(table: Table) -> tuple[float, Table]:
    t = float(table["t_day"].max())
    sel = select(table, table["t_day"] == t)
    return t, select(sel, np.argsort(sel["pile"], kind="stable"))


def heads_section(run: RunData) -> list[str]:
    """Each pile's head actions and largest bending moment at the last output time."""
    lines = ["## Pile heads and largest moments", ""]
    if run.heads is None:
        return lines + ["No `pile_heads.csv`: no pile head actions.", ""]
    t, h = _last(run.heads)
    mm = read_csv(run.out_dir / MAX_MOMENT_CSV)
    lines += [f"At the last output time, t = {number(t)} day: the cap's action on each pile at "
              "its head (`pile_heads.csv`; N compression positive, global axes) and the pile's "
              "largest resultant bending moment with its depth (`pile_max_moment.csv`).", ""]
    rows = []
    for r in range(len(h["pile"])):
        i = int(h["pile"][r])
        m_max, z = np.nan, np.nan
        if mm is not None:
            hit = np.flatnonzero((mm["pile"] == i) & (np.abs(mm["t_day"] - t) <= 1e-9))
            if hit.size:
                m_max, z = float(mm["M_max_kNm"][hit[0]]), float(mm["depth_m"][hit[0]])
        rows.append([run.pile_name(i), *(_fmt(float(h[c][r]), ".1f") for c, _ in HEAD_COLUMNS),
                     _fmt(m_max, ".1f"), _fmt(z, ".2f")])
    return lines + _table(["pile", *(name for _, name in HEAD_COLUMNS), "M max (kN m)",
                           "depth of M max (m)"], rows) + max_moment_over_time(run, mm)


def max_moment_over_time(run: RunData, mm: Table | None) -> list[str]:
    """The largest moment of each pile over every output time, with its time and depth."""
    if mm is None:
        return ["No `pile_max_moment.csv`: no largest moments.", ""]
    rows = []
    for i in np.unique(mm["pile"]):
        sel = select(mm, mm["pile"] == i)
        k = int(np.argmax(np.abs(sel["M_max_kNm"])))
        rows.append([run.pile_name(int(i)), _fmt(float(sel["M_max_kNm"][k]), ".1f"),
                     _fmt(float(sel["depth_m"][k]), ".2f"), number(float(sel["t_day"][k]))])
    return ["Largest bending moment of each pile over all output times:", "",
            *_table(["pile", "M max (kN m)", "depth (m)", "t (day)"], rows)]


def shares_section(run: RunData) -> list[str]:
    """Each pile's share of the piles' total axial head force at the last output time."""
    lines = ["## Load shares", ""]
    last = run.head_forces()
    if last is None:
        return lines + ["No `pile_heads.csv` or `pile_loads.csv`: no load shares.", ""]
    t, forces, source = last
    total = sum(forces.values())
    mean = total / len(forces) if forces else 0.0
    lines += [f"At t = {number(t)} day; head force: {source}. Ratio: the pile's force over the "
              "mean of the piles.", ""]
    rows = []
    for i in sorted(forces):
        f = forces[i]
        p = run.pile(i)
        rows.append([run.pile_name(i), p.role or "-", _fmt(f, ".1f"),
                     _fmt(100 * f / total, ".1f") if total else "-",
                     _fmt(f / mean, ".2f") if mean else "-"])
    rows.append(["total", "", _fmt(total, ".1f"), "100.0" if total else "-", ""])
    lines += _table(["pile", "place", "head force (kN)", "share (%)", "ratio to mean"], rows,
                    left=2)
    applied = applied_vertical_load(run.scenario)
    if applied is not None:
        lines += [f"Vertical load of the last load stage: {applied:.1f} kN.", ""]
    return lines


def neutral_section(run: RunData) -> list[str]:
    """Neutral plane, dragload and downdrag of each pile, where the ground moves."""
    if not moves_ground(run.scenario):
        return []
    lines = ["## Neutral plane and dragload", ""]
    if run.neutral is None:
        return lines + ["The ground moves in this scenario, but the run has no "
                        "`neutral_plane.csv`.", ""]
    t, n = _last(run.neutral)
    lines += [f"At the last output time, t = {number(t)} day (`neutral_plane.csv`): the "
              "neutral plane is the depth of the largest axial force; dragload = that force "
              "minus the head load; downdrag = the pile's settlement at the neutral plane.", ""]
    rows = [[run.pile_name(int(n["pile"][r])), _fmt(float(n["neutral_plane_depth_m"][r])),
             _fmt(float(n["head_load_kN"][r]), ".1f"),
             _fmt(float(n["max_axial_force_kN"][r]), ".1f"),
             _fmt(float(n["dragload_kN"][r]), ".1f"), _fmt(1000 * float(n["downdrag_m"][r]),
                                                           ".2f")]
            for r in range(len(n["pile"]))]
    return lines + _table(["pile", "neutral plane (m)", "head load (kN)",
                           "max axial force (kN)", "dragload (kN)", "downdrag (mm)"], rows)


def _solver_rows(solver: dict[str, Any]) -> list[list[str]]:
    rows = []
    for key, what in (("linear_solver", "linear solver"), ("preset", "solver preset"),
                      ("dofs", "unknowns"), ("steps", "time steps"),
                      ("rejected_steps", "rejected steps"),
                      ("newton_iterations", "Newton iterations"),
                      ("ksp_iterations", "Krylov iterations"),
                      ("lu_factorisations", "LU factorisations"),
                      ("final_time_day", "final time (day)"),
                      ("wall_s", "solver wall time (s)")):
        if solver.get(key) is not None:
            v = solver[key]
            rows.append([what, number(v) if isinstance(v, float) else str(v)])
    peak = solver.get("peak_rss_mb_per_rank")
    if peak:
        rows.append(["peak memory per rank (MB)", number(max(peak))])
    return rows


def run_section(summary: dict[str, Any]) -> list[str]:
    """The run's mesh, element, solver and wall time (``summary.json``)."""
    lines = ["## Mesh, element, solver and wall time", ""]
    if not summary:
        return lines + ["No `summary.json`: nothing known of the run's discretisation.", ""]
    disc = summary.get("discretisation") or {}
    mesh, solver = summary.get("mesh") or {}, summary.get("solver") or {}
    rows = [["status", run_status(summary)]]
    for d, key, what in ((mesh, "cells", "cells"), (mesh, "vertices", "vertices"),
                         (mesh, "h_m", "element size near the piles (m)"),
                         (mesh, "min_scaled_jacobian", "smallest scaled Jacobian")):
        if d.get(key) is not None:
            rows.append([what, number(d[key])])
    sizes = disc.get("mesh") or {}
    if sizes:
        rows.append(["mesh sizes", ", ".join(key_value(k, v) for k, v in sizes.items()
                                             if isinstance(v, int | float))])
    element = disc.get("element") or solver.get("element")
    if element:
        why = f" ({disc['element_reason']})" if disc.get("element_reason") else ""
        rows.append(["element pair", f"{element}{why}"])
    sym = solver.get("symmetry") or {}
    if sym.get("model"):
        rows.append(["symmetry", f"{sym['model']}: {sym.get('reason', '')}".rstrip(": ")])
    rows += _solver_rows(solver)
    if summary.get("ranks") is not None:
        rows.append(["MPI ranks", str(summary["ranks"])])
    if summary.get("wall_s") is not None:
        rows.append(["wall time of the job (s)", number(summary["wall_s"])])
    rows = [[a, b.replace("|", "\\|")] for a, b in rows]
    return lines + _table(["item", "value"], rows, left=2)
