"""An o-grid ring's soil blocks: whether they fold, and the cell-side grading that unfolds them.

A pile cell's soil blocks run from a quarter of the pile's circle (``nq`` edges) to a cell side
(``nq`` edges). Divided evenly, a side whose pile lies much nearer one of its ends than the
other puts the node facing the arc's midpoint far along the side; across a thin ring with few
radial edges those blocks fold. Graded geometrically, the side's middle node faces the pile.
Pointwise geometry, no gmsh: :meth:`pilegroup.geometry.plan.PlanView.grade_side` applies it.
Lengths in m.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = ["MIN_CORNER_SINE", "fractions", "ring_folds", "side_grading"]

#: Smallest corner sine (cross product of unit edges) of a soil quadrilateral of an o-grid ring
#: below which the ring counts as folded: its cell side is then graded.
MIN_CORNER_SINE = 0.1


def fractions(n: int, coef: float) -> np.ndarray:
    """Node positions (0..1) of ``n`` edges growing by ``coef`` (gmsh's "Progression")."""
    if abs(coef - 1.0) < 1e-12:
        return np.linspace(0.0, 1.0, n + 1)
    return (1.0 - coef ** np.arange(n + 1)) / (1.0 - coef ** n)


def side_grading(centre: tuple[float, float], a: tuple[float, float], b: tuple[float, float],
                 nq: int) -> float:
    """Ratio of the ``nq`` edges from ``a`` to ``b`` whose middle is the pile centre's projection.

    With ratio ``c`` the middle of ``2 m`` edges lies at ``1 / (1 + c^m)`` of the side, so the
    node facing the pile's arc midpoint sits on the ray from the centre at right angles to the
    side (for odd ``nq`` the same formula centres the distribution there). The projection is
    kept within 5 % of the side's ends (a pile's cell keeps it well inside: ``cell_grid``).
    """
    d = np.subtract(b, a)
    s = float(np.dot(np.subtract(centre, a), d) / np.dot(d, d))
    s = min(max(s, 0.05), 0.95)
    return ((1.0 - s) / s) ** (2.0 / nq)


def ring_folds(pile: tuple[float, float, float], k: int,
               side: tuple[tuple[float, float], tuple[float, float], int, float],
               radial: tuple[int, float]) -> bool:
    """Whether the soil quadrilaterals between arc ``k`` of a pile and its cell side fold.

    ``pile``: centre x, y and meshed radius (m); ``side``: corners ``a``, ``b`` (corner ``k``
    and ``k + 1``), edge count and ratio along it; ``radial``: edge count and ratio from the
    circle outwards. The block's nodes are taken on the straight lines joining each arc node
    to its side node (the transfinite block's rows); a corner sine below
    :data:`MIN_CORNER_SINE` (or a negative one: an inverted cell) is a fold.
    """
    (px, py, r), (a, b, nq, side_coef), (m_out, coef) = pile, side, radial
    ang = math.pi / 4 + k * math.pi / 2 + (math.pi / 2) * np.arange(nq + 1) / nq
    arc = np.column_stack([px + r * np.cos(ang), py + r * np.sin(ang)])
    f = fractions(nq, side_coef)[:, None]
    outer = np.asarray(a) + f * (np.subtract(b, a))
    t = fractions(m_out, coef)[:, None, None]
    nodes = arc[None] + t * (outer - arc)[None]  # (layer, node along the side, xy)
    # every quadrilateral counter-clockwise: outer j, outer j + 1, inner j + 1, inner j
    quad = np.stack([nodes[1:, :-1], nodes[1:, 1:], nodes[:-1, 1:], nodes[:-1, :-1]], axis=2)
    e_next = np.roll(quad, -1, axis=2) - quad
    e_prev = np.roll(quad, 1, axis=2) - quad
    cross = e_next[..., 0] * e_prev[..., 1] - e_next[..., 1] * e_prev[..., 0]
    norm = np.linalg.norm(e_next, axis=-1) * np.linalg.norm(e_prev, axis=-1)
    return bool(np.min(cross / np.maximum(norm, 1e-300)) < MIN_CORNER_SINE)

