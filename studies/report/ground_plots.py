"""Figures of ground that moves: the unified method's two diagrams and the surface trough.

``unified_method.png`` (Fellenius' unified method, at the last output time): left, the axial
force of the piles against depth with their neutral planes; right, the settlement against depth
of the piles (solid), of the soil beside them (dashed) and of the free field (black); every
pile of a small group, the key piles of a large one
(:func:`~pilegroup.studies.report.figure_parts.drawn_piles`), down to below the deepest toe.
``surface_trough.png``: the ground surface's settlement across the block through the group's
centre at every output time. Tables: :mod:`pilegroup.studies.results.tables`.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from pilegroup.studies.report.figure_parts import depth_axis, drawn_piles
from pilegroup.studies.results.rundata import RunData, select


def plot_unified_method(run: RunData) -> Figure:
    """Axial force and settlement against depth of the piles drawn, last output time."""
    sp = run.settlement_profiles
    assert sp is not None
    t = float(sp["t_day"].max())
    last = select(sp, sp["t_day"] == t)
    drawn = drawn_piles(run, [int(i) for i in np.unique(last["pile"]) if i > 0])
    piles = [i for i, _ in drawn]
    fig = Figure(figsize=(11.0, 7.0))
    ax_n, ax_s = fig.subplots(1, 2, sharey=True)
    cmap = colormaps["tab10"]
    for k, (i, name) in enumerate(drawn):
        m = last["pile"] == i
        z = last["depth_m"][m]
        c = cmap(k % 10)
        ax_n.plot(last["axial_force_kN"][m], z, color=c, label=name)
        ax_s.plot(1000 * last["pile_settlement_m"][m], z, color=c, label=name)
        ax_s.plot(1000 * last["soil_settlement_m"][m], z, color=c, ls="--", lw=0.8)
    if run.neutral is not None:
        nl = select(run.neutral, run.neutral["t_day"] == float(run.neutral["t_day"].max()))
        for k, i in enumerate(piles):
            m = nl["pile"] == i
            if m.any():
                ax_n.plot(nl["max_axial_force_kN"][m], nl["neutral_plane_depth_m"][m], "o",
                          color=cmap(k % 10))
    free = last["pile"] == 0
    if free.any():
        ax_s.plot(1000 * last["soil_settlement_m"][free], last["depth_m"][free], color="k",
                  lw=2.0, label="free field")
    depth_axis(ax_n, run, float(np.max(last["depth_m"][last["pile"] > 0], initial=0.0)))
    ax_n.set_xlabel("axial force (kN, compression +); dots: neutral plane")
    ax_s.set_xlabel("settlement (mm, down +); dashed: soil beside the pile")
    ax_n.set_title(f"Axial force, t = {t:g} d")
    ax_s.set_title(f"Settlement, t = {t:g} d")
    for ax in (ax_n, ax_s):
        ax.grid(alpha=0.3)
    ax_s.legend(fontsize="small")
    return fig


def plot_surface_trough(run: RunData) -> Figure:
    """Ground-surface settlement across the block through the group's centre, every output time."""
    tr = run.trough
    assert tr is not None
    fig = Figure(figsize=(8.5, 5.0))
    ax = fig.subplots()
    times = np.unique(tr["t_day"])
    for k, t in enumerate(times):
        m = tr["t_day"] == t
        ax.plot(tr["x_m"][m], 1000 * tr["settlement_m"][m],
                color=colormaps["viridis"](0.1 + 0.8 * k / max(len(times) - 1, 1)),
                label=f"t = {t:g} d")
    ax.invert_yaxis()
    ax.set_xlabel("x (m), through the group's centre")
    ax.set_ylabel("ground surface settlement (mm, down +)")
    ax.set_title("Surface settlement trough (gaps: piles)")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return fig


#: (file, caption, tables needed, function) of each figure.
GROUND_FIGURES = (
    ("unified_method.png", "Axial force and settlement against depth of the piles and the free"
     " field, with the neutral planes (Fellenius' unified method)", "settlement_profiles",
     plot_unified_method),
    ("surface_trough.png", "Ground surface settlement across the group against time", "trough",
     plot_surface_trough),
)
