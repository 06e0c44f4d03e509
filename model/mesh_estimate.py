"""A count of the cells a scenario's mesh will have, before any meshing.

The mesh is plan quads extruded down through the layers (docs/geometry.md), so the count is
(plan quads) x (element layers), each from the sizing keys of ``numerics.mesh`` following the
mesher:

* plan (:func:`plan_quads`): the structured region (the cap, or the piles' bounding box plus a
  margin) is a grid of pile cells, each an o-grid of ``N`` edges around its pile and radial
  edges growing from ``size_m``; the far field around it is graded from the region's edge by
  ``growth`` up to ``far_field_size_m`` (the integral of ``1 / size^2`` over that band, times
  :data:`FAR_FIELD_FILL`);
* vertical (:func:`element_layers`): the mesher's rule for the soil column's slabs (cut at the
  layer boundaries, toes and water table) and the cap's.

On the bundled scenarios' meshes and groups up to 6 x 6 the layers are exact and the plan
quads 0.83-1.05 times the meshed count (docs/benchmarks.md, "Memory estimate before meshing");
:func:`estimated_cells` adds :data:`SAFETY` for the memory check (``tests/model/test_fuzz.py``
checks that it bounds the meshed count); a symmetry-reduced model has a half or a quarter of
those cells. :data:`MAX_CELLS` is the largest estimate a scenario may have.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Callable
from typing import Protocol

import numpy as np

from pilegroup.model.analysis import Numerics
from pilegroup.model.piles import Piles
from pilegroup.model.site import Cap, Layer, Site


class EstimatedScenario(Protocol):
    """What the estimate reads of a scenario.

    :class:`pilegroup.model.scenario.Scenario` follows it; the scenario checks its estimate when
    it is built, so this module cannot import it.
    """

    @property
    def site(self) -> Site: ...  # noqa: D102
    @property
    def layers(self) -> tuple[Layer, ...]: ...  # noqa: D102
    @property
    def piles(self) -> Piles: ...  # noqa: D102
    @property
    def cap(self) -> Cap | None: ...  # noqa: D102
    @property
    def numerics(self) -> Numerics: ...  # noqa: D102

#: Largest estimated cell count accepted: ~50 GB of memory for a Q1-Q1 Biot system with a
#: direct solver, far beyond the 2-core machines the tool targets.
MAX_CELLS = 50_000_000
#: Factor on the estimated cells: an upper bound for the memory check.
SAFETY = 2.0
#: The o-grid's radial growth and its radial edges inside a pile (geometry/plan.py), and the
#: structured margin around the piles without a cap (geometry/spec.py, ``near_field_margin``).
OGRID_GROWTH, OGRID_INSIDE, NEAR_FIELD_MARGIN = 1.35, 2, 1.5
#: Unstructured quads per ideal quad of the far field's size field (with it the plan quads of
#: the bundled scenarios' meshes and of groups up to 6 x 6 are estimated at 0.83-1.05 times).
FAR_FIELD_FILL = 2.0
#: Vertices per hexahedron of the graded meshes (1.11 for the pier, more for small meshes).
VERTICES_PER_CELL = 1.15
#: Unknowns per vertex: 3 displacements (Q2: ~8 nodes per vertex) and 1 pressure.
UNKNOWNS_PER_VERTEX = {"Q1Q1": 4, "Q2Q1": 25}


def graded_count(length: float, start: float, cap: float, growth: float) -> float:
    """Elements across ``length`` (m) graded from ``start`` by ``growth`` up to ``cap`` (m)."""
    a = growth - 1.0
    start = min(start, cap)
    reach = (cap - start) / a
    if length <= reach:
        return math.log1p(a * length / start) / a
    return math.log(cap / start) / a + (length - reach) / cap


def edges_around(d_max: float, h: float, n_circ_min: int) -> int:
    """Element edges around every pile circle (the mesher's rule, a multiple of 4).

    ``max(n_circ_min, 4 ceil(pi d / 4 h))`` with ``d`` the largest diameter and ``h`` the size
    at the piles (m).
    """
    return max(n_circ_min, 4 * math.ceil(math.pi * d_max / (4.0 * h) - 1e-9))


def column_sizes(z: np.ndarray, foci: list[tuple[float, float]], growth: float,
                 z_deepest: float, dz_max: float, dz_max_deep: float) -> np.ndarray:
    """The mesher's vertical element size (m) at the levels ``z`` (m, up; ground surface 0).

    ``min_k (dz_k + (growth - 1) |z - z_k|)`` over the ``foci`` ``(z_k, dz_k)``, at most
    ``dz_max`` above the deepest toe ``z_deepest`` and ``dz_max_deep`` below it.
    """
    val = np.full_like(z, np.inf)
    for zf, d0 in foci:
        val = np.minimum(val, d0 + (growth - 1.0) * np.abs(z - zf))
    return np.minimum(val, np.where(z >= z_deepest, dz_max, dz_max_deep))


def size_integral(z0: float, z1: float, size: Callable[[np.ndarray], np.ndarray]
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Distances from ``z0`` towards ``z1`` (m, 4001 samples) and ``int 1 / size`` up to each.

    A slab has ``max(min_layer_divisions, ceil(total - 1e-6))`` elements (:func:`slab_elements`).
    """
    s = np.linspace(0.0, abs(z1 - z0), 4001)
    w = 1.0 / size(z0 + np.sign(z1 - z0) * s)
    return s, np.concatenate([[0.0], np.cumsum(0.5 * (w[1:] + w[:-1]) * np.diff(s))])


def slab_elements(total: float, n_min: int) -> int:
    """Elements across a slab whose ``int 1 / dz`` is ``total``: at least ``n_min``."""
    return max(n_min, int(np.ceil(total - 1e-6)))


def plan_quads(sc: EstimatedScenario) -> float:
    """Estimated plan quads of the whole block (no symmetry reduction).

    The structured region (the cap, or the piles' bounding box widened by the mesher's margin)
    is a grid of pile cells, each an o-grid of ``N`` edges around its pile (``N`` from the
    thickest pile: ``max(n_circ_min, 4 ceil(pi d / 4 size_m))``): ``(N/4)^2 + N m_in`` quads
    inside the pile and ``N m_out`` outside, ``m_out`` radial edges from ``size_m`` at the
    pile growing to the cell side's edge. The far field around it is graded from that edge by
    ``growth`` up to ``far_field_size_m``: the integral of ``1 / size^2`` over the band, times
    :data:`FAR_FIELD_FILL` (an unstructured quad mesh has more quads than its size field).
    """
    m = sc.numerics.mesh
    h, h_far = m.size_m, max(m.far_field_size_m, m.size_m)
    n = edges_around(max(sc.piles.diameters), h, m.n_circ_min)
    xs = {round(x, 6) for x, _ in sc.piles.xy}
    ys = {round(y, 6) for _, y in sc.piles.xy}
    if sc.cap is not None:
        w, b = sc.cap.size_x_m, sc.cap.size_y_m
    else:
        pad = max(sc.piles.diameters) + 2.0 * NEAR_FIELD_MARGIN
        w, b = max(xs) - min(xs) + pad, max(ys) - min(ys) + pad
    # within the block (a layout off the block is refused by the scenario's own checks)
    w, b = min(w, sc.site.size_x_m), min(b, sc.site.size_y_m)
    cw, cb = w / len(xs), b / len(ys)
    side = min(cw, cb) / (n / 4)
    reach = max(0.5 * math.hypot(cw, cb) - 0.5 * min(sc.piles.diameters), h)
    m_out = math.ceil(graded_count(reach, h, max(side, h), OGRID_GROWTH) - 1e-9)
    cells = len(xs) * len(ys) * ((n / 4) ** 2 + n * (OGRID_INSIDE + m_out))
    return cells + FAR_FIELD_FILL * _far_field_quads(sc, 2.0 * (w + b), w * b, min(side, h_far))


def _far_field_quads(sc: EstimatedScenario, perimeter: float, inner: float, edge: float) -> float:
    """Quads of the block outside a region of ``perimeter`` and area ``inner`` (m, m^2).

    Sizes ``edge + (growth - 1) t`` at the distance ``t`` from the region, up to
    ``far_field_size_m``, over the block's area.
    """
    m = sc.numerics.mesh
    h_far, a = max(m.far_field_size_m, m.size_m), m.growth - 1.0
    avail = max(sc.site.size_x_m * sc.site.size_y_m - inner, 0.0)
    t = (h_far - edge) / a  # where the size reaches h_far
    if perimeter * t + math.pi * t * t > avail:  # the band fills the block first
        t = 2.0 * avail / (perimeter + math.hypot(perimeter, 2.0 * math.sqrt(math.pi * avail)))
    u = edge + a * t
    band = (perimeter * (1.0 / edge - 1.0 / u)
            + 2.0 * math.pi / a * (math.log(u / edge) + edge / u - 1.0)) / a
    return band + max(avail - perimeter * t - math.pi * t * t, 0.0) / h_far ** 2


def element_layers(sc: EstimatedScenario) -> float:
    """Element layers of the extrusion (soil and cap), by the mesher's rule (docs/geometry.md).

    The soil column is cut at every layer boundary, pile toe and the water table; a slab has
    :func:`slab_elements` of the :func:`size_integral` of :func:`column_sizes` (from the ground
    surface, ``dz_surface_m``, and the toes, ``dz_toe_m``); the cap's slabs (cut at the pile
    tops) ``ceil(thickness / dz_cap_m)``.
    """
    m = sc.numerics.mesh
    depth = sc.site.depth_m
    toes = sorted(set(sc.piles.lengths))
    bottoms = list(itertools.accumulate(lay.thickness_m or depth for lay in sc.layers))
    cuts = sorted({0.0, depth, *toes, *(d for d in bottoms if d < depth),
                   *([sc.site.water_table_depth_m] if sc.site.water_table_depth_m > 0 else [])})
    foci = [(0.0, m.dz_surface_m)] + [(-t, m.dz_toe_m) for t in toes]

    def size(z: np.ndarray) -> np.ndarray:
        return column_sizes(z, foci, m.dz_growth, -toes[-1], m.dz_max_m, m.dz_max_deep_m)

    n = sum(slab_elements(size_integral(-top, -bot, size)[1][-1], m.min_layer_divisions)
            for top, bot in itertools.pairwise(cuts))
    if sc.cap is not None:
        t = sc.cap.thickness_m
        levels = sorted({0.0, t, sc.piles.embedment_m})
        n += sum(math.ceil((hi - lo) / m.dz_cap_m - 1e-6) for lo, hi in itertools.pairwise(levels)
                 if hi - lo > 1e-9 * t)
    return float(n)


def estimated_cells(sc: EstimatedScenario) -> float:
    """Conservative estimate of the mesh's hexahedra (see the module docstring)."""
    return SAFETY * plan_quads(sc) * element_layers(sc)


def estimated_unknowns(sc: EstimatedScenario, fraction: float = 1.0) -> float:
    """Central estimate of the unknowns of the whole model (or of its kept ``fraction``).

    The cells without :data:`SAFETY`, times :data:`VERTICES_PER_CELL`, times the unknowns
    per vertex of the scenario's element pair (:data:`UNKNOWNS_PER_VERTEX`).
    """
    cells = estimated_cells(sc) / SAFETY * fraction
    return cells * VERTICES_PER_CELL * UNKNOWNS_PER_VERTEX[sc.numerics.element]


__all__ = ["MAX_CELLS", "SAFETY", "UNKNOWNS_PER_VERTEX", "VERTICES_PER_CELL", "column_sizes",
           "edges_around", "element_layers", "estimated_cells", "estimated_unknowns",
           "graded_count", "plan_quads", "size_integral", "slab_elements"]
