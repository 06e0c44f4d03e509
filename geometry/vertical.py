"""Vertical division of the extrusion: segments between levels and graded element heights.

Pure numpy (no gmsh). Levels in m, z up, ground surface z = 0. The soil column is cut at every
layer boundary, every pile toe and the spec's other levels (a water table); the cap at every
pile top (embedment) and its top. Inside
each segment the element height follows the size function

    dz(z) = min(dz_cap_here, min_k (dz_k + (g - 1) |z - z_k|))

with foci ``z_k`` at the ground surface (``dz_surface``) and the pile toes (``dz_toe``), growth
``g = dz_growth``, and ``dz_cap_here`` = ``dz_max`` above the deepest toe, ``dz_max_deep``
below it (and a layer's own ``dz_max`` if given). The number of elements of a segment is the
integral of ``1 / dz`` rounded up (at least ``min_layer_divisions``); the nodes are placed at
equal increments of that integral, which gives smooth geometric-like grading.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from pilegroup.geometry.spec import GeometrySpec
from pilegroup.model.mesh_estimate import column_sizes, size_integral, slab_elements

__all__ = ["Segment", "vertical_segments"]

_TOL = 1e-9

#: Vertical element size (m) as a function of the level z (m).
SizeFunction = Callable[[np.ndarray], np.ndarray]


@dataclass(frozen=True)
class Segment:
    """One extrusion slab between two levels (m).

    Attributes:
        z_start: level the extrusion starts from (m) (the ground surface side).
        z_end: level the extrusion ends at (m).
        region: ``"soil"`` or ``"cap"``.
        layer: 1-based layer index for soil slabs, 0 for the cap.
        heights: cumulative fractions (0, 1] of ``|z_end - z_start|`` of every element
            boundary after the start, ending with 1.0 (gmsh ``extrude(..., heights=...)``).
    """

    z_start: float
    z_end: float
    region: str
    layer: int
    heights: tuple[float, ...]

    @property
    def n(self) -> int:
        """Number of elements across the slab."""
        return len(self.heights)

    def levels(self) -> np.ndarray:
        """Levels z (m) of the element boundaries, from ``z_start`` (excluded) to ``z_end``."""
        return self.z_start + (self.z_end - self.z_start) * np.asarray(self.heights)


def _unique_sorted_desc(values: list[float], scale: float) -> list[float]:
    out: list[float] = []
    for v in sorted(values, reverse=True):
        if not out or out[-1] - v > _TOL * scale:
            out.append(v)
    return out


def _size_function(spec: GeometrySpec) -> SizeFunction:
    s = spec.sizing
    foci = [(0.0, s.dz_surface)] + [(-p.length_in_soil, s.dz_toe) for p in spec.piles]
    z_deepest = min(-p.length_in_soil for p in spec.piles)
    bottoms = np.asarray(spec.layer_bottoms())
    layer_caps = np.asarray([np.inf if lay.dz_max is None else lay.dz_max
                             for lay in spec.layers])

    def dz(z: np.ndarray) -> np.ndarray:
        val = column_sizes(z, foci, s.dz_growth, z_deepest, s.dz_max, s.dz_max_deep)
        # layer index of each z (boundaries belong to the layer above)
        idx = np.searchsorted(-bottoms, -z, side="left")
        idx = np.clip(idx, 0, len(layer_caps) - 1)
        return np.minimum(val, layer_caps[idx])

    return dz


def _graded(z0: float, z1: float, dz: SizeFunction, n_min: int) -> tuple[float, ...]:
    """Cumulative height fractions from z0 towards z1 following the size function dz."""
    s, cum = size_integral(z0, z1, dz)
    total = cum[-1]
    n = slab_elements(total, n_min)
    t = np.linspace(0.0, total, n + 1)[1:]
    frac = np.interp(t, cum, s) / abs(z1 - z0)
    frac[-1] = 1.0
    return tuple(float(f) for f in frac)


def vertical_segments(spec: GeometrySpec) -> tuple[list[Segment], list[Segment]]:
    """The extrusion slabs of the soil (from z = 0 down) and of the cap (from z = 0 up).

    Returns ``(soil, cap)``; ``cap`` is empty without a cap. Soil slabs are cut at every layer
    boundary, pile toe and level of ``spec.levels`` (a water table), cap slabs at every pile
    top.
    """
    s = spec.sizing
    depth = spec.block.depth
    dz = _size_function(spec)
    cuts = [0.0, *spec.layer_bottoms(), *(-p.length_in_soil for p in spec.piles),
            *(-d for d in spec.levels)]
    levels = _unique_sorted_desc(cuts, depth)
    soil = []
    for za, zb in zip(levels[:-1], levels[1:], strict=True):
        layer = spec.layer_of_depth(0.5 * (za + zb))
        soil.append(Segment(za, zb, "soil", layer, _graded(za, zb, dz, s.min_layer_divisions)))
    cap: list[Segment] = []
    if spec.cap is not None:
        t = spec.cap.thickness
        up = sorted({0.0, t, *(p.embedment for p in spec.piles)})
        up = [v for k, v in enumerate(up) if k == 0 or v - up[k - 1] > _TOL * t]
        for za, zb in zip(up[:-1], up[1:], strict=True):
            n = max(1, int(np.ceil((zb - za) / s.dz_cap - 1e-6)))
            cap.append(Segment(za, zb, "cap", 0, tuple(float(k) / n for k in range(1, n + 1))))
    return soil, cap
