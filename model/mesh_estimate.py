"""A rough, conservative count of the cells a scenario's mesh will have, before any meshing.

The mesh is plan quads extruded down through the layers (docs/geometry.md), so the count is
(plan quads) x (element layers), each estimated from the sizing keys of ``numerics.mesh``:

* plan: around each pile (diameter ``d``) the element size grows from ``h_eff = min(size_m,
  pi d / n_circ_min)`` by the factor ``growth`` per element up to ``far_field_size_m``
  (``h_far``); integrating ``1 / size^2`` over that graded annulus gives ``2 pi R / a
  (1/h_eff - 1/h_far) + 2 pi / a^2 (ln(h_far/h_eff) + h_eff/h_far - 1)`` quads per pile
  (``a = growth - 1``), and the rest of the block holds ``area / h_far^2``;
* vertical: the same graded integral of ``1 / dz`` from the ground surface and the pile toes
  (every distinct toe level), plus ``min_layer_divisions + 1`` per slab (rounding up per
  layer, toe cut, water table and cap).

The product times :data:`SAFETY` is above the real cell count of the whole model by 1.3-3x
for the bundled scenarios and the benchmark meshes (h = 0.1-1 m; ``tests/model/test_fuzz.py``
checks the bound on meshes); a symmetry-reduced model has a half or a quarter of those cells.
:data:`MAX_CELLS` is the largest estimate a scenario may have.
"""

from __future__ import annotations

import math
from collections import Counter
from typing import Protocol

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
#: Factor on the graded-mesh integral (the quads are not the ideal sizes everywhere).
SAFETY = 2.0
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


def plan_quads(sc: EstimatedScenario) -> float:
    """Estimated plan quads of the whole block (no symmetry reduction).

    Every pile circle has the same number of edges, set by the thickest pile (the o-grid cells
    share their sides): a thinner pile's first element is ``h_eff`` scaled by its diameter
    over the largest one.
    """
    m = sc.numerics.mesh
    h_far = max(m.far_field_size_m, m.size_m)
    a = m.growth - 1.0
    d_max = max(sc.piles.diameters)
    total = 0.0
    for d, count in Counter(sc.piles.diameters).items():
        h = min(m.size_m, math.pi * d / m.n_circ_min, h_far)
        if d < d_max:
            h = min(h, m.size_m * d / d_max)
        per_pile = (math.pi * d / a * (1.0 / h - 1.0 / h_far)
                    + 2.0 * math.pi / a ** 2 * (math.log(h_far / h) + h / h_far - 1.0))
        total += count * per_pile
    return total + sc.site.size_x_m * sc.site.size_y_m / h_far ** 2


def element_layers(sc: EstimatedScenario) -> float:
    """Estimated element layers of the extrusion (soil and cap).

    The column is graded from the ground surface and from every distinct toe level: each
    stretch between two of these levels is refined from both of its ends.
    """
    m = sc.numerics.mesh
    depth = sc.site.depth_m
    toes = sorted(set(sc.piles.lengths))
    n = 0.0
    top, first = 0.0, m.dz_surface_m
    for toe in toes:
        n += (graded_count((toe - top) / 2, first, m.dz_max_m, m.dz_growth)
              + graded_count((toe - top) / 2, m.dz_toe_m, m.dz_max_m, m.dz_growth))
        top, first = toe, m.dz_toe_m
    n += graded_count(depth - top, m.dz_toe_m, m.dz_max_deep_m, m.dz_growth)
    slabs = len(sc.layers) + len(toes) + (sc.site.water_table_depth_m > 0.0)  # its surface
    if sc.cap is not None:
        n += sc.cap.thickness_m / m.dz_cap_m
        slabs += 2
    return n + slabs * (m.min_layer_divisions + 1)


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


__all__ = ["MAX_CELLS", "SAFETY", "UNKNOWNS_PER_VERTEX", "VERTICES_PER_CELL", "element_layers",
           "estimated_cells", "estimated_unknowns", "graded_count", "plan_quads"]
