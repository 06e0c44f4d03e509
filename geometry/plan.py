"""The plan view (z = 0) of the pier builder: o-grid pile cells and the unstructured far field.

The structured region (the cap outline, or the pile circles' bounding box plus
``near_field_margin`` without a cap) is cut into a rectilinear grid of cells, one per pile, with
cell edges half-way between pile rows and columns. Each pile cell is an o-grid: inside the pile
an inner square plus four curved blocks, outside it four blocks from the circle to the cell
sides; every block is transfinite, so pile cross-sections are structured.
``N = max(n_circ_min, 4 ceil(pi d / (4 h)))`` edges run around each circle and ``N / 4`` along
every cell side; the radial edges next to the pile start at ``h`` and grow geometrically towards
the cell side. Outside the structured region the plan is meshed unstructured (Frontal-Delaunay
for quads + Blossom recombination), sized by the distance to the region outline, growing by
``growth`` up to ``h_far``. Lengths in m; gmsh built-in "geo" kernel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import gmsh
import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.geometry.spec import GeometrySpec, PileSpec

__all__ = [
    "FAR_FIELD_ALGORITHMS",
    "CellPiles",
    "PlanSurface",
    "PlanView",
    "build_plan",
    "cell_grid",
    "circumferential_divisions",
    "mesh_plan",
    "outline_edge",
    "pile_cell",
    "progression",
    "radial_edges",
    "set_far_field_size",
]

#: gmsh 2D algorithms tried for the far field (6 Frontal-Delaunay, 5 Delaunay, 8 Frontal-Delaunay
#: for quads), all with Blossom recombination.
FAR_FIELD_ALGORITHMS = (6, 5, 8)

#: Plan cell (ix, iy) of the structured grid -> index (0-based) of the pile it holds.
CellPiles = dict[tuple[int, int], int]


def circumferential_divisions(spec: GeometrySpec) -> int:
    """Number of element edges around every pile circle (multiple of 4)."""
    d = max(p.diameter for p in spec.piles)
    h = spec.sizing.h_pile
    return max(spec.sizing.n_circ_min, 4 * math.ceil(math.pi * d / (4.0 * h) - 1e-9))


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


class PlanView:
    """Points, curves and surfaces of the plan view in the geo kernel (shares coincident ones).

    Transfinite curve counts are collected and set once, after every surface exists.
    """

    def __init__(self, scale: float) -> None:
        self.scale = scale
        self.points: dict[tuple[int, int], int] = {}
        self.lines: dict[tuple[int, int], int] = {}
        self.coords: dict[int, tuple[float, float]] = {}
        self.surfaces: list[PlanSurface] = []
        self.block_curves: list[list[int]] = []
        self.transfinite: dict[int, tuple[int, float]] = {}

    def point(self, x: float, y: float) -> int:
        """The point at (x, y) m, z = 0 (an existing one within 1e-9 x scale)."""
        key = (round(x / self.scale * 1e9), round(y / self.scale * 1e9))
        if key not in self.points:
            self.points[key] = gmsh.model.geo.addPoint(x, y, 0.0)
            self.coords[self.points[key]] = (x, y)
        return self.points[key]

    def line(self, p: int, q: int) -> int:
        """The straight curve from ``p`` to ``q`` (an existing one, negated when reversed)."""
        if (p, q) in self.lines:
            return self.lines[(p, q)]
        if (q, p) in self.lines:
            return -self.lines[(q, p)]
        tag = gmsh.model.geo.addLine(p, q)
        self.lines[(p, q)] = tag
        return tag

    def arc(self, p: int, centre: int, q: int) -> int:
        """A new circle arc from ``p`` to ``q`` about ``centre`` (less than a half circle)."""
        tag = gmsh.model.geo.addCircleArc(p, centre, q)
        self.lines[(p, q)] = tag
        return tag

    def edges(self, curve: int, n_edges: int, coef: float = 1.0) -> None:
        """Make ``curve`` transfinite with ``n_edges`` edges (geometric ratio ``coef``)."""
        self.transfinite[abs(curve)] = (n_edges, coef)

    def block(self, curves: list[int], corners: list[int], pile: int | None) -> None:
        """A transfinite, recombined surface bounded by ``curves`` with the 4 ``corners``."""
        loop = gmsh.model.geo.addCurveLoop(curves, reorient=True)
        s = gmsh.model.geo.addPlaneSurface([loop])
        gmsh.model.geo.mesh.setTransfiniteSurface(s, "Left", corners)
        gmsh.model.geo.mesh.setRecombine(2, s)
        self.surfaces.append(PlanSurface(s, len(curves), pile, True))
        self.block_curves.append(list(curves))

    def set_transfinite(self) -> None:
        """Set every collected transfinite curve in the gmsh model."""
        for tag, (n, coef) in self.transfinite.items():
            gmsh.model.geo.mesh.setTransfiniteCurve(tag, n + 1, "Progression", coef)


def _breaks(vals: list[float], lo: float, hi: float) -> list[float]:
    """Cell edges from ``lo`` to ``hi``: half-way between the distinct values of ``vals``."""
    u = sorted(set(round(v, 9) for v in vals))
    return [lo, *((a + c) / 2 for a, c in zip(u[:-1], u[1:], strict=True)), hi]


def cell_grid(spec: GeometrySpec) -> tuple[list[float], list[float], CellPiles]:
    """Cell edges in x and y of the structured region and the pile of each pile cell.

    Raises :class:`~pilegroup.errors.ScenarioError` (exit code 2) if two piles share a cell or
    a pile leaves less than 0.2 x its radius to its cell edge.
    """
    x0, x1, y0, y1 = spec.structured_region()
    xb = _breaks([p.x for p in spec.piles], x0, x1)
    yb = _breaks([p.y for p in spec.piles], y0, y1)
    cell_pile: CellPiles = {}
    for i, p in enumerate(spec.piles):
        ix = int(np.searchsorted(xb, p.x)) - 1
        iy = int(np.searchsorted(yb, p.y)) - 1
        if (ix, iy) in cell_pile:
            raise ScenarioError(f"piles[{i + 1}] position", [p.x, p.y],
                                f"falls into the structured cell of pile {cell_pile[(ix, iy)] + 1}"
                                ": pile positions must form a rectilinear grid", "m")
        cx0, cx1, cy0, cy1 = xb[ix], xb[ix + 1], yb[iy], yb[iy + 1]
        clear = min(p.x - cx0, cx1 - p.x, p.y - cy0, cy1 - p.y) - p.radius
        if clear < 0.2 * p.radius:
            raise ScenarioError(f"piles[{i + 1}] position", [p.x, p.y],
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
    r = p.radius
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
    r = p.radius
    c = pv.point(p.x, p.y)
    ang = [math.pi / 4 + k * math.pi / 2 for k in range(4)]
    q = [pv.point(p.x + r * math.cos(a), p.y + r * math.sin(a)) for a in ang]
    rho = 0.6 * r
    sq = [pv.point(p.x + rho * math.cos(a), p.y + rho * math.sin(a)) for a in ang]
    arcs = [pv.arc(q[k], c, q[(k + 1) % 4]) for k in range(4)]
    sq_sides = [pv.line(sq[k], sq[(k + 1) % 4]) for k in range(4)]
    spokes = [pv.line(sq[k], q[k]) for k in range(4)]
    diags = [pv.line(q[k], g[k]) for k in range(4)]
    m_in, m_out, coef = radial_edges(spec, p, [pv.coords[t] for t in g], n_circ)
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


def _far_field(pv: PlanView, spec: GeometrySpec, grid: dict[tuple[int, int], int],
               nxb: int, nyb: int) -> list[int]:
    """The far field: the block rectangle minus the structured region, one recombined surface.

    The region has ``nxb`` x ``nyb`` cells with corner points ``grid``. Returns its outline.
    """
    ring = ([grid[(i, 0)] for i in range(nxb)] + [grid[(nxb, j)] for j in range(nyb)]
            + [grid[(i, nyb)] for i in range(nxb, 0, -1)]
            + [grid[(0, j)] for j in range(nyb, 0, -1)])  # counter-clockwise
    outline = [pv.line(ring[k], ring[(k + 1) % len(ring)]) for k in range(len(ring))]
    b = spec.block
    bx, by = b.size_x / 2, b.size_y / 2
    bc = [pv.point(-bx, -by), pv.point(bx, -by), pv.point(bx, by), pv.point(-bx, by)]
    blines = [pv.line(bc[k], bc[(k + 1) % 4]) for k in range(4)]
    for k, ln in enumerate(blines):
        n = max(2, math.ceil((b.size_x if k % 2 == 0 else b.size_y) / spec.sizing.h_far - 1e-9))
        gmsh.model.geo.mesh.setTransfiniteCurve(abs(ln), n + 1)
    outer = gmsh.model.geo.addCurveLoop(blines, reorient=True)
    inner = gmsh.model.geo.addCurveLoop(outline, reorient=True)
    far = gmsh.model.geo.addPlaneSurface([outer, inner])
    gmsh.model.geo.mesh.setRecombine(2, far)
    pv.surfaces.append(PlanSurface(far, 4 + len(outline), None, False))
    return outline


def build_plan(spec: GeometrySpec) -> tuple[list[PlanSurface], list[int]]:
    """Create the plan-view surfaces at z = 0 in the current gmsh model.

    Returns the surfaces (the far field last) and the curves of the structured region's outline.
    """
    b = spec.block
    pv = PlanView(max(b.size_x, b.size_y))
    xb, yb, cell_pile = cell_grid(spec)
    n_circ = circumferential_divisions(spec)
    grid = {(i, j): pv.point(xb[i], yb[j]) for i in range(len(xb)) for j in range(len(yb))}
    for ix in range(len(xb) - 1):
        for iy in range(len(yb) - 1):
            g = [grid[(ix + 1, iy + 1)], grid[(ix, iy + 1)], grid[(ix, iy)], grid[(ix + 1, iy)]]
            sides = [pv.line(g[k], g[(k + 1) % 4]) for k in range(4)]
            for s in sides:
                pv.edges(s, n_circ // 4)
            if (ix, iy) in cell_pile:
                pile_cell(pv, spec, cell_pile[(ix, iy)], g, sides, n_circ)
            else:
                pv.block(sides, g, None)
    pv.set_transfinite()
    outline = _far_field(pv, spec, grid, len(xb) - 1, len(yb) - 1)
    return pv.surfaces, [abs(t) for t in outline]


def outline_edge(spec: GeometrySpec) -> float:
    """Mean edge size (m) of the structured region's outline."""
    x0, x1, y0, y1 = spec.structured_region()
    nq = circumferential_divisions(spec) // 4
    nx = len({round(p.x, 9) for p in spec.piles})
    ny = len({round(p.y, 9) for p in spec.piles})
    return 0.5 * ((x1 - x0) / (nx * nq) + (y1 - y0) / (ny * nq))


def set_far_field_size(spec: GeometrySpec, outline: list[int]) -> None:
    """Background mesh size: the outline edge size growing by ``growth`` up to ``h_far``."""
    sz = spec.sizing
    fld = gmsh.model.mesh.field
    f_dist = fld.add("Distance")
    fld.setNumbers(f_dist, "CurvesList", outline)
    fld.setNumber(f_dist, "Sampling", 20)
    f_math = fld.add("MathEval")
    edge = outline_edge(spec)
    fld.setString(f_math, "F", f"Min({sz.h_far}, {edge} + {sz.growth - 1.0}*F{f_dist})")
    fld.setAsBackgroundMesh(f_math)


def mesh_plan(far: int, growth: float) -> tuple[int, float]:
    """Mesh all surfaces with the far-field algorithm giving the best all-quad plan.

    ``far`` is the far-field surface, ``growth`` the sizing's (named in the error). Returns
    (algorithm, far-field minimum scaled Jacobian). Raises
    :class:`~pilegroup.errors.ScenarioError` naming ``numerics.mesh.growth`` when no algorithm
    recombines the far field into quads: the sizing is one this mesher cannot build (exit 2),
    which the user fixes by changing it.
    """
    best: tuple[float, int] | None = None
    for alg in FAR_FIELD_ALGORITHMS:
        gmsh.model.mesh.clear()
        gmsh.model.mesh.setAlgorithm(2, far, alg)
        try:
            gmsh.model.mesh.generate(2)
        except Exception:  # noqa: BLE001 - an algorithm may refuse a surface; try the next
            continue
        types, tags, _ = gmsh.model.mesh.getElements(2, far)
        if any(t != 3 for t in types):  # 3 = 4-node quadrangle
            continue
        q = float(np.min(gmsh.model.mesh.getElementQualities(np.concatenate(tags), "minSJ")))
        if best is None or q > best[0]:
            best = (q, alg)
        if q >= 0.35:
            break
    if best is None:
        raise ScenarioError("numerics.mesh.growth", growth,
                            "the far field cannot be meshed with quads at this sizing (every "
                            f"gmsh algorithm {FAR_FIELD_ALGORITHMS} left triangles): change "
                            "numerics.mesh.growth, far_field_size_m or size_m", "-")
    if best[1] != alg:
        gmsh.model.mesh.clear()
        gmsh.model.mesh.setAlgorithm(2, far, best[1])
        gmsh.model.mesh.generate(2)
    return best[1], best[0]
