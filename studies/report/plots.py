"""The PNG figures of a run (:class:`~pilegroup.studies.results.rundata.RunData`), one per data set.

Every figure function takes a run and returns a matplotlib ``Figure`` (no pyplot, no display);
:data:`FIGURES` lists them with their file names, captions and the tables they need. Figures
speak of the scenario: piles named by their place, layers by their names, depth axes to below
the deepest toe (:mod:`pilegroup.studies.report.figure_parts`); a published value is drawn
only from the scenario's ``[reference]`` (:attr:`RunData.reference`).
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from pilegroup.fileio import atomic_path
from pilegroup.studies.report.figure_parts import depth_axis, legend_name
from pilegroup.studies.report.gauge_plots import GAUGE_FIGURES
from pilegroup.studies.report.ground_plots import GROUND_FIGURES
from pilegroup.studies.report.lateral_plots import LATERAL_FIGURES
from pilegroup.studies.results.rundata import (
    RunData,
    layer_label,
    layer_series,
    select,
    zero_note,
)


def _profile_figure(run: RunData, column: str, scale: float, xlabel: str, title: str) -> Figure:
    """``column`` against depth, one panel per key pile, one curve per output time."""
    p = run.all_profiles if run.all_profiles is not None else run.profiles
    assert p is not None
    keys = [(pile, why) for pile, why in run.key_piles() if np.any(p["pile"] == pile.number)]
    if not keys:
        keys = [(run.pile(int(i)), "") for i in np.unique(p["pile"])[:1]]
    fig = Figure(figsize=(1.0 + 3.6 * len(keys), 7.0))
    axes = np.atleast_1d(fig.subplots(1, len(keys), sharey=True, squeeze=False)[0])
    times = np.unique(p["t_day"])
    for k, (ax, (pile, why)) in enumerate(zip(axes, keys, strict=True)):
        rows = select(p, p["pile"] == pile.number)
        for n, t in enumerate(times):
            m = rows["t_day"] == t
            order = np.argsort(rows["depth_m"][m])
            ax.plot(scale * rows[column][m][order], rows["depth_m"][m][order], marker=".",
                    color=colormaps["viridis"](0.1 + 0.8 * n / max(len(times) - 1, 1)),
                    label=f"t = {t:g} d")
        ax.axvline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(xlabel)
        shown = why if why and why != "single" else ""
        ax.set_title(legend_name(pile) + (f"\n({shown})" if shown else ""), fontsize="medium")
        ax.grid(alpha=0.3)
        if k == 0:
            depth_axis(ax, run, float(np.max(p["depth_m"])))
    axes[-1].legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.suptitle(title)
    return fig


def _time_figure(run: RunData, column: str, scale: float, ylabel: str, title: str) -> Figure:
    """Layer means of the pile nearest the centre against time.

    With a reference: its soft layers drawn thick, the end of its early period marked.
    """
    series = layer_series(run, column)
    ref = run.reference
    soft = ref.soft_layers if ref is not None else ()
    early = ref.early_day if ref is not None else None
    fig = Figure(figsize=(8.5, 5.0))
    ax = fig.subplots()
    for j, (t, v) in series.items():
        ax.plot(t, scale * v, label=layer_label(run, j), lw=2.0 if j in soft else 1.0)
    tmax = max((float(t[-1]) for t, _ in series.values()), default=0.0)
    if early is not None and tmax > early:
        ax.axvline(early, color="0.5", ls=":", lw=0.8)
        ax.text(early, 1.0, f" {early:g} d (reference)", transform=ax.get_xaxis_transform(),
                va="top", fontsize="small", color="0.4")
    ax.set_xlabel("time (day)")
    ax.set_ylabel(ylabel)
    note = (f" (thick: soft layers {', '.join(map(str, soft))} of the reference)"
            if soft else "")
    ax.set_title(f"{title}, {run.pile_name(run.centre_pile)}{note}", fontsize="medium")
    ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5), title="layer")
    ax.grid(alpha=0.3)
    return fig


def _reference_settlement(ax: Axes, run: RunData) -> None:
    """The reference's published settlement, if the scenario carries one."""
    ref = run.reference
    if ref is None or ref.settlement_m is None:
        return
    value = 1000.0 * ref.settlement_m
    when = f"day {ref.settlement_day:g}" if ref.settlement_day is not None else "no time stated"
    label = f"reference: {value:g} mm ({when})"
    if ref.settlement_day is None:
        ax.axhline(value, color="C3", ls="--", lw=1.0, label=label)
    else:
        ax.plot([ref.settlement_day], [value], "s", color="C3", label=label)


def plot_settlement(run: RunData) -> Figure:
    """Cap settlement (mm, down) against time; the reference's settlement where there is one."""
    assert run.settlement is not None
    s = run.settlement
    fig = Figure(figsize=(7.0, 4.5))
    ax = fig.subplots()
    order = np.argsort(s["t_day"], kind="stable")
    ax.plot(s["t_day"][order], 1000 * s["settlement_m"][order], marker="o", label="this run")
    _reference_settlement(ax, run)
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
    """Shaft friction (kPa) of the key piles against depth, one curve per output time."""
    return _profile_figure(run, "shaft_friction_kPa", 1.0,
                           "shaft friction (kPa, + = soil supports the pile)", "Shaft friction")


def plot_friction_time(run: RunData) -> Figure:
    """Layer-mean shaft friction (kPa) against time, one curve per layer."""
    return _time_figure(run, "shaft_friction_kPa", 1.0, "layer-mean shaft friction (kPa)",
                        "Shaft friction")


def plot_relative_displacement_profiles(run: RunData) -> Figure:
    """Relative displacement (mm) of the key piles against depth per output time."""
    return _profile_figure(run, "relative_displacement_m", 1000.0,
                           "pile-soil relative displacement (mm, + = pile moves down)",
                           "Relative displacement" + zero_note(run))


def plot_relative_displacement_time(run: RunData) -> Figure:
    """Layer-mean relative displacement (mm) against time, one curve per layer."""
    return _time_figure(run, "relative_displacement_m", 1000.0,
                        "layer-mean relative displacement (mm)",
                        "Relative displacement" + zero_note(run))


def plot_axial_force_profiles(run: RunData) -> Figure:
    """Axial force (kN, compression positive) of the key piles against depth per output time."""
    return _profile_figure(run, "axial_force_kN", 1.0, "axial force (kN, compression +)",
                           "Axial force")


def plot_pile_loads(run: RunData) -> Figure:
    """Plan view of the head force of each pile at the last output time (kN and % of total)."""
    last = run.head_forces()
    assert last is not None
    t, forces, source = last
    piles = sorted(forces)
    f = np.array([forces[i] for i in piles])
    xy = np.array([(run.pile(i).x, run.pile(i).y) for i in piles])
    if not np.all(np.isfinite(xy)):
        table = run.heads if run.heads is not None else run.loads
        assert table is not None
        rows = select(table, table["t_day"] == t)
        at = {int(i): (x, y) for i, x, y in zip(rows["pile"], rows["x_m"], rows["y_m"],
                                                strict=True)}
        xy = np.array([at[i] for i in piles])
    total = float(f.sum())
    fig = Figure(figsize=(7.0, 6.0))
    ax = fig.subplots()
    size = 3000.0 * np.abs(f) / max(float(np.abs(f).max()), 1e-30)
    ax.scatter(xy[:, 0], xy[:, 1], s=size, alpha=0.4, color="C0", edgecolor="k")
    for (x, y), i, fi in zip(xy, piles, f, strict=True):
        share = f"{100 * fi / total:.1f} %" if total else "-"
        ax.annotate(f"{legend_name(run.pile(i))}\n{fi:.0f} kN\n{share}", (x, y), ha="center",
                    va="center", fontsize="small")
    ax.set_aspect("equal")
    ax.margins(0.25)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Pile head forces at t = {t:g} d, total {total:.0f} kN\n"
                 f"({source.replace('`', '')})", fontsize="medium")
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
    ("friction_profiles.png", "Shaft friction profiles of the key piles", "profiles",
     plot_friction_profiles),
    ("friction_time.png", "Layer-mean shaft friction of the pile nearest the centre against time",
     "history|profiles", plot_friction_time),
    ("relative_displacement_profiles.png", "Relative displacement profiles of the key piles",
     "profiles", plot_relative_displacement_profiles),
    ("relative_displacement_time.png",
     "Layer-mean relative displacement of the pile nearest the centre against time",
     "history|profiles",
     plot_relative_displacement_time),
    ("axial_force_profiles.png", "Axial force profiles of the key piles", "profiles",
     plot_axial_force_profiles),
    ("pile_loads.png", "Pile head forces at the last output time", "heads|loads",
     plot_pile_loads),
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
