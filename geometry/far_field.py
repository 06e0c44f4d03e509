"""The plan of a model: one part's structured cells and far field, and the part's mirror images.

The *part* is what the geometry's mirror symmetry leaves: x >= 0 when the layout is symmetric
about x = 0, y >= 0 when about y = 0 (:meth:`GeometrySpec.symmetry_planes
<pilegroup.geometry.spec.GeometrySpec.symmetry_planes>`), the whole plan otherwise. Every model
of a geometry is that part plus its mirror images about the planes the model does not cut at
(:func:`mirror_signs`): the quarter model of a doubly symmetric layout is the part, the half
model the part and one image, the whole model four. So a reduced model's mesh is exactly the
restriction of the whole model's mesh: the same nodes and cells on its side of the planes.

The far field (the part of the block outside the structured region) is meshed once per build,
in a separate gmsh model, by :func:`far_field`:

* its boundary is made of single-edge lines: the structured outline's curves split at their
  nodes, the planes from the structured region out to the block sides (edges growing
  geometrically from the outline's edge size towards ``h_far``, ratio <= 1.35) and the block
  sides (``h_far``), one edge added to the longest side when the total is odd;
* it is meshed unstructured, sized ``edge + (growth - 1) * distance`` up to ``h_far`` around
  the outline, with each of :data:`FAR_FIELD_ALGORITHMS` and Blossom recombination;
  recombination may leave pairs of triangles, which :func:`~pilegroup.geometry.quadfix.
  all_quads` turns into quadrilaterals; the all-quad mesh with the best minimum scaled
  Jacobian is kept;
* when no algorithm gives one, the block sides are split instead at the size the grading
  reaches at their distance from the structured region (at most ``h_far``) and the algorithms
  are tried again. Sides split far coarser than the grading asks there can leave gmsh a
  boundary it fills badly: an 8 x 2 group of mixed piles in a 96 m x 76 m block (two 48 m
  edges a side where the grading reaches 19 m) got a Delaunay mesh with a triangle turned
  over by the smoothing, and frontal meshes without a node inside (fans of 132 triangles).

:func:`build_plan` then records each image of the part in a
:class:`~pilegroup.geometry.plan.PlanView`: the structured cells, the outline split into the
same single-edge lines, and the far field as one surface with the far-field mesh's nodes and
interior edges embedded (gmsh then recombines exactly those quadrilaterals, checked after
meshing). Every image gets the same nodes, mirrored, and nothing is left to a random choice.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import gmsh
import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.geometry.plan import (
    Embedded,
    PlanSurface,
    PlanView,
    circumferential_divisions,
    outline_edge,
    progression,
)
from pilegroup.geometry.plan_cells import outline, structured_cells
from pilegroup.geometry.quadfix import all_quads, edge_ratio, element_quality
from pilegroup.geometry.spec import GeometrySpec
from pilegroup.geometry.symmetry import find_pile

__all__ = ["FAR_FIELD_ALGORITHMS", "EmittedPlan", "FarField", "build_plan", "far_field",
           "mirror_signs"]

#: gmsh 2D algorithms tried for the far field (5 Delaunay, 6 Frontal-Delaunay, 8
#: Frontal-Delaunay for quads), all with Blossom recombination.
FAR_FIELD_ALGORITHMS = (5, 6, 8)
#: A far-field mesh with a quadrilateral whose shortest edge is below this fraction of its
#: longest is not used (two nodes all but coincide: gmsh would merge them).
MIN_EDGE_RATIO = 1e-3

Segment = tuple[int, int]


@dataclass(frozen=True)
class FarField:
    """The all-quadrilateral far-field mesh of the part (part coordinates, m).

    Attributes:
        xy: node coordinates (n, 2); the boundary nodes are the part's outline, plane and side
            nodes exactly.
        quads: node indices (m, 4), counter-clockwise.
        algorithm: the gmsh 2D algorithm of the kept mesh.
        min_sj: its minimum scaled Jacobian (-).
        pairs: pairs of leftover triangles joined into quadrilaterals.
    """

    xy: np.ndarray
    quads: np.ndarray
    algorithm: int
    min_sj: float
    pairs: int


def mirror_signs(spec: GeometrySpec) -> list[tuple[float, float]]:
    """Signs (x, y) of the part's images that make up the model (the part itself first)."""
    part, cut = spec.symmetry_planes(), spec.cut_planes()
    sx = (1.0, -1.0) if "x" in part and "x" not in cut else (1.0,)
    sy = (1.0, -1.0) if "y" in part and "y" not in cut else (1.0,)
    return [(a, b) for b in sy for a in sx]


def _chain(pv: PlanView, a: tuple[float, float], b: tuple[float, float],
           fractions: Sequence[float]) -> list[Segment]:
    """Single-edge segments from ``a`` to ``b`` through the nodes at ``fractions`` of the way."""
    pts = [pv.point(a[0] + f * (b[0] - a[0]), a[1] + f * (b[1] - a[1])) for f in fractions]
    return list(zip(pts[:-1], pts[1:], strict=True))


def _boundary(pv: PlanView, spec: GeometrySpec, planes: Sequence[str],
              curves: list[int], graded: bool = False) -> list[Segment]:
    """The far field's boundary segments: outline ``curves`` (split), planes, block sides.

    The block sides are split at ``h_far``, or (``graded``) at the size the grading reaches
    at each side's distance from the structured region (at most ``h_far``).
    """
    segs = [(pv.curves[t].p, pv.curves[t].q) for c in curves for t in pv.split(c)]
    bx, by = spec.block.size_x / 2, spec.block.size_y / 2
    bx0, by0 = (0.0 if "x" in planes else -bx), (0.0 if "y" in planes else -by)
    sx0, sx1, sy0, sy1 = spec.structured_region()
    sx0, sy0 = (0.0 if "x" in planes else sx0), (0.0 if "y" in planes else sy0)
    rays = []
    if "x" in planes:
        rays += [((0.0, sy1), (0.0, by))] + ([] if "y" in planes else [((0.0, sy0), (0.0, -by))])
    if "y" in planes:
        rays += [((sx1, 0.0), (bx, 0.0))] + ([] if "x" in planes else [((sx0, 0.0), (-bx, 0.0))])
    for a, b in rays:
        n, q = progression(math.dist(a, b), outline_edge(spec), spec.sizing.h_far)
        frac = ([k / n for k in range(n + 1)] if q == 1.0
                else [(q**k - 1.0) / (q**n - 1.0) for k in range(n + 1)])
        segs += _chain(pv, a, b, frac)
    corners = [(bx0, by0), (bx, by0), (bx, by), (bx0, by)]
    size = [spec.sizing.h_far] * 4
    if graded:  # each side's distance from the structured region (sides y-, x+, y+, x-)
        size = [min(spec.sizing.h_far, outline_edge(spec) + (spec.sizing.growth - 1.0) * gap)
                for gap in (by + sy0, bx - sx1, by - sy1, bx + sx0)]
    sides = [(corners[k], corners[(k + 1) % 4], size[k]) for k in range(4)
             if not ((k == 0 and "y" in planes) or (k == 3 and "x" in planes))]
    counts = [max(2, math.ceil(math.dist(a, b) / h - 1e-9)) for a, b, h in sides]
    if (len(segs) + sum(counts)) % 2:  # an odd boundary leaves a triangle in any quad mesh
        counts[max(range(len(sides)), key=lambda k: math.dist(*sides[k][:2]))] += 1
    for (a, b, _), n in zip(sides, counts, strict=True):
        segs += _chain(pv, a, b, [k / n for k in range(n + 1)])
    return segs


def _loops(segs: list[Segment]) -> list[list[int]]:
    """The boundary segments as closed loops of points."""
    links: dict[int, list[int]] = {}
    for p, q in segs:
        links.setdefault(p, []).append(q)
        links.setdefault(q, []).append(p)
    if any(len(v) != 2 for v in links.values()):
        raise RuntimeError("the far field's boundary is not made of closed loops")
    loops, seen = [], set()
    for start in links:
        if start in seen:
            continue
        loop, prev, at = [start], None, start
        while True:
            nxt = next(q for q in links[at] if q != prev) if prev is not None else links[at][0]
            if nxt == start:
                break
            loop.append(nxt)
            prev, at = at, nxt
        seen.update(loop)
        loops.append(loop)
    return loops


def _area(pv: PlanView, loop: list[int]) -> float:
    p = np.array([pv.coords[k] for k in loop])
    return 0.5 * float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _set_size(spec: GeometrySpec, curves: list[int]) -> None:
    """Background mesh size: the outline edge size growing by ``growth`` up to ``h_far``."""
    sz = spec.sizing
    fld = gmsh.model.mesh.field
    f_dist = fld.add("Distance")
    fld.setNumbers(f_dist, "CurvesList", curves)
    fld.setNumber(f_dist, "Sampling", 20)
    f_math = fld.add("MathEval")
    fld.setString(f_math, "F", f"Min({sz.h_far}, {outline_edge(spec)} + {sz.growth - 1.0}"
                  f"*F{f_dist})")
    fld.setAsBackgroundMesh(f_math)


def _surface(pv: PlanView, segs: list[Segment], n_outline: int) -> tuple[int, list[int]]:
    """The far-field surface in the current gmsh model; returns it and its outline curves."""
    geo = gmsh.model.geo
    pt = {p: geo.addPoint(*pv.coords[p], 0.0) for seg in segs for p in seg}
    tags = {}
    for p, q in segs:
        tags[(p, q)] = geo.addLine(pt[p], pt[q])
        geo.mesh.setTransfiniteCurve(tags[(p, q)], 2)
    loops = sorted(_loops(segs), key=lambda lp: -abs(_area(pv, lp)))  # outer loop first
    curve_loops = []
    for lp in loops:
        edges = zip(lp, [*lp[1:], lp[0]], strict=True)
        curve_loops.append(geo.addCurveLoop([tags[(p, q)] if (p, q) in tags else -tags[(q, p)]
                                             for p, q in edges], reorient=True))
    surface = geo.addPlaneSurface(curve_loops)
    geo.mesh.setRecombine(2, surface)
    geo.synchronize()
    return surface, [tags[s] for s in segs[:n_outline]]


def _quad_mesh(surface: int) -> tuple[np.ndarray, np.ndarray, int]:
    """The current mesh of ``surface`` made all-quadrilateral: (xy, quads, triangle pairs)."""
    tags, xyz, _ = gmsh.model.mesh.getNodes(2, surface, includeBoundary=True)
    index = {int(t): k for k, t in enumerate(tags)}
    elements = []
    for etype, n in ((2, 3), (3, 4)):
        _, nodes = gmsh.model.mesh.getElementsByType(etype, surface)
        elements += [[index[int(t)] for t in nodes[k:k + n]] for k in range(0, len(nodes), n)]
    return all_quads(xyz.reshape(-1, 3)[:, :2], elements)


def _mesh(pv: PlanView, spec: GeometrySpec, segs: list[Segment],
          n_outline: int) -> FarField | None:
    """Mesh the far field bounded by ``segs`` in a gmsh model of its own (then removed).

    The all-quadrilateral mesh of the algorithm with the best minimum scaled Jacobian, or None
    when no algorithm gives one.
    """
    gmsh.model.add("far_field")
    try:
        surface, curves = _surface(pv, segs, n_outline)
        _set_size(spec, curves)
        best: FarField | None = None
        for alg in FAR_FIELD_ALGORITHMS:
            gmsh.model.mesh.clear()
            gmsh.model.mesh.setAlgorithm(2, surface, alg)
            try:
                gmsh.model.mesh.generate(2)
                xy, quads, pairs = _quad_mesh(surface)
            except Exception:  # noqa: BLE001 - an algorithm may fail (QuadRepairError): next
                continue
            q = min(element_quality(xy, e) for e in quads)
            ratio = min(edge_ratio(xy, e) for e in quads)
            if q > 0.0 and ratio >= MIN_EDGE_RATIO and (best is None or q > best.min_sj):
                best = FarField(xy, quads, alg, q, pairs)
    finally:
        gmsh.model.remove()
    return best


def far_field(spec: GeometrySpec) -> FarField:
    """The all-quadrilateral far-field mesh of ``spec``'s part (see the module docstring).

    The block sides split at ``h_far`` first; when no algorithm gives convex quadrilaterals,
    split at the size the grading reaches there. Raises
    :class:`~pilegroup.errors.ScenarioError` naming ``numerics.mesh.growth`` when neither does.
    """
    planes = spec.symmetry_planes()
    for graded in (False, True):
        pv = PlanView(max(spec.block.size_x, spec.block.size_y))
        structured_cells(pv, spec, planes, circumferential_divisions(spec))
        curves = outline(pv, 0, planes)
        n_outline = sum(len(pv.split(c)) for c in curves)
        far = _mesh(pv, spec, _boundary(pv, spec, planes, curves, graded), n_outline)
        if far is not None:
            return far
    raise ScenarioError("numerics.mesh.growth", spec.sizing.growth,
                        "the far field cannot be meshed with convex quadrilaterals at this "
                        f"sizing (every gmsh algorithm {FAR_FIELD_ALGORITHMS} failed): change "
                        "numerics.mesh.growth, far_field_size_m or size_m", "-")


@dataclass
class EmittedPlan:
    """The plan view of a model in the current gmsh model.

    Attributes:
        surfaces: structured blocks (``in_region``) and one far-field surface per image.
        far: the part's far-field mesh (each far-field surface holds ``len(far.quads)``
            quadrilaterals).
        embedded: what to embed in the far-field surfaces once the gmsh model is synchronised
            (:meth:`embed`).
    """

    surfaces: list[PlanSurface]
    far: FarField
    embedded: list[Embedded]

    def embed(self) -> None:
        """Embed the far-field meshes' nodes and interior edges (after synchronising)."""
        for e in self.embedded:
            e.embed()

    def check(self) -> None:
        """Raise ``RuntimeError`` unless every far-field surface holds ``far``'s quadrilaterals.

        Their number, and nothing else (no triangle).
        """
        for e in self.embedded:
            types, tags, _ = gmsh.model.mesh.getElements(2, e.surface)
            counts = {int(t): len(k) for t, k in zip(types, tags, strict=True)}
            if counts != {3: len(self.far.quads)}:  # 3: 4-node quadrangle
                raise RuntimeError(f"far-field surface {e.surface} meshed as {counts} (gmsh "
                                   f"element type: count), not {len(self.far.quads)} quads")


def _record_far_field(pv: PlanView, far: FarField) -> None:
    """Record the far-field mesh ``far`` in ``pv`` as a free surface of single-edge lines."""
    pts = [pv.point(x, y) for x, y in far.xy]
    use = Counter(tuple(sorted((pts[a], pts[b]))) for quad in far.quads
                  for a, b in zip(quad, np.roll(quad, -1), strict=True))
    for p, q in use:
        pv.edges(pv.line(p, q), 1)
    boundary = [e for e, n in use.items() if n == 1]
    on_boundary = {p for e in boundary for p in e}
    loops = sorted(_loops(boundary), key=lambda lp: -abs(_area(pv, lp)))
    pv.free_surface(loops, [pv.line(*e) for e, n in use.items() if n == 2],
                    sorted({p for quad in far.quads for p in (pts[k] for k in quad)}
                           - on_boundary))


def build_plan(spec: GeometrySpec) -> EmittedPlan:
    """Create the plan-view surfaces of ``spec``'s model at z = 0 in the current gmsh model."""
    far = far_field(spec)
    planes = spec.symmetry_planes()
    n_circ = circumferential_divisions(spec)
    pv = PlanView(max(spec.block.size_x, spec.block.size_y))
    for sign in mirror_signs(spec):
        pv.sign = sign
        pv.pile_map = {i: find_pile(spec.piles, sign[0] * p.x, sign[1] * p.y) or i
                       for i, p in enumerate(spec.piles, start=1)}
        first = len(pv.blocks)
        structured_cells(pv, spec, planes, n_circ)
        for c in outline(pv, first, planes):
            pv.split(c)
        _record_far_field(pv, far)
    surfaces = pv.emit()
    return EmittedPlan(surfaces, far, pv.embedded)
