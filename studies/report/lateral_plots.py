"""Figures of a run with cap actions: pile bending and the cap's motion.

``pile_bending.png`` (at the last output time): the lateral deflection and the bending moment of
the piles against depth, along x and along y (every pile of a small group, the key piles of a
large one), from the head (depth 0) down to below the deepest toe, a dot at every section of
``pile_bending.csv``. ``cap_motion.png``: the cap's displacements and
rotations at the action point against time. Conventions: :mod:`pilegroup.studies.run.section_probe`.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from pilegroup.studies.report.figure_parts import depth_axis, drawn_piles
from pilegroup.studies.results.rundata import RunData, select


def plot_pile_bending(run: RunData) -> Figure:
    """Deflection (mm) and bending moment (kN m) of the piles drawn against depth, last time."""
    b = run.bending
    assert b is not None
    t = float(b["t_day"].max())
    last = select(b, b["t_day"] == t)
    fig = Figure(figsize=(13.0, 7.0))
    axes = fig.subplots(1, 4, sharey=True)
    cmap = colormaps["tab10"]
    for k, (i, name) in enumerate(drawn_piles(run, [int(i) for i in np.unique(last["pile"])])):
        m = last["pile"] == i
        order = np.argsort(last["depth_m"][m])
        z = last["depth_m"][m][order]
        for ax, col, scale in zip(axes, ("ux_m", "uy_m", "My_kNm", "Mx_kNm"),
                                  (1000.0, 1000.0, 1.0, 1.0), strict=True):
            ax.plot(scale * last[col][m][order], z, color=cmap(k % 10), marker=".", label=name)
    for ax, label in zip(axes, ("deflection ux (mm)", "deflection uy (mm)",
                                "moment My (kN m)", "moment Mx (kN m)"), strict=True):
        ax.axvline(0.0, color="0.5", lw=0.6)
        ax.set_xlabel(label)
        ax.grid(alpha=0.3)
    depth_axis(axes[0], run, float(np.max(last["depth_m"])))
    axes[-1].legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5))
    fig.suptitle(f"Pile deflection and bending moment at t = {t:g} d")
    return fig


def plot_cap_motion(run: RunData) -> Figure:
    """The cap's displacements (mm) and rotations (mrad) at the action point against time."""
    c = run.cap_motion
    assert c is not None
    order = np.argsort(c["t_day"], kind="stable")
    fig = Figure(figsize=(9.0, 6.5))
    ax_u, ax_r = fig.subplots(2, 1, sharex=True)
    for col, label in (("ux_m", "ux"), ("uy_m", "uy"), ("uz_m", "uz (up)")):
        ax_u.plot(c["t_day"][order], 1000 * c[col][order], marker=".", label=label)
    for col, label in (("rx_rad", "rx"), ("ry_rad", "ry"), ("rz_rad", "rz")):
        ax_r.plot(c["t_day"][order], 1000 * c[col][order], marker=".", label=label)
    ax_u.set_ylabel("displacement (mm)")
    ax_r.set_ylabel("rotation (mrad)")
    ax_r.set_xlabel("time (day)")
    for ax in (ax_u, ax_r):
        ax.legend(fontsize="small")
        ax.grid(alpha=0.3)
    ax_u.set_title("Cap motion at the action point")
    return fig


#: file name, caption, the RunData table it needs, plotting function.
LATERAL_FIGURES = (
    ("pile_bending.png", "Lateral deflection and bending moment of the piles against depth",
     "bending", plot_pile_bending),
    ("cap_motion.png", "Cap displacements and rotations against time", "cap_motion",
     plot_cap_motion),
)
