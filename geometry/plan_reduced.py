"""The plan view (z = 0) of a symmetry-reduced model: the kept half or quarter of the full plan.

The full model's structured grid (:func:`~pilegroup.geometry.plan.cell_grid`) is computed
first. Cells in the kept part (x >= 0 for the plane x = 0, y >= 0 for y = 0) are built exactly
as in the full model; cells wholly on the other side are dropped; a cell that straddles a plane
is centred on it (the grid of a symmetric layout is symmetric) and is split along it:

* its o-grid quadrants whose middle direction lies on the plane (top and bottom for x = 0, left
  and right for y = 0) are halved by a radial node line from the inner square through the pile
  surface to the cell side; the other quadrants are kept or dropped whole;
* the inner square (and a cell without a pile) is cut along its mid-line.

Every curve keeps the full model's edges: a quadrant of ``nq = N / 4`` edges halves into
``nq / 2`` edges when ``nq`` is even (the plane is a node line of the full o-grid). When ``nq``
is odd the plane runs through the middle of the full model's middle edge: the half keeps
``(nq - 1) / 2`` full edges plus one half edge at the plane, and on the pile surface the node on
the plane is the midpoint of the full model's chord, so the cut pile cross-section is exactly
half (a quarter) of the full model's N-gon. Curves on a plane lie exactly on it (their
coordinate normal to it is 0.0), so every mesh node on them does too.

The far field is the kept part of the block minus the kept structured region: one surface whose
boundary runs along the block sides, the planes (geometric edges from the structured region
outwards) and the structured outline; its edge count is made even for an all-quad mesh.
"""

from __future__ import annotations

import math
from collections import Counter

import gmsh

from pilegroup.geometry.plan import (
    PlanSurface,
    PlanView,
    cell_grid,
    circumferential_divisions,
    outline_edge,
    pile_cell,
    progression,
    radial_edges,
)
from pilegroup.geometry.spec import GeometrySpec
from pilegroup.geometry.symmetry import TOL

__all__ = ["build_reduced_plan"]

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

    ``half``: ``a`` is a node of the full model, ``b`` the side's midpoint on a plane; for odd
    ``n`` the half edge is the one at ``b``.
    """
    if not half or n % 2 == 0:
        line = pv.line(a, b)
        pv.edges(line, n // 2 if half else n)
        return [line]
    j = n // 2
    (xa, ya), (xb, yb) = pv.coords[a], pv.coords[b]
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
        self.r = p.radius
        self.a = 0.6 * p.radius * _S  # half side of the inner square
        self.m_in, self.m_out, self.coef = radial_edges(spec, p, [pv.coords[t] for t in g],
                                                        n_circ)
        self.centre = pv.point(self.cx, self.cy)
        # on an odd quadrant the node on the plane is the midpoint of the full model's chord
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
            gx, gy = pv.coords[self.g[k]]
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


def _structured(pv: PlanView, spec: GeometrySpec, n_circ: int) -> None:
    """The blocks of the kept structured region."""
    planes = spec.cut_planes()
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


def _loop(curves: list[int], ends: dict[int, tuple[int, int]]) -> list[int]:
    """``curves`` (positive tags) ordered and signed into one closed loop."""
    links: dict[int, list[tuple[int, int]]] = {}
    for c in curves:
        p, q = ends[c]
        links.setdefault(p, []).append((c, q))
        links.setdefault(q, []).append((-c, p))
    start = ends[curves[0]][0]
    out, at = [], start
    while True:
        c, nxt = next((c, n) for c, n in links[at] if not out or abs(c) != abs(out[-1]))
        out.append(c)
        at = nxt
        if at == start:
            break
    if len(out) != len(curves):
        raise RuntimeError(f"far-field boundary is not one loop ({len(out)} of {len(curves)} "
                           "curves)")
    return out


def _far_field(pv: PlanView, spec: GeometrySpec) -> list[int]:
    """The far field of the kept part: one recombined surface, appended to ``pv.surfaces``.

    Returns the structured outline (the curves the far field shares with the blocks).
    """
    planes = spec.cut_planes()
    ends = {tag: pq for pq, tag in pv.lines.items()}
    use = Counter(abs(c) for curves in pv.block_curves for c in curves)

    def on_plane(tag: int) -> bool:
        (xp, yp), (xq, yq) = (pv.coords[t] for t in ends[tag])
        return ("x" in planes and xp == 0.0 == xq) or ("y" in planes and yp == 0.0 == yq)

    outline = sorted(t for t, n in use.items() if n == 1 and not on_plane(t))
    bx0, bx1, by0, by1 = spec.plan_bounds()
    sx0, sx1, sy0, sy1 = spec.structured_region()
    sx0, sy0 = (0.0 if "x" in planes else sx0), (0.0 if "y" in planes else sy0)
    # the planes from the structured region out to the block sides: edges grow geometrically
    rays = []
    if "x" in planes:
        rays += [((0.0, sy1), (0.0, by1))] + ([] if "y" in planes else [((0.0, sy0), (0.0, by0))])
    if "y" in planes:
        rays += [((sx1, 0.0), (bx1, 0.0))] + ([] if "x" in planes else [((sx0, 0.0), (bx0, 0.0))])
    sz = spec.sizing
    edge = outline_edge(spec)
    extra = []
    for a, b in rays:
        ray = pv.line(pv.point(*a), pv.point(*b))
        pv.edges(ray, *progression(math.dist(a, b), edge, sz.h_far))
        extra.append(ray)
    corners = [(bx0, by0), (bx1, by0), (bx1, by1), (bx0, by1)]
    sides = []
    for k in range(4):
        if (k == 0 and "y" in planes) or (k == 3 and "x" in planes):
            continue  # on a plane: the rays and the structured region cover it
        a, b = corners[k], corners[(k + 1) % 4]
        side = pv.line(pv.point(*a), pv.point(*b))
        pv.edges(side, max(2, math.ceil(math.dist(a, b) / sz.h_far - 1e-9)))
        sides.append((math.dist(a, b), side))
    total = sum(pv.transfinite[abs(c)][0] for c in [*outline, *extra, *(s for _, s in sides)])
    if total % 2:  # an odd boundary leaves a triangle in the recombined far field
        _, longest = max(sides)
        pv.edges(longest, pv.transfinite[longest][0] + 1)
    ends = {tag: pq for pq, tag in pv.lines.items()}
    loop = _loop([*outline, *extra, *(s for _, s in sides)], ends)
    far = gmsh.model.geo.addPlaneSurface([gmsh.model.geo.addCurveLoop(loop, reorient=True)])
    gmsh.model.geo.mesh.setRecombine(2, far)
    pv.surfaces.append(PlanSurface(far, len(loop), None, False))
    return outline


def build_reduced_plan(spec: GeometrySpec) -> tuple[list[PlanSurface], list[int]]:
    """Create the plan-view surfaces at z = 0 of a reduced ``spec`` in the current gmsh model.

    ``spec.symmetry`` is not "none". Returns the surfaces (the far field last) and the curves
    of the structured region's outline off the planes (as
    :func:`~pilegroup.geometry.plan.build_plan`).
    """
    b = spec.block
    pv = PlanView(max(b.size_x, b.size_y))
    n_circ = circumferential_divisions(spec)
    _structured(pv, spec, n_circ)
    outline = _far_field(pv, spec)
    pv.set_transfinite()
    return pv.surfaces, outline
