"""The structured cells of a plan part: whole, or cut at the mirror planes x = 0 / y = 0.

A *part* of the plan is what a model cut at ``planes`` keeps (x >= 0 for the plane x = 0,
y >= 0 for y = 0; the whole plan for no plane). The whole model's structured grid
(:func:`~pilegroup.geometry.plan.cell_grid`) is computed first. Cells in the part are built as
o-grids (:func:`~pilegroup.geometry.plan.pile_cell`); cells wholly on the other side of a plane
are dropped; a cell that straddles a plane is centred on it (the grid of a symmetric layout is
symmetric) and is split along it:

* its o-grid quadrants whose middle direction lies on the plane (top and bottom for x = 0, left
  and right for y = 0) are halved by a radial node line from the inner square through the pile
  surface to the cell side; the other quadrants are kept or dropped whole;
* the inner square (and a cell without a pile) is cut along its mid-line.

Every curve keeps the uncut o-grid's edges: a quadrant of ``nq = N / 4`` edges halves into
``nq / 2`` edges when ``nq`` is even (the plane is a node line of the uncut o-grid). When ``nq``
is odd the plane runs through the middle of the uncut o-grid's middle edge: the half keeps
``(nq - 1) / 2`` whole edges plus one half edge at the plane, and on the pile surface the node on
the plane is the midpoint of the uncut N-gon's chord, so the cut pile cross-section is exactly
half (a quarter) of the N-gon. Curves on a plane lie exactly on it (their coordinate normal to
it is 0.0), so every mesh node on them does too.

A whole model of a mirror-symmetric layout is made of its part and the part's mirror images
(:mod:`pilegroup.geometry.far_field`), which share the curves on the planes.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence

from pilegroup.geometry.plan import PlanView, cell_grid, pile_cell, polygon_radius, radial_edges
from pilegroup.geometry.spec import GeometrySpec
from pilegroup.geometry.symmetry import TOL

__all__ = ["outline", "structured_cells"]

_S = math.sqrt(0.5)
#: Quadrants of the o-grid's corner radials (k = 0..3, counter-clockwise from the top right)
#: and directions of the middle radials of the quadrants between corner k and k + 1 (top, left,
#: bottom, right): the quadrant k is halved by the plane x = 0 for k = 0, 2, by y = 0 for 1, 3.
_CORNER = ((1.0, 1.0), (-1.0, 1.0), (-1.0, -1.0), (1.0, -1.0))
_MIDDLE = ((0.0, 1.0), (-1.0, 0.0), (0.0, -1.0), (1.0, 0.0))


def _reverse(path: list[int]) -> list[int]:
    return [-c for c in reversed(path)]


def _straight(pv: PlanView, a: int, b: int, n: int, half: bool) -> list[int]:
    """Curves from point ``a`` to ``b``: a side of ``n`` edges, or half of one.

    ``half``: ``a`` is a node of the uncut side, ``b`` the side's midpoint on a plane; for odd
    ``n`` the half edge is the one at ``b``.
    """
    if not half or n % 2 == 0:
        line = pv.line(a, b)
        pv.edges(line, n // 2 if half else n)
        return [line]
    j = n // 2
    (xa, ya), (xb, yb) = pv.xy(a), pv.xy(b)
    f = 2 * j / n
    t = pv.point(xa + f * (xb - xa), ya + f * (yb - ya))
    first, last = pv.line(a, t), pv.line(t, b)
    pv.edges(first, j)
    pv.edges(last, 1)
    return [first, last]


class _CutPile:
    """The points and curves of one pile's o-grid in a cell split by a plane.

    ``g``: the cell's corner points (top right first, counter-clockwise); ``cut``: which planes
    run through the cell's middle, (x, y).
    """

    def __init__(self, pv: PlanView, spec: GeometrySpec, i: int, g: list[int],
                 cut: tuple[bool, bool], n_circ: int) -> None:
        p = spec.piles[i]
        self.pv, self.pile, self.g, self.cut = pv, i + 1, g, cut
        self.nq = n_circ // 4
        self.cx = 0.0 if cut[0] else p.x
        self.cy = 0.0 if cut[1] else p.y
        self.r = polygon_radius(p.radius, n_circ)
        self.a = 0.6 * self.r * _S  # half side of the inner square
        self.m_in, self.m_out, self.coef = radial_edges(spec, p, [pv.xy(t) for t in g],
                                                        n_circ)
        self.centre = pv.point(self.cx, self.cy)
        # on an odd quadrant the node on the plane is the midpoint of the uncut N-gon's chord
        self.r_mid = self.r if self.nq % 2 == 0 else self.r * math.cos(math.pi / n_circ)

    def at(self, dx: float, dy: float) -> int:
        """The point at (dx, dy) m from the pile centre (on a plane when that offset is 0)."""
        return self.pv.point(self.cx + dx, self.cy + dy)

    def radial(self, k: int, middle: bool) -> tuple[int, int, int]:
        """Points (inner square, pile surface, cell side) of a radial node line.

        The corner radial ``k``, or (``middle``) the one halving quadrant ``k``; its spoke and
        diagonal curves are made too.
        """
        pv = self.pv
        if middle:
            dx, dy = _MIDDLE[k]
            s, q = self.at(self.a * dx, self.a * dy), self.at(self.r_mid * dx, self.r_mid * dy)
            # the middle of cell side k (from corner k to k + 1), on the plane
            gx, gy = pv.xy(self.g[k])
            g = pv.point(0.0 if dx == 0.0 else gx, 0.0 if dy == 0.0 else gy)
        else:
            dx, dy = _CORNER[k]
            s = self.at(self.a * dx, self.a * dy)
            q = self.at(self.r * _S * dx, self.r * _S * dy)
            g = self.g[k]
        pv.edges(pv.line(s, q), self.m_in)
        pv.edges(pv.line(q, g), self.m_out, self.coef)
        return s, q, g

    def arc_half(self, k: int, corner: int) -> list[int]:
        """Pile surface from corner radial ``corner`` (k or k + 1) to quadrant ``k``'s middle."""
        pv, nq = self.pv, self.nq
        q = self.radial(corner % 4, False)[1]
        m = self.radial(k, True)[1]
        if nq % 2 == 0:
            arc = pv.arc(q, self.centre, m)
            pv.edges(arc, nq // 2)
            return [arc]
        j = nq // 2
        a0 = math.pi / 4 + corner * math.pi / 2
        ang = a0 + (1 if corner == k else -1) * j * (math.pi / 2) / nq
        t = pv.point(self.cx + self.r * math.cos(ang), self.cy + self.r * math.sin(ang))
        arc, chord = pv.arc(q, self.centre, t), pv.line(t, m)
        pv.edges(arc, j)
        pv.edges(chord, 1)
        return [arc, chord]

    def sector(self, k: int, half: int | None) -> None:
        """Pile and soil blocks of quadrant ``k``, whole or half.

        ``half``: ``None`` (whole), 0 (from corner k to the middle) or 1 (from the middle to
        corner k + 1).
        """
        pv, nq, k1 = self.pv, self.nq, (k + 1) % 4
        if half is None:
            ra, rb = self.radial(k, False), self.radial(k1, False)
            paths = [[pv.line(ra[0], rb[0])], [pv.arc(ra[1], self.centre, rb[1])],
                     [pv.line(ra[2], rb[2])]]
            for path in paths:
                pv.edges(path[0], nq)
            pv.grade_side(paths[2][0], k, (self.cx, self.cy, self.r), (self.m_out, self.coef))
        else:
            corner = k if half == 0 else k1
            rc, rm = self.radial(corner, False), self.radial(k, True)
            paths = [_straight(pv, rc[0], rm[0], nq, True), self.arc_half(k, corner),
                     _straight(pv, rc[2], rm[2], nq, True)]
            ra, rb = (rc, rm) if half == 0 else (rm, rc)
            if half == 1:
                paths = [_reverse(path) for path in paths]
        inner, circle, outer = paths
        spoke_a, spoke_b = pv.line(ra[0], ra[1]), pv.line(rb[0], rb[1])
        diag_a, diag_b = pv.line(ra[1], ra[2]), pv.line(rb[1], rb[2])
        pv.block([*inner, spoke_b, *_reverse(circle), -spoke_a], [ra[0], rb[0], rb[1], ra[1]],
                 self.pile)
        pv.block([*circle, diag_b, *_reverse(outer), -diag_a], [ra[1], rb[1], rb[2], ra[2]],
                 None)

    def build(self) -> None:
        """Every kept sector and the kept part of the inner square."""
        cut_x, cut_y = self.cut
        for k in range(4):
            mx, my = _MIDDLE[k]
            if (cut_x and mx == 0.0) or (cut_y and my == 0.0):
                for half, (dx, dy) in ((0, _CORNER[k]), (1, _CORNER[(k + 1) % 4])):
                    if _inside(mx + _S * dx, my + _S * dy, self.cut):
                        self.sector(k, half)
            elif _inside(mx, my, self.cut):
                self.sector(k, None)
        _rectangle(self.pv, (self.cx - self.a, self.cx + self.a, self.cy - self.a,
                             self.cy + self.a), self.cut, self.nq, self.pile)


def _inside(dx: float, dy: float, cut: tuple[bool, bool]) -> bool:
    """Whether the direction (dx, dy) from a cell's centre points into the kept part."""
    return (not cut[0] or dx > 0.0) and (not cut[1] or dy > 0.0)


def _rectangle(pv: PlanView, box: tuple[float, float, float, float], cut: tuple[bool, bool],
               nq: int, pile: int | None) -> None:
    """The kept part of a rectangle cut through its middle: one transfinite block.

    ``box``: (x0, x1, y0, y1) m with ``nq`` edges a side; ``cut``: which planes cut it (x, y).
    """
    x0, x1, y0, y1 = box
    xa = 0.0 if cut[0] else x0
    ya = 0.0 if cut[1] else y0
    c = [pv.point(x1, y1), pv.point(xa, y1), pv.point(xa, ya), pv.point(x1, ya)]
    curves = [*_straight(pv, c[0], c[1], nq, cut[0]), *_straight(pv, c[1], c[2], nq, cut[1]),
              *_reverse(_straight(pv, c[3], c[2], nq, cut[0])),
              *_reverse(_straight(pv, c[0], c[3], nq, cut[1]))]
    pv.block(curves, c, pile)


def _span(lo: float, hi: float, cut: bool) -> str:
    """A cell edge interval [lo, hi] against a plane at 0: "keep", "drop" or "cut"."""
    if not cut or lo >= -TOL:
        return "keep"
    return "drop" if hi <= TOL else "cut"


def _snap(values: list[float], cut: bool) -> list[float]:
    """Grid lines within TOL of a plane moved onto it."""
    return [0.0 if cut and abs(v) <= TOL else v for v in values]


def structured_cells(pv: PlanView, spec: GeometrySpec, planes: Sequence[str],
                     n_circ: int) -> None:
    """Record the blocks of the structured region of the part cut at ``planes`` in ``pv``."""
    xb, yb, cell_pile = cell_grid(spec)
    xb, yb = _snap(xb, "x" in planes), _snap(yb, "y" in planes)
    nq = n_circ // 4
    for ix in range(len(xb) - 1):
        sx = _span(xb[ix], xb[ix + 1], "x" in planes)
        for iy in range(len(yb) - 1):
            sy = _span(yb[iy], yb[iy + 1], "y" in planes)
            if "drop" in (sx, sy):
                continue
            box = (xb[ix], xb[ix + 1], yb[iy], yb[iy + 1])
            g = [pv.point(box[1], box[3]), pv.point(box[0], box[3]), pv.point(box[0], box[2]),
                 pv.point(box[1], box[2])]
            cut = (sx == "cut", sy == "cut")
            i = cell_pile.get((ix, iy))
            if any(cut):
                if i is None:
                    _rectangle(pv, box, cut, nq, None)
                else:
                    _CutPile(pv, spec, i, g, cut, n_circ).build()
                continue
            sides = [pv.line(g[k], g[(k + 1) % 4]) for k in range(4)]
            for s in sides:
                pv.edges(s, nq)
            if i is None:
                pv.block(sides, g, None)
            else:
                pile_cell(pv, spec, i, g, sides, n_circ)


def outline(pv: PlanView, first_block: int, planes: Sequence[str]) -> list[int]:
    """Curves of the outline of the structured blocks recorded from ``first_block`` on.

    The curves one of those blocks uses and no other, except those on a plane in ``planes``:
    the boundary the part's structured region shares with its far field.
    """
    use = Counter(abs(c) for b in pv.blocks[first_block:] for c in b.curves)

    def on_plane(curve: int) -> bool:
        c = pv.curves[curve]
        (xp, yp), (xq, yq) = pv.coords[c.p], pv.coords[c.q]
        return ("x" in planes and xp == 0.0 == xq) or ("y" in planes and yp == 0.0 == yq)

    return sorted(t for t, n in use.items() if n == 1 and not on_plane(t))
