"""The plan view (z = 0) of the pier builder: the recorder of points, curves and blocks, o-grids.

The structured region (the cap outline, or the pile circles' bounding box plus
``near_field_margin`` without a cap) is cut into a rectilinear grid of cells, one per pile, with
cell edges between pile rows and columns (half-way between equal piles; a thicker pile gets
the larger share of the gap to a thinner one). Each pile cell is an o-grid: inside the pile
an inner square plus four curved blocks, outside it four blocks from the circle to the cell
sides; every block is transfinite, so pile cross-sections are structured.
``N = max(n_circ_min, 4 ceil(pi d / (4 h)))`` edges (``d`` the largest diameter) run around
every circle, whatever its diameter, and ``N / 4`` along every cell side; the radial edges
next to the pile start at ``h`` and grow geometrically towards the cell side
(:mod:`pilegroup.geometry.plan_cells` cuts cells at mirror planes,
:mod:`pilegroup.geometry.far_field` meshes the rest of the plan).

:class:`PlanView` records everything first and emits it into the gmsh built-in "geo" kernel at
once: a recorded part can be mirrored (``sign``), coincident points and straight curves are
shared, and a curve can be split into single-edge lines through its nodes after the blocks
that use it exist (the far field's boundary). Besides transfinite blocks it records *free*
surfaces whose mesh is given: every node and interior edge of the mesh is embedded in the
surface (:class:`Embedded`), every boundary edge is a single-edge line, so gmsh's
triangulation is that of the given quadrilaterals and Blossom recombination restores them
(the only perfect matching). Lengths in m.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import gmsh
import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.geometry.ring import fractions, ring_folds, side_grading
from pilegroup.geometry.spec import GeometrySpec, PileSpec
from pilegroup.model.mesh_estimate import edges_around

__all__ = [
    "CellPiles",
    "Embedded",
    "PlanSurface",
    "PlanView",
    "cell_grid",
    "circumferential_divisions",
    "outline_edge",
    "meshed_radii",
    "pile_cell",
    "polygon_radius",
    "progression",
    "radial_edges",
]

#: Plan cell (ix, iy) of the structured grid -> index (0-based) of the pile it holds.
CellPiles = dict[tuple[int, int], int]


def polygon_radius(radius: float, n_sides: int) -> float:
    """Circumradius (m) of the regular ``n_sides``-gon with the area of the circle ``radius``.

    A pile is meshed as that polygon, so its axial stiffness E A is the circle's, and its
    second moment of area is within 0.3 % of the circle's from 8 sides on (the inscribed
    12-gon has 4.5 % less area and 9 % less; docs/geometry.md).
    """
    return radius * math.sqrt(2.0 * math.pi / (n_sides * math.sin(2.0 * math.pi / n_sides)))


def circumferential_divisions(spec: GeometrySpec) -> int:
    """Number of element edges around every pile circle (multiple of 4)."""
    return edges_around(max(p.diameter for p in spec.piles), spec.sizing.h_pile,
                        spec.sizing.n_circ_min)


def meshed_radii(spec: GeometrySpec) -> list[float]:
    """Every pile's meshed circumradius (m): the corners of its polygon lie on it."""
    n = circumferential_divisions(spec)
    return [polygon_radius(p.radius, n) for p in spec.piles]


def perimeter_factor(n_sides: int) -> float:
    """The circle's circumference over the perimeter of its polygon (:func:`polygon_radius`).

    The polygon of the circle's area is longer around: by 2.7 / 1.2 / 0.65 % at 8 / 12 / 16
    sides. The interface scales the shaft's shear tractions by this factor, so that a shaft
    carries the circle's friction force per unit length on any mesh (docs/geometry.md).
    """
    side = 2.0 * polygon_radius(1.0, n_sides) * math.sin(math.pi / n_sides)
    return 2.0 * math.pi / (n_sides * side)


def shaft_factor(spec: GeometrySpec) -> float:
    """:func:`perimeter_factor` of the piles of ``spec`` (all have the same number of sides)."""
    return perimeter_factor(circumferential_divisions(spec))


@dataclass
class PlanSurface:
    """A plan-view surface: its gmsh tag, number of bounding curves and what it holds.

    ``pile`` is the pile number (1-based) of a surface inside a pile, ``None`` for soil;
    ``in_region``: the surface lies in the structured region (extruded up into the cap too).
    """

    tag: int
    n_curves: int
    pile: int | None
    in_region: bool


def progression(length: float, first: float, last: float) -> tuple[int, float]:
    """Edges and ratio of a geometric distribution of ``length`` (m) from ``first`` to ~``last``.

    Uniform (edges <= ``first``) when ``first >= last``.
    """
    if first >= last * 0.999 or length <= first:
        n = max(1, math.ceil(length / first - 1e-9))  # edges <= first (= h at the pile)
        return n, 1.0
    best: tuple[float, int, float] | None = None
    for n in range(1, 400):
        # ratio q with first * (q^n - 1) / (q - 1) = length, by bisection on q in [1, 3]
        def total(q: float, n: int = n) -> float:
            return first * n if abs(q - 1) < 1e-12 else first * (q**n - 1) / (q - 1)
        if total(1.0) > length:
            break
        lo, hi = 1.0, 3.0
        if total(hi) < length:
            continue
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            if total(mid) < length:
                lo = mid
            else:
                hi = mid
        q = 0.5 * (lo + hi)
        err = abs(math.log(first * q ** (n - 1) / last))
        if q <= 1.35 and (best is None or err < best[0]):
            best = (err, n, q)
    if best is None:  # cannot grow slowly enough: uniform with edges ~ first
        n = max(1, round(length / first))
        return n, 1.0
    return best[1], best[2]


@dataclass
class _Curve:
    """A recorded curve: a straight line from point ``p`` to ``q`` or an arc about ``centre``."""

    p: int
    q: int
    centre: int | None = None
    n: int = 0
    coef: float = 1.0
    pinned: bool = False


@dataclass
class _Block:
    """A recorded transfinite, recombined surface."""

    curves: list[int]
    corners: list[int]
    pile: int | None
    in_region: bool


@dataclass
class _Free:
    """A recorded unstructured, recombined surface whose mesh is fixed by embedded entities."""

    loops: list[list[int]]
    lines: list[int]
    points: list[int]


@dataclass
class Embedded:
    """Curves and points (gmsh tags) to embed in surface ``surface`` once the model is synced."""

    surface: int
    curves: list[int]
    points: list[int]

    def embed(self) -> None:
        """Embed them (the model must be synchronised)."""
        gmsh.model.mesh.embed(1, self.curves, 2, self.surface)
        gmsh.model.mesh.embed(0, self.points, 2, self.surface)


@dataclass
class PlanView:
    """Points, curves and transfinite blocks of the plan view, recorded, then emitted to gmsh.

    Builders work in *part* coordinates; ``sign`` (per axis, +-1) maps them to the model, so
    the same recording code makes a part and its mirror images. Points are shared within
    1e-9 x ``scale``, straight curves between the same two points too (a reference is negated
    when it runs backwards); ``pile_map`` renumbers the piles of a mirrored part (number of
    the part's pile -> number of its image). Curve ids start at 1.
    """

    scale: float
    sign: tuple[float, float] = (1.0, 1.0)
    pile_map: dict[int, int] = field(default_factory=dict)
    coords: list[tuple[float, float]] = field(default_factory=list)
    curves: list[_Curve] = field(default_factory=lambda: [_Curve(-1, -1)])
    blocks: list[_Block] = field(default_factory=list)
    chains: dict[int, list[int]] = field(default_factory=dict)
    free: list[_Free] = field(default_factory=list)
    embedded: list[Embedded] = field(default_factory=list)
    _points: dict[tuple[int, int], int] = field(default_factory=dict)
    _lines: dict[tuple[int, int], int] = field(default_factory=dict)

    def point(self, x: float, y: float) -> int:
        """The point at (x, y) m in part coordinates."""
        return self.point_at(self.sign[0] * float(x) + 0.0, self.sign[1] * float(y) + 0.0)

    def point_at(self, x: float, y: float) -> int:
        """The point at (x, y) m in model coordinates (an existing one within the tolerance)."""
        key = (round(x / self.scale * 1e9), round(y / self.scale * 1e9))
        if key not in self._points:
            self._points[key] = len(self.coords)
            self.coords.append((x, y))
        return self._points[key]

    def xy(self, p: int) -> tuple[float, float]:
        """Part coordinates (m) of point ``p``."""
        x, y = self.coords[p]
        return self.sign[0] * x + 0.0, self.sign[1] * y + 0.0

    def line(self, p: int, q: int) -> int:
        """The straight curve from ``p`` to ``q`` (an existing one, negated when reversed)."""
        if (p, q) in self._lines:
            return self._lines[(p, q)]
        if (q, p) in self._lines:
            return -self._lines[(q, p)]
        self.curves.append(_Curve(p, q))
        self._lines[(p, q)] = len(self.curves) - 1
        return len(self.curves) - 1

    def arc(self, p: int, centre: int, q: int) -> int:
        """A new circle arc from ``p`` to ``q`` about ``centre`` (less than a half circle)."""
        self.curves.append(_Curve(p, q, centre))
        return len(self.curves) - 1

    def edges(self, curve: int, n_edges: int, coef: float = 1.0, pin: bool = False) -> None:
        """Mesh ``curve`` with ``n_edges`` edges (geometric ratio ``coef`` along its direction).

        ``pin``: this ``coef`` stays when the curve's edges are set again (a cell side graded
        by :meth:`grade_side` is set again by the cell on its other side).
        """
        c = self.curves[abs(curve)]
        c.n = n_edges
        if pin or not c.pinned:
            c.coef, c.pinned = coef, c.pinned or pin

    def grade_side(self, side: int, k: int, pile: tuple[float, float, float],
                   radial: tuple[int, float]) -> None:
        """Grade o-grid cell side ``side`` (from corner ``k`` to ``k + 1``) if its ring folds.

        ``pile``: centre x, y and meshed radius (m); ``radial``: edge count and ratio from the
        circle to the side. Evenly divided, the soil blocks between the pile's arc ``k`` and
        the side may fold (:func:`~pilegroup.geometry.ring.ring_folds`); the side is then
        graded so that its middle node faces the pile (:func:`~pilegroup.geometry.ring.
        side_grading`) and keeps that grading when the neighbouring cell sets it again.
        """
        c = self.curves[abs(side)]
        a, b = self.xy(c.p), self.xy(c.q)
        if side < 0:
            a, b = b, a
        if ring_folds(pile, k, (a, b, c.n, 1.0), radial):
            ratio = side_grading(pile[:2], a, b, c.n)
            self.edges(side, c.n, ratio if side > 0 else 1.0 / ratio, pin=True)

    def block(self, curves: list[int], corners: list[int], pile: int | None,
              in_region: bool = True) -> None:
        """A transfinite, recombined surface bounded by ``curves`` with the 4 ``corners``.

        ``pile``: the part's pile number inside a pile (mapped by ``pile_map``), else ``None``.
        """
        self.blocks.append(_Block(list(curves), list(corners),
                                  None if pile is None else self.pile_map.get(pile, pile),
                                  in_region))

    def free_surface(self, loops: list[list[int]], lines: list[int], points: list[int]) -> None:
        """A recombined surface with ``lines`` and ``points`` embedded in it.

        ``loops``: its boundary as loops of points joined by their straight lines (recorded
        already), the outer loop first.
        """
        self.free.append(_Free([list(lp) for lp in loops], list(lines), list(points)))

    def split(self, curve: int) -> list[int]:
        """Make straight ``curve`` a chain of single-edge lines through its nodes."""
        c = self.curves[abs(curve)]
        if c.n == 1:
            return [curve]
        if abs(curve) not in self.chains:
            if c.centre is not None:
                raise ValueError(f"curve {curve} is not a straight line")
            (xp, yp), (xq, yq) = self.coords[c.p], self.coords[c.q]
            pts = [c.p, *(self.point_at(xp + f * (xq - xp), yp + f * (yq - yp))
                          for f in fractions(c.n, c.coef)[1:-1]), c.q]
            chain = [self.line(a, b) for a, b in zip(pts[:-1], pts[1:], strict=True)]
            for t in chain:
                self.edges(t, 1)
            self.chains[abs(curve)] = chain
        chain = self.chains[abs(curve)]
        return chain if curve > 0 else [-t for t in reversed(chain)]

    def _expand(self, curves: list[int]) -> list[int]:
        return [t for c in curves for t in (self.split(c) if abs(c) in self.chains else [c])]

    def emit(self) -> list[PlanSurface]:
        """Create the recorded points, curves and blocks in the gmsh geo kernel (z = 0)."""
        geo = gmsh.model.geo
        used = {p for cid, c in enumerate(self.curves[1:], start=1) if cid not in self.chains
                for p in (c.p, c.q, c.centre) if p is not None}
        used.update(p for f in self.free for p in f.points)
        pt = {p: geo.addPoint(*self.coords[p], 0.0) for p in sorted(used)}  # no orphan point
        tag: dict[int, int] = {}
        for cid, c in enumerate(self.curves[1:], start=1):
            if cid in self.chains:
                continue
            if c.n < 1:
                raise RuntimeError(f"plan curve {cid} has no edge count")
            tag[cid] = (geo.addLine(pt[c.p], pt[c.q]) if c.centre is None
                        else geo.addCircleArc(pt[c.p], pt[c.centre], pt[c.q]))
            geo.mesh.setTransfiniteCurve(tag[cid], c.n + 1, "Progression", c.coef)
        out = []
        for b in self.blocks:
            loop = [tag[c] if c > 0 else -tag[-c] for c in self._expand(b.curves)]
            s = geo.addPlaneSurface([geo.addCurveLoop(loop, reorient=True)])
            geo.mesh.setTransfiniteSurface(s, "Left", [pt[c] for c in b.corners])
            geo.mesh.setRecombine(2, s)
            out.append(PlanSurface(s, len(loop), b.pile, b.in_region))
        for f in self.free:
            loops = [[self.line(a, b) for a, b in zip(lp, [*lp[1:], lp[0]], strict=True)]
                     for lp in f.loops]
            s = geo.addPlaneSurface([geo.addCurveLoop([tag[c] if c > 0 else -tag[-c]
                                                       for c in loop], reorient=True)
                                     for loop in loops])
            geo.mesh.setRecombine(2, s)
            out.append(PlanSurface(s, sum(len(loop) for loop in loops), None, False))
            self.embedded.append(Embedded(s, [tag[abs(c)] for c in f.lines],
                                          [pt[p] for p in f.points]))
        return out


def _breaks(piles: tuple[PileSpec, ...], axis: str, lo: float, hi: float) -> list[float]:
    """Cell edges along ``axis`` ("x" or "y") from ``lo`` to ``hi``, between the pile rows.

    Between two neighbouring rows (distinct coordinates ``a < c``) whose largest radii are
    ``ra`` and ``rc``: half-way when the radii are equal, else where the gap between the
    piles' surfaces, ``c - a - ra - rc``, is shared in proportion to the radii, so that a
    thick pile beside a thin one keeps the same fraction of its radius to the cell edge.
    """
    radius: dict[float, float] = {}
    for p in piles:
        v = round(p.x if axis == "x" else p.y, 9)
        radius[v] = max(radius.get(v, 0.0), p.radius)
    u = sorted(radius)
    edges = []
    for a, c in zip(u[:-1], u[1:], strict=True):
        ra, rc = radius[a], radius[c]
        edges.append((a + c) / 2 if ra == rc else a + ra + (c - a - ra - rc) * ra / (ra + rc))
    return [lo, *edges, hi]


def cell_grid(spec: GeometrySpec) -> tuple[list[float], list[float], CellPiles]:
    """Cell edges in x and y of the structured region and the pile of each pile cell.

    The edges lie between the pile rows and columns (:func:`_breaks`: half-way between equal
    piles, in proportion to the radii between piles of different diameters).
    Raises :class:`~pilegroup.errors.ScenarioError` (exit code 2) if two piles share a cell or
    a pile leaves less than 0.2 x its radius to its cell edge.
    """
    x0, x1, y0, y1 = spec.structured_region()
    xb = _breaks(spec.piles, "x", x0, x1)
    yb = _breaks(spec.piles, "y", y0, y1)
    cell_pile: CellPiles = {}
    for i, p in enumerate(spec.piles):
        ix = int(np.searchsorted(xb, p.x)) - 1
        iy = int(np.searchsorted(yb, p.y)) - 1
        if (ix, iy) in cell_pile:
            raise ScenarioError(f"piles[{i}]", [p.x, p.y],
                                f"falls into the structured cell of pile {cell_pile[(ix, iy)] + 1}"
                                ": pile positions must form a rectilinear grid", "m")
        cx0, cx1, cy0, cy1 = xb[ix], xb[ix + 1], yb[iy], yb[iy + 1]
        clear = min(p.x - cx0, cx1 - p.x, p.y - cy0, cy1 - p.y) - p.radius
        if clear < 0.2 * p.radius:
            raise ScenarioError(f"piles[{i}]", [p.x, p.y],
                                f"leaves only {clear:.3g} m to its structured cell edge: piles"
                                " too close to each other or to the cap edge (need >= 0.2 x"
                                " radius)", "m")
        cell_pile[(ix, iy)] = i
    return xb, yb, cell_pile


def radial_edges(spec: GeometrySpec, p: PileSpec, corners: list[tuple[float, float]],
                 n_circ: int) -> tuple[int, int, float]:
    """Radial edges of pile ``p``'s o-grid: (inside the pile, outside it, outside ratio).

    ``corners``: the cell's corners (m), counter-clockwise from the top right. Outside the pile
    the edges start at ``h`` at the pile surface and grow towards the cell-side spacing.
    """
    r = polygon_radius(p.radius, n_circ)
    arc_len = 2 * math.pi * r / n_circ
    m_in = max(2, round(0.45 * r / arc_len))
    h = spec.sizing.h_pile
    nq = n_circ // 4
    side_h = min(math.hypot(corners[(k + 1) % 4][0] - corners[k][0],
                            corners[(k + 1) % 4][1] - corners[k][1]) for k in range(4)) / nq
    ang = [math.pi / 4 + k * math.pi / 2 for k in range(4)]
    dlen = [math.hypot(corners[k][0] - (p.x + r * math.cos(a)),
                       corners[k][1] - (p.y + r * math.sin(a))) for k, a in enumerate(ang)]
    m_out, coef = progression(float(np.mean(dlen)), h, max(side_h, h))
    return m_in, m_out, coef


def pile_cell(pv: PlanView, spec: GeometrySpec, i: int, g: list[int], sides: list[int],
               n_circ: int) -> None:
    """The o-grid of the cell with corners ``g`` and sides ``sides`` around pile ``i`` (0-based).

    Pile: an inner square and 4 curved blocks; soil: 4 blocks from the circle to the sides.
    """
    p: PileSpec = spec.piles[i]
    nq = n_circ // 4
    r = polygon_radius(p.radius, n_circ)
    c = pv.point(p.x, p.y)
    ang = [math.pi / 4 + k * math.pi / 2 for k in range(4)]
    q = [pv.point(p.x + r * math.cos(a), p.y + r * math.sin(a)) for a in ang]
    rho = 0.6 * r
    sq = [pv.point(p.x + rho * math.cos(a), p.y + rho * math.sin(a)) for a in ang]
    arcs = [pv.arc(q[k], c, q[(k + 1) % 4]) for k in range(4)]
    sq_sides = [pv.line(sq[k], sq[(k + 1) % 4]) for k in range(4)]
    spokes = [pv.line(sq[k], q[k]) for k in range(4)]
    diags = [pv.line(q[k], g[k]) for k in range(4)]
    m_in, m_out, coef = radial_edges(spec, p, [pv.xy(t) for t in g], n_circ)
    for k in range(4):
        pv.grade_side(sides[k], k, (p.x, p.y, r), (m_out, coef))
    for k in range(4):
        pv.edges(arcs[k], nq)
        pv.edges(sq_sides[k], nq)
        pv.edges(spokes[k], m_in)
    for k in range(4):
        pv.edges(diags[k], m_out, coef)
    pv.block(sq_sides, sq, i + 1)
    for k in range(4):
        k1 = (k + 1) % 4
        pv.block([sq_sides[k], spokes[k1], -arcs[k], -spokes[k]],
                 [sq[k], sq[k1], q[k1], q[k]], i + 1)
    for k in range(4):
        k1 = (k + 1) % 4
        pv.block([arcs[k], diags[k1], -sides[k], -diags[k]], [q[k], q[k1], g[k1], g[k]], None)


def outline_edge(spec: GeometrySpec) -> float:
    """Mean edge size (m) of the structured region's outline."""
    x0, x1, y0, y1 = spec.structured_region()
    nq = circumferential_divisions(spec) // 4
    nx = len({round(p.x, 9) for p in spec.piles})
    ny = len({round(p.y, 9) for p in spec.piles})
    return 0.5 * ((x1 - x0) / (nx * nq) + (y1 - y0) / (ny * nq))
