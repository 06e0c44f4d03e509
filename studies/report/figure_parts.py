"""What the figures of a run share: depth axes, the piles shown, evenly spread picks.

A depth axis runs from the ground surface down to 10 % below the deepest pile toe (not to the
block's bottom), with the scenario's layer boundaries drawn and named. A figure of many piles
shows the piles that matter (:func:`~pilegroup.studies.results.pile_roles.key_piles`: one of
each role, the most and the least loaded), a figure of a few shows them all.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from matplotlib.axes import Axes

from pilegroup.studies.results.pile_roles import PileInfo
from pilegroup.studies.results.rundata import RunData

#: A figure of every pile draws them all up to this many; beyond, the key piles.
MAX_PILES_DRAWN = 6


def spread(values: Sequence[float] | np.ndarray, count: int) -> list[float]:
    """Up to ``count`` of the sorted unique ``values``, evenly spread, first and last included."""
    v = np.unique(np.asarray(values, dtype=float))
    if v.size <= count:
        return [float(x) for x in v]
    k = np.unique(np.round(np.linspace(0, v.size - 1, count)).astype(int))
    return [float(x) for x in v[k]]


def depth_axis(ax: Axes, run: RunData, deepest_data: float, names: bool = True) -> None:
    """Depth down the y axis, to below the deepest toe, with the layer boundaries (named).

    ``deepest_data``: the deepest depth drawn (m), the axis's end when the run gives no pile
    length. ``names``: write each layer's name at its top, inside the axes.
    """
    bottom = run.depth_limit(deepest_data)
    top = 0.0
    for j, z in enumerate(run.layer_bottoms, start=1):
        if top >= bottom:
            break
        if z < bottom:
            ax.axhline(z, color="0.75", lw=0.6, zorder=0)
        if names and j in run.layer_names:
            ax.text(0.01, top, f" {run.layer_names[j]}", transform=ax.get_yaxis_transform(),
                    va="top", ha="left", fontsize="x-small", color="0.45", zorder=0)
        top = z
    toe = run.deepest_toe
    if toe is not None:
        ax.axhline(toe, color="0.3", lw=0.8, ls="--", zorder=0)
    ax.set_ylim(bottom, 0.0)
    ax.set_ylabel("depth below ground surface (m)")


def drawn_piles(run: RunData, numbers: Sequence[int]) -> list[tuple[int, str]]:
    """The piles of ``numbers`` a figure of every pile draws, each with its legend name.

    All of them up to :data:`MAX_PILES_DRAWN`, else those of the run's key piles among them.
    """
    numbers = sorted(int(i) for i in numbers)
    if len(numbers) > MAX_PILES_DRAWN:
        keys = {p.number for p, _ in run.key_piles()}
        numbers = [i for i in numbers if i in keys] or numbers[:MAX_PILES_DRAWN]
    return [(i, legend_name(run.pile(i))) for i in numbers]


def legend_name(p: PileInfo) -> str:
    """A pile's name in a legend: ``pile 5, r2 c2`` (``pile 5`` when its place is unknown)."""
    return p.short if np.isfinite(p.x) else f"pile {p.number}"


__all__ = ["MAX_PILES_DRAWN", "depth_axis", "drawn_piles", "legend_name", "spread"]
