"""gmsh builder: cap, piles and layered soil block as an all-hexahedral, tagged mesh.

Construction (gmsh built-in "geo" kernel, lengths in m):

1. **Plan view (z = 0), all quadrilaterals.** The structured region (the cap outline, or the
   pile circles' bounding box plus ``near_field_margin`` without a cap) is cut into a
   rectilinear grid of cells, one per pile, with cell edges half-way between pile rows and
   columns. Each pile cell is an o-grid: inside the pile an inner square plus four curved
   blocks, outside it four blocks from the circle to the cell sides; every block is transfinite,
   so pile cross-sections are structured. ``N = max(n_circ_min, 4 ceil(pi d / (4 h)))`` edges
   run around each circle and ``N / 4`` along every cell side; the radial edges next to the
   pile start at ``h`` and grow geometrically towards the cell side. Outside the structured
   region the plan is meshed unstructured (Frontal-Delaunay for quads + Blossom recombination),
   sized by the distance to the region outline, growing by ``growth`` up to ``h_far``.
2. **Extrusion.** The whole plan is extruded down through every layer boundary, the pile toes
   and the bottom; the structured region is extruded up through the pile tops and the cap top.
   Each slab carries graded element heights (``vertical.py``) and ``recombine=True`` so quads
   become hexahedra. Node sharing at every slab and block interface makes the mesh conforming.

Physical groups (names as ``dolfinx.io.gmsh.model_to_mesh`` returns them; tag values fixed):

====================  =====  ===========  ==============================================
name                  dim    tag          what
====================  =====  ===========  ==============================================
soil_layer_{jj:02d}   3      jj           soil of layer jj (1-based, top down)
pile_{i}              3      100 + i      pile i (1-based, spec order), incl. embedded part
cap                   3      300          the cap (minus the embedded pile heads)
side_xmin/xmax        2      1 / 2        block sides x = -size_x/2, +size_x/2
side_ymin/ymax        2      3 / 4        block sides y = -size_y/2, +size_y/2
bottom                2      5            z = -depth
ground_surface        2      6            soil top (z = 0) not under the cap or a pile
cap_bottom            2      7            cap bottom facets touching soil (z = 0)
cap_top               2      8            cap top, z = cap thickness
cap_side              2      9            cap vertical sides
base_p{i}             2      100 + i      pile toe facets (pile / soil), z = -L_i
head_p{i}             2      400 + i      pile head on the ground (only without a cap)
embed_p{i}            2      700 + i      pile / cap facets (embedded part: sides and top)
shaft_p{i}_l{jj:02d}  2      1000 i + jj  pile i shaft in layer jj (pile / soil facets)
====================  =====  ===========  ==============================================

Shaft groups exist only for the layers a pile reaches (Pier 667: toe at 63.5 m in layer 9, so
9 x 9 = 81 shaft groups). Interior facets between two soil cells, two pile cells or two cap
cells carry no tag.
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from pilegroup.geometry.spec import GeometrySpec
from pilegroup.geometry.vertical import Segment, vertical_segments

__all__ = [
    "FACET_TAGS",
    "BuildResult",
    "build_gmsh_model",
    "cell_tag_of_layer",
    "cell_tag_of_pile",
    "circumferential_divisions",
]

CAP_TAG = 300
#: gmsh options the builder sets (single thread: the machines are shared).
GMSH_OPTIONS = {
    "General.NumThreads": 1,
    "Mesh.RecombinationAlgorithm": 1,
    "Mesh.MeshSizeExtendFromBoundary": 0,
    "Mesh.MeshSizeFromPoints": 0,
    "Mesh.MeshSizeFromCurvature": 0,
    "Mesh.ElementOrder": 1,
    # duplicates of the extruded entities are removed once, after all extrusions (much faster
    # than after every extrusion)
    "Geometry.AutoCoherence": 0,
}
FACET_TAGS = {"side_xmin": 1, "side_xmax": 2, "side_ymin": 3, "side_ymax": 4, "bottom": 5,
              "ground_surface": 6, "cap_bottom": 7, "cap_top": 8, "cap_side": 9}


def cell_tag_of_layer(j: int) -> int:
    """Cell tag of soil layer ``j`` (1-based)."""
    return j


def cell_tag_of_pile(i: int) -> int:
    """Cell tag of pile ``i`` (1-based)."""
    return 100 + i


def circumferential_divisions(spec: GeometrySpec) -> int:
    """Number of element edges around every pile circle (multiple of 4)."""
    d = max(p.diameter for p in spec.piles)
    h = spec.sizing.h_pile
    return max(spec.sizing.n_circ_min, 4 * math.ceil(math.pi * d / (4.0 * h) - 1e-9))


@dataclass
class BuildResult:
    """What :func:`build_gmsh_model` made (the mesh itself stays in the gmsh model).

    Attributes:
        cell_groups / facet_groups: physical name -> tag.
        n_hex: number of hexahedra; n_nodes: number of mesh nodes.
        min_sj: minimum scaled Jacobian over all hexahedra (gmsh "minSJ", -).
        n_plan_quads: quadrilaterals of the plan view (z = 0, soil side).
        n_vertical_soil / n_vertical_cap: element layers in the soil column / cap.
        timings: seconds for geometry, meshing, quality evaluation.
    """

    cell_groups: dict[str, int]
    facet_groups: dict[str, int]
    n_hex: int = 0
    n_nodes: int = 0
    min_sj: float = float("nan")
    n_plan_quads: int = 0
    n_circ: int = 0
    n_vertical_soil: int = 0
    n_vertical_cap: int = 0
    far_field_algorithm: int = 0
    far_field_min_sj: float = float("nan")
    timings: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return dict(self.__dict__)


# ------------------------------------------------------------------------------------------------
# plan view
# ------------------------------------------------------------------------------------------------
def _progression(length: float, first: float, last: float) -> tuple[int, float]:
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


class _Plan:
    """Points/curves registry for the plan view in the geo kernel (shares coincident ones)."""

    def __init__(self, geo: Any, scale: float) -> None:
        self.geo = geo
        self.scale = scale
        self.points: dict[tuple[int, int], int] = {}
        self.lines: dict[tuple[int, int], int] = {}
        self.coords: dict[int, tuple[float, float]] = {}

    def point(self, x: float, y: float) -> int:
        key = (round(x / self.scale * 1e9), round(y / self.scale * 1e9))
        if key not in self.points:
            self.points[key] = self.geo.addPoint(x, y, 0.0)
            self.coords[self.points[key]] = (x, y)
        return self.points[key]

    def line(self, p: int, q: int) -> int:
        if (p, q) in self.lines:
            return self.lines[(p, q)]
        if (q, p) in self.lines:
            return -self.lines[(q, p)]
        tag = self.geo.addLine(p, q)
        self.lines[(p, q)] = tag
        return tag

    def arc(self, p: int, centre: int, q: int) -> int:
        tag = self.geo.addCircleArc(p, centre, q)
        self.lines[(p, q)] = tag
        return tag

    def length(self, p: int, q: int) -> float:
        (x0, y0), (x1, y1) = self.coords[p], self.coords[q]
        return math.hypot(x1 - x0, y1 - y0)


@dataclass
class _PlanSurface:
    tag: int
    n_curves: int
    role: tuple[str, int]  # ("pile", i) or ("soil", 0); soil in the structured region or not
    in_region: bool


def _build_plan(spec: GeometrySpec, geo: Any) -> tuple[list[_PlanSurface], list[int]]:
    """Create the plan-view surfaces at z = 0; return them and the region-outline curves."""
    sz = spec.sizing
    b = spec.block
    pl = _Plan(geo, max(b.size_x, b.size_y))
    x0, x1, y0, y1 = spec.structured_region()
    n_circ = circumferential_divisions(spec)
    nq = n_circ // 4

    # rectilinear cells: breaks half-way between distinct pile x (y) positions
    def breaks(vals: list[float], lo: float, hi: float) -> list[float]:
        u = sorted(set(round(v, 9) for v in vals))
        return [lo, *((a + c) / 2 for a, c in zip(u[:-1], u[1:], strict=True)), hi]

    xb = breaks([p.x for p in spec.piles], x0, x1)
    yb = breaks([p.y for p in spec.piles], y0, y1)
    cell_pile: dict[tuple[int, int], int] = {}
    for i, p in enumerate(spec.piles):
        ix = int(np.searchsorted(xb, p.x)) - 1
        iy = int(np.searchsorted(yb, p.y)) - 1
        if (ix, iy) in cell_pile:
            raise ValueError(f"piles {cell_pile[(ix, iy)] + 1} and {i + 1} fall into the same "
                             "structured cell: pile positions must form a rectilinear grid")
        cx0, cx1, cy0, cy1 = xb[ix], xb[ix + 1], yb[iy], yb[iy + 1]
        clear = min(p.x - cx0, cx1 - p.x, p.y - cy0, cy1 - p.y) - p.radius
        if clear < 0.2 * p.radius:
            raise ValueError(f"pile {i + 1} at ({p.x:g}, {p.y:g}) m leaves only {clear:.3g} m "
                             "to its structured cell edge: piles too close to each other or to "
                             "the cap edge (need >= 0.2 x radius)")
        cell_pile[(ix, iy)] = i

    grid = {(i, j): pl.point(xb[i], yb[j]) for i in range(len(xb)) for j in range(len(yb))}
    surfaces: list[_PlanSurface] = []
    transfinite_lines: dict[int, tuple[int, float]] = {}

    def tl(tag: int, n_edges: int, coef: float = 1.0) -> None:
        transfinite_lines[abs(tag)] = (n_edges, coef)

    def add_surface(curves: list[int], corners: list[int], role: tuple[str, int]) -> None:
        loop = geo.addCurveLoop(curves, reorient=True)
        s = geo.addPlaneSurface([loop])
        geo.mesh.setTransfiniteSurface(s, "Left", corners)
        geo.mesh.setRecombine(2, s)
        surfaces.append(_PlanSurface(s, len(curves), role, True))

    for ix in range(len(xb) - 1):
        for iy in range(len(yb) - 1):
            g = [grid[(ix + 1, iy + 1)], grid[(ix, iy + 1)], grid[(ix, iy)], grid[(ix + 1, iy)]]
            sides = [pl.line(g[k], g[(k + 1) % 4]) for k in range(4)]
            for s_ in sides:
                tl(s_, nq)
            if (ix, iy) not in cell_pile:
                add_surface(sides, g, ("soil", 0))
                continue
            i = cell_pile[(ix, iy)]
            p = spec.piles[i]
            r = p.radius
            c = pl.point(p.x, p.y)
            ang = [math.pi / 4 + k * math.pi / 2 for k in range(4)]
            q = [pl.point(p.x + r * math.cos(a), p.y + r * math.sin(a)) for a in ang]
            rho = 0.6 * r
            sq = [pl.point(p.x + rho * math.cos(a), p.y + rho * math.sin(a)) for a in ang]
            arcs = [pl.arc(q[k], c, q[(k + 1) % 4]) for k in range(4)]
            sq_sides = [pl.line(sq[k], sq[(k + 1) % 4]) for k in range(4)]
            spokes = [pl.line(sq[k], q[k]) for k in range(4)]
            diags = [pl.line(q[k], g[k]) for k in range(4)]
            arc_len = 2 * math.pi * r / n_circ
            m_in = max(2, round(0.45 * r / arc_len))
            for k in range(4):
                tl(arcs[k], nq)
                tl(sq_sides[k], nq)
                tl(spokes[k], m_in)
            # radial edges outside the pile: start at h, grow towards the cell-side spacing
            side_h = min(pl.length(g[k], g[(k + 1) % 4]) for k in range(4)) / nq
            dlen = [pl.length(q[k], g[k]) for k in range(4)]
            m_out, coef = _progression(float(np.mean(dlen)), sz.h_pile, max(side_h, sz.h_pile))
            for k in range(4):
                tl(diags[k], m_out, coef)
            # pile: inner square + 4 blocks
            add_surface(sq_sides, sq, ("pile", i + 1))
            for k in range(4):
                k1 = (k + 1) % 4
                add_surface([sq_sides[k], spokes[k1], -arcs[k], -spokes[k]],
                            [sq[k], sq[k1], q[k1], q[k]], ("pile", i + 1))
            # soil: 4 blocks between the circle and the cell sides
            for k in range(4):
                k1 = (k + 1) % 4
                add_surface([arcs[k], diags[k1], -sides[k], -diags[k]],
                            [q[k], q[k1], g[k1], g[k]], ("soil", 0))

    for tag, (n, coef) in transfinite_lines.items():
        geo.mesh.setTransfiniteCurve(tag, n + 1, "Progression", coef)

    # outline of the structured region (counter-clockwise)
    nxb, nyb = len(xb) - 1, len(yb) - 1
    ring = ([grid[(i, 0)] for i in range(nxb)] + [grid[(nxb, j)] for j in range(nyb)]
            + [grid[(i, nyb)] for i in range(nxb, 0, -1)]
            + [grid[(0, j)] for j in range(nyb, 0, -1)])
    outline = [pl.line(ring[k], ring[(k + 1) % len(ring)]) for k in range(len(ring))]

    # far field: block rectangle minus the structured region
    bx, by = b.size_x / 2, b.size_y / 2
    bc = [pl.point(-bx, -by), pl.point(bx, -by), pl.point(bx, by), pl.point(-bx, by)]
    blines = [pl.line(bc[k], bc[(k + 1) % 4]) for k in range(4)]
    for k, ln in enumerate(blines):
        n = max(2, math.ceil((b.size_x if k % 2 == 0 else b.size_y) / sz.h_far - 1e-9))
        geo.mesh.setTransfiniteCurve(abs(ln), n + 1)
    outer = geo.addCurveLoop(blines, reorient=True)
    inner = geo.addCurveLoop(outline, reorient=True)
    far = geo.addPlaneSurface([outer, inner])
    geo.mesh.setRecombine(2, far)
    surfaces.append(_PlanSurface(far, 4 + len(outline), ("soil", 0), False))
    return surfaces, [abs(t) for t in outline]


def _far_field_size(spec: GeometrySpec, outline: list[int], gmsh: Any) -> None:
    sz = spec.sizing
    fld = gmsh.model.mesh.field
    f_dist = fld.add("Distance")
    fld.setNumbers(f_dist, "CurvesList", outline)
    fld.setNumber(f_dist, "Sampling", 20)
    f_math = fld.add("MathEval")
    edge = _outline_edge(spec)
    fld.setString(f_math, "F", f"Min({sz.h_far}, {edge} + {sz.growth - 1.0}*F{f_dist})")
    fld.setAsBackgroundMesh(f_math)


def _outline_edge(spec: GeometrySpec) -> float:
    """Mean edge size (m) of the structured region's outline."""
    x0, x1, y0, y1 = spec.structured_region()
    nq = circumferential_divisions(spec) // 4
    nx = len({round(p.x, 9) for p in spec.piles})
    ny = len({round(p.y, 9) for p in spec.piles})
    return 0.5 * ((x1 - x0) / (nx * nq) + (y1 - y0) / (ny * nq))


# ------------------------------------------------------------------------------------------------
# extrusion, groups
# ------------------------------------------------------------------------------------------------
def _extrude(geo: Any, surfaces: list[_PlanSurface], seg: Segment,
             vol_role: dict[int, tuple[str, int]], role_of: Any) -> list[_PlanSurface]:
    dz = seg.z_end - seg.z_start
    out = geo.extrude([(2, s.tag) for s in surfaces], 0.0, 0.0, dz,
                      numElements=[1] * seg.n, heights=list(seg.heights), recombine=True)
    tops: list[_PlanSurface] = []
    k = 0
    for s in surfaces:
        top, vol = out[k], out[k + 1]
        if top[0] != 2 or vol[0] != 3:
            raise RuntimeError("unexpected gmsh extrude output layout")
        vol_role[vol[1]] = role_of(s, seg)
        tops.append(_PlanSurface(top[1], s.n_curves, s.role, s.in_region))
        k += 2 + s.n_curves
    if k != len(out):
        raise RuntimeError(f"gmsh extrude returned {len(out)} entities, expected {k}")
    return tops


def build_gmsh_model(spec: GeometrySpec, name: str = "pilegroup") -> BuildResult:
    """Build geometry, mesh and physical groups of ``spec`` in a new gmsh model ``name``.

    gmsh must be initialised by the caller; the model stays current so that it can be written or
    converted. Lengths in m. Raises ``RuntimeError`` if anything but hexahedra is produced.
    """
    import gmsh

    t0 = time.perf_counter()
    for key, val in GMSH_OPTIONS.items():
        gmsh.option.setNumber(key, val)
    gmsh.model.add(name)
    geo = gmsh.model.geo
    surfaces, outline = _build_plan(spec, geo)
    soil_segs, cap_segs = vertical_segments(spec)
    vol_role: dict[int, tuple[str, int]] = {}

    def soil_role(s: _PlanSurface, seg: Segment) -> tuple[str, int]:
        if s.role[0] == "pile":
            p = spec.piles[s.role[1] - 1]
            if seg.z_end >= -p.length_in_soil - 1e-9 * spec.block.depth:
                return s.role
        return ("soil", seg.layer)

    current = surfaces
    for seg in soil_segs:
        current = _extrude(geo, current, seg, vol_role, soil_role)

    def cap_role(s: _PlanSurface, seg: Segment) -> tuple[str, int]:
        if s.role[0] == "pile":
            p = spec.piles[s.role[1] - 1]
            if seg.z_end <= p.embedment + 1e-9 * spec.cap.thickness:  # type: ignore[union-attr]
                return s.role
        return ("cap", 0)

    current = [s for s in surfaces if s.in_region]
    for seg in cap_segs:
        current = _extrude(geo, current, seg, vol_role, cap_role)
    geo.removeAllDuplicates()
    geo.synchronize()
    _far_field_size(spec, outline, gmsh)
    cell_groups, facet_groups = _physical_groups(spec, vol_role, gmsh)
    t1 = time.perf_counter()

    res = BuildResult(cell_groups, facet_groups)
    res.far_field_algorithm, res.far_field_min_sj = _mesh_plan(gmsh, surfaces[-1].tag)
    gmsh.model.mesh.generate(3)
    t2 = time.perf_counter()
    res.n_circ = circumferential_divisions(spec)
    res.n_vertical_soil = sum(s.n for s in soil_segs)
    res.n_vertical_cap = sum(s.n for s in cap_segs)
    etypes, etags, _ = gmsh.model.mesh.getElements(3)
    bad = [gmsh.model.mesh.getElementProperties(t)[0] for t in etypes if t != 5]
    if bad:
        counts = {gmsh.model.mesh.getElementProperties(t)[0]: len(e)
                  for t, e in zip(etypes, etags, strict=True)}
        raise RuntimeError(f"mesh is not all-hexahedral: {counts}")
    hexes = np.concatenate(etags) if len(etags) else np.zeros(0, dtype=np.uint64)
    res.n_hex = int(hexes.size)
    res.n_nodes = int(gmsh.model.mesh.getNodes()[0].size)
    q = gmsh.model.mesh.getElementQualities(hexes, "minSJ")
    res.min_sj = float(np.min(q))
    res.n_plan_quads = sum(len(t) for s in surfaces
                           for t in gmsh.model.mesh.getElements(2, s.tag)[1])
    t3 = time.perf_counter()
    res.timings = {"geometry_s": t1 - t0, "mesh_s": t2 - t1, "quality_s": t3 - t2}
    return res


#: gmsh 2D algorithms tried for the far field (6 Frontal-Delaunay, 5 Delaunay, 8 Frontal-Delaunay
#: for quads), all with Blossom recombination.
FAR_FIELD_ALGORITHMS = (6, 5, 8)


def _mesh_plan(gmsh: Any, far: int) -> tuple[int, float]:
    """Mesh all surfaces with the far-field algorithm giving the best all-quad plan.

    Returns (algorithm, far-field minimum scaled Jacobian).
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
        raise RuntimeError("far-field recombination left triangles with every algorithm "
                           f"{FAR_FIELD_ALGORITHMS}; change sizing.growth or h_far")
    if best[1] != alg:
        gmsh.model.mesh.clear()
        gmsh.model.mesh.setAlgorithm(2, far, best[1])
        gmsh.model.mesh.generate(2)
    return best[1], best[0]


def _physical_groups(spec: GeometrySpec, vol_role: dict[int, tuple[str, int]],
                     gmsh: Any) -> tuple[dict[str, int], dict[str, int]]:
    b = spec.block
    tol = 1e-7 * max(b.size_x, b.size_y, b.depth)
    face_vols: dict[int, list[int]] = {}
    for v in vol_role:
        for _, f in gmsh.model.getBoundary([(3, v)], combined=False, oriented=False):
            face_vols.setdefault(abs(f), []).append(v)

    groups: dict[str, list[int]] = {}
    tags: dict[str, int] = {}

    def put(name: str, tag: int, face: int) -> None:
        groups.setdefault(name, []).append(face)
        tags[name] = tag

    for f, vols in face_vols.items():
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(2, f)
        vertical = zmax - zmin > tol
        roles = sorted({vol_role[v] for v in vols})
        if len(vols) > 2:
            raise RuntimeError(f"surface {f} bounds {len(vols)} volumes")
        if len(vols) == 2:
            kinds = {r[0] for r in roles}
            if kinds == {"pile", "soil"}:
                i = next(r[1] for r in roles if r[0] == "pile")
                j = next(r[1] for r in roles if r[0] == "soil")
                if vertical:
                    put(f"shaft_p{i}_l{j:02d}", 1000 * i + j, f)
                else:
                    put(f"base_p{i}", 100 + i, f)
            elif kinds == {"cap", "soil"}:
                put("cap_bottom", FACET_TAGS["cap_bottom"], f)
            elif kinds == {"pile", "cap"}:
                i = next(r[1] for r in roles if r[0] == "pile")
                put(f"embed_p{i}", 700 + i, f)
            continue
        (kind, idx), = roles
        if vertical:
            if kind == "cap":
                put("cap_side", FACET_TAGS["cap_side"], f)
            elif abs(xmax + b.size_x / 2) < tol:
                put("side_xmin", FACET_TAGS["side_xmin"], f)
            elif abs(xmin - b.size_x / 2) < tol:
                put("side_xmax", FACET_TAGS["side_xmax"], f)
            elif abs(ymax + b.size_y / 2) < tol:
                put("side_ymin", FACET_TAGS["side_ymin"], f)
            elif abs(ymin - b.size_y / 2) < tol:
                put("side_ymax", FACET_TAGS["side_ymax"], f)
            else:
                raise RuntimeError(f"unclassified vertical boundary surface {f} ({kind})")
        elif abs(zmin + b.depth) < tol:
            put("bottom", FACET_TAGS["bottom"], f)
        elif kind == "cap":
            put("cap_top", FACET_TAGS["cap_top"], f)
        elif abs(zmax) < tol and kind == "soil":
            put("ground_surface", FACET_TAGS["ground_surface"], f)
        elif abs(zmax) < tol and kind == "pile":
            put(f"head_p{idx}", 400 + idx, f)
        else:
            raise RuntimeError(f"unclassified horizontal boundary surface {f} ({kind}, z={zmax})")

    cell_vols: dict[str, list[int]] = {}
    cell_tags: dict[str, int] = {}
    for v, (kind, idx) in vol_role.items():
        if kind == "soil":
            nm, tg = f"soil_layer_{idx:02d}", cell_tag_of_layer(idx)
        elif kind == "pile":
            nm, tg = f"pile_{idx}", cell_tag_of_pile(idx)
        else:
            nm, tg = "cap", CAP_TAG
        cell_vols.setdefault(nm, []).append(v)
        cell_tags[nm] = tg
    for nm in sorted(cell_vols, key=lambda n: cell_tags[n]):
        gmsh.model.addPhysicalGroup(3, sorted(cell_vols[nm]), cell_tags[nm], nm)
    for nm in sorted(groups, key=lambda n: tags[n]):
        gmsh.model.addPhysicalGroup(2, sorted(groups[nm]), tags[nm], nm)
    return cell_tags, tags
