"""The PNG figures of a run (:class:`~pilegroup.studies.results.rundata.RunData`), one per data set.

Every figure function takes a run and returns a matplotlib ``Figure`` (no pyplot, no display);
:data:`FIGURES` lists them with their file names, captions and the tables they need.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from pilegroup.fileio import atomic_path
from pilegroup.studies.report.gauge_plots import GAUGE_FIGURES
from pilegroup.studies.report.ground_plots import GROUND_FIGURES
from pilegroup.studies.report.lateral_plots import LATERAL_FIGURES
from pilegroup.studies.report.paper_values import (
    EARLY_DAY,
    PAPER_MESH_M,
    PAPER_SETTLEMENT_CM,
    SOFT_LAYERS,
)
from pilegroup.studies.results.rundata import (
    RunData,
    layer_label,
    layer_series,
    pile_loads_last,
    zero_note,
)


def _profile_figure(run: RunData, column: str, scale: float, xlabel: str, title: str) -> Figure:
    assert run.profiles is not None
    p = run.profiles
    fig = Figure(figsize=(6.0, 7.0))
    ax = fig.subplots()
    times = np.unique(p["t_day"])
    colors = [(0.1 + 0.8 * k / max(len(times) - 1, 1)) for k in range(len(times))]
    for t, c in zip(times, colors, strict=True):
        m = p["t_day"] == t
        order = np.argsort(p["depth_m"][m])
        ax.plot(scale * p[column][m][order], p["depth_m"][m][order], marker=".",
                color=colormaps["viridis"](c), label=f"t = {t:g} d")
    if run.history is not None:
        for d in np.unique(run.history["depth_bottom_m"]):
            ax.axhline(d, color="0.8", lw=0.6, zorder=0)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.invert_yaxis()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("depth below ground surface (m)")
    ax.set_title(f"{title}, centre pile {run.centre_pile}")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return fig


def _time_figure(run: RunData, column: str, scale: float, ylabel: str, title: str) -> Figure:
    series = layer_series(run, column)
    fig = Figure(figsize=(8.5, 5.0))
    ax = fig.subplots()
    for j, (t, v) in series.items():
        ax.plot(t, scale * v, label=layer_label(run, j), lw=2.0 if j in SOFT_LAYERS else 1.0)
    tmax = max((float(t[-1]) for t, _ in series.values()), default=0.0)
    if tmax > EARLY_DAY:
        ax.axvline(EARLY_DAY, color="0.5", ls=":", lw=0.8)
        ax.text(EARLY_DAY, 1.0, f" {EARLY_DAY:g} d", transform=ax.get_xaxis_transform(),
                va="top", fontsize="small", color="0.4")
    ax.set_xlabel("time (day)")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title}, centre pile {run.centre_pile} (thick: soft layers 1-3)")
    ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5), title="layer")
    ax.grid(alpha=0.3)
    return fig


def plot_settlement(run: RunData) -> Figure:
    """Cap settlement (mm, down) against time, with the paper's ABAQUS value (Table 2)."""
    assert run.settlement is not None
    s = run.settlement
    fig = Figure(figsize=(7.0, 4.5))
    ax = fig.subplots()
    order = np.argsort(s["t_day"], kind="stable")
    ax.plot(s["t_day"][order], 1000 * s["settlement_m"][order], marker="o", label="this run")
    ref = 10 * PAPER_SETTLEMENT_CM[PAPER_MESH_M]
    ax.axhline(ref, color="C3", ls="--", lw=1.0,
               label=f"paper, ABAQUS, Table 2 ({PAPER_MESH_M:g} m mesh): "
                     f"{PAPER_SETTLEMENT_CM[PAPER_MESH_M]:g} cm (time not stated)")
    ax.set_ylim(bottom=min(0.0, 1000 * float(s["settlement_m"].min())))
    ax.invert_yaxis()
    ax.set_xlabel("time (day)")
    ax.set_ylabel("cap settlement (mm, down)")
    status = "" if run.complete is not False else " (interrupted run)"
    ax.set_title(f"Cap settlement{status}")
    ax.legend(fontsize="small", loc="best")
    ax.grid(alpha=0.3)
    return fig


def plot_friction_profiles(run: RunData) -> Figure:
    """Centre-pile shaft friction (kPa) against depth, one curve per output time (Figure 4)."""
    return _profile_figure(run, "shaft_friction_kPa", 1.0,
                           "shaft friction (kPa, + = soil supports the pile)", "Shaft friction")


def plot_friction_time(run: RunData) -> Figure:
    """Layer-mean shaft friction (kPa) against time, one curve per layer (Figure 5)."""
    return _time_figure(run, "shaft_friction_kPa", 1.0, "layer-mean shaft friction (kPa)",
                        "Shaft friction")


def plot_relative_displacement_profiles(run: RunData) -> Figure:
    """Centre-pile relative displacement (mm) against depth per output time (Figure 6)."""
    return _profile_figure(run, "relative_displacement_m", 1000.0,
                           "pile-soil relative displacement (mm, + = pile moves down)",
                           "Relative displacement" + zero_note(run))


def plot_relative_displacement_time(run: RunData) -> Figure:
    """Layer-mean relative displacement (mm) against time, one curve per layer (Figure 7)."""
    return _time_figure(run, "relative_displacement_m", 1000.0,
                        "layer-mean relative displacement (mm)",
                        "Relative displacement" + zero_note(run))


def plot_axial_force_profiles(run: RunData) -> Figure:
    """Centre-pile axial force (kN, compression positive) against depth per output time."""
    return _profile_figure(run, "axial_force_kN", 1.0, "axial force (kN, compression +)",
                           "Axial force")


def plot_pile_loads(run: RunData) -> Figure:
    """Plan view of the head force of each pile at the last output time (kN and % of total)."""
    last = pile_loads_last(run)
    assert last is not None
    t, rows = last
    f = rows["head_force_kN"]
    total = float(f.sum())
    fig = Figure(figsize=(7.0, 6.0))
    ax = fig.subplots()
    size = 3000.0 * np.abs(f) / max(float(np.abs(f).max()), 1e-30)
    ax.scatter(rows["x_m"], rows["y_m"], s=size, alpha=0.4, color="C0", edgecolor="k")
    for x, y, i, fi in zip(rows["x_m"], rows["y_m"], rows["pile"], f, strict=True):
        share = f"{100 * fi / total:.1f} %" if total else "-"
        ax.annotate(f"pile {int(i)}\n{fi:.0f} kN\n{share}", (x, y), ha="center", va="center",
                    fontsize="small")
    ax.set_aspect("equal")
    ax.margins(0.25)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Pile head forces at t = {t:g} d (total {total:.0f} kN of the listed piles)")
    ax.grid(alpha=0.3)
    return fig


def plot_load_settlement(run: RunData) -> Figure:
    """Load on the foundation (kN) against its settlement (mm), every accepted step."""
    assert run.load_settlement is not None
    c = run.load_settlement
    order = np.argsort(c["t_day"], kind="stable")
    fig = Figure(figsize=(7.0, 4.5))
    ax = fig.subplots()
    ax.plot(1000 * c["settlement_m"][order], c["load_kN"][order], marker=".", lw=1.0)
    ax.set_xlabel("settlement (mm, down)")
    ax.set_ylabel("load on the foundation (kN)")
    status = run.summary.get("status")
    note = " (stopped: no equilibrium beyond the last point)" if status == "failed" else ""
    ax.set_title(f"Load–settlement curve{note}")
    ax.grid(alpha=0.3)
    return fig


def plot_capacity(run: RunData) -> Figure:
    """The capacity stage's load–settlement curves (group and piles) with the criteria marked."""
    assert run.capacity is not None
    c = run.capacity
    solver = run.summary.get("solver") or {}
    cap = (solver.get("capacity") if isinstance(solver, dict) else None) or {}
    fig = Figure(figsize=(7.5, 5.0))
    ax = fig.subplots()
    piles = np.unique(c["pile"]).astype(int)
    for i in piles:
        m = c["pile"] == i
        ax.plot(1000 * c["settlement_m"][m], c["load_kN"][m], marker="." if i == 0 else None,
                lw=2.0 if i == 0 else 0.8, label="group (cap load)" if i == 0 else None,
                color="C0" if i == 0 else "0.6")
    if len(piles) > 1:
        ax.plot([], [], color="0.6", lw=0.8, label="each pile (head force)")
    group = cap.get("group") or {}
    crit = group.get("settlement_10pct_d") or {}
    if crit.get("settlement_m") is not None:
        ax.axvline(1000 * crit["settlement_m"], color="C1", ls="--", lw=1.0,
                   label="10 % of the pile diameter")
    for key, color, label in (("settlement_10pct_d", "C1", "at 10 % D"),
                              ("plunging", "C3", "plunging")):
        q = (group.get(key) or {}).get("load_kN")
        if q is not None:
            ax.axhline(q, color=color, ls=":", lw=1.0, label=f"{label}: {q:.4g} kN")
    ax.set_xlabel("settlement (mm, down)")
    ax.set_ylabel("load (kN)")
    ult = group.get("ultimate_kN")
    ax.set_title("Capacity: " + (f"ultimate {ult:.4g} kN ({group.get('governing')})"
                                 if ult is not None else "no criterion reached"))
    ax.legend(fontsize="small", loc="lower right")
    ax.grid(alpha=0.3)
    return fig


#: Every figure: file name, caption, the RunData table it needs, plotting function.
FIGURES: tuple[tuple[str, str, str, Callable[[RunData], Figure]], ...] = (
    ("settlement_time.png", "Cap settlement against time", "settlement", plot_settlement),
    ("friction_profiles.png", "Shaft friction profiles of the centre pile (cf. paper Fig. 4)",
     "profiles", plot_friction_profiles),
    ("friction_time.png", "Layer-mean shaft friction against time (cf. paper Fig. 5)",
     "history|profiles", plot_friction_time),
    ("relative_displacement_profiles.png",
     "Relative displacement profiles of the centre pile (cf. paper Fig. 6)", "profiles",
     plot_relative_displacement_profiles),
    ("relative_displacement_time.png",
     "Layer-mean relative displacement against time (cf. paper Fig. 7)", "history|profiles",
     plot_relative_displacement_time),
    ("axial_force_profiles.png", "Axial force profiles of the centre pile", "profiles",
     plot_axial_force_profiles),
    ("pile_loads.png", "Pile head forces at the last output time", "loads", plot_pile_loads),
    ("load_settlement.png", "Load–settlement curve (every accepted step)", "load_settlement",
     plot_load_settlement),
    ("capacity.png", "Capacity stage: load–settlement curves and the capacity criteria",
     "capacity", plot_capacity),
    *GAUGE_FIGURES,
    *GROUND_FIGURES,
    *LATERAL_FIGURES,
)


def save_figure(fig: Figure, path: Path) -> Path:
    """Save ``fig`` as PNG to ``path`` atomically (temporary file in the same folder)."""
    with atomic_path(path) as tmp:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
    return path
