"""An all-quadrilateral plane mesh from a quad-dominant one: leftover triangles paired up.

gmsh's Blossom recombination turns a triangulation into quadrilaterals by a minimum-cost perfect
matching of neighbouring triangles. A perfect matching with convex quadrilaterals need not exist
(e.g. two triangles fanned at a node on a straight boundary can only form a quadrilateral with a
180 degree corner), so a recombined surface can keep a few triangles even when its boundary has
an even number of edges. Their number is then even, and each is paired with the nearest other
one along a shortest path of quadrilaterals (breadth first over shared edges) by refining the
path: a node is added at the middle of every edge the path crosses, which makes each of the two
triangles a quadrilateral and splits each quadrilateral on the path in two (the path enters and
leaves through opposite sides) or three around a new centre node (adjacent sides). The
boundary and the other elements are kept. The new nodes are placed by Laplace smoothing and a
pattern search for the best worst element *shape* (:func:`shape_quality`: the scaled Jacobian,
capped by the ratio of the shortest to the longest edge); of the nearest paths the first with a
good worst shape (:data:`GOOD`) is taken, else the best convex one.

The scaled Jacobian alone (the sine of the worst corner) cannot see an edge shrink: a new node
pushed onto a neighbour leaves a quadrilateral whose corners all stay near 90 degrees while
one of its edges is gone. Maximising it alone drove a node to 3e-7 m from a boundary node
(a 5 x 5 group of 1 m piles at 3 m under a 14 m cap, 28 edges around a pile): gmsh then merged
the two points and the mesh broke. The edge ratio in :func:`shape_quality` keeps every new node
away from its neighbours.

Pure numpy on plane coordinates; node ids index ``xy``.
"""

from __future__ import annotations

import math
from collections import deque
from collections.abc import Iterator, Sequence

import numpy as np

__all__ = ["QuadRepairError", "all_quads", "edge_ratio", "element_quality",
           "shape_quality"]

Element = tuple[int, ...]

#: A pairing path is taken at once when its new elements' worst shape reaches GOOD;
#: otherwise the best of the first TRIES paths (more if none of them is convex).
GOOD, TRIES = 0.3, 8
#: :func:`shape_quality` caps the scaled Jacobian at EDGE_WEIGHT x the edge ratio: a new
#: element's shortest edge is then kept at or above GOOD / EDGE_WEIGHT of its longest when
#: that is possible, and never shrinks towards zero.
EDGE_WEIGHT = 3.0


class QuadRepairError(RuntimeError):
    """No valid pairing of the leftover triangles was found."""


def element_quality(xy: np.ndarray, element: Sequence[int]) -> float:
    """Scaled Jacobian of a counter-clockwise polygon (-).

    The minimum over its corners of the sine of the corner angle: 1 for a square, <= 0 for a
    concave or inverted element.
    """
    pts = [(float(xy[k][0]), float(xy[k][1])) for k in element]
    worst = math.inf
    for k, (x, y) in enumerate(pts):
        ax, ay = pts[(k + 1) % len(pts)][0] - x, pts[(k + 1) % len(pts)][1] - y
        bx, by = pts[k - 1][0] - x, pts[k - 1][1] - y
        norm = math.hypot(ax, ay) * math.hypot(bx, by)
        worst = min(worst, (ax * by - ay * bx) / norm if norm > 0.0 else -1.0)
    return worst


def edge_ratio(xy: np.ndarray, element: Sequence[int]) -> float:
    """Shortest over longest edge of a polygon (-): 0 when two consecutive nodes coincide."""
    pts = [(float(xy[k][0]), float(xy[k][1])) for k in element]
    lengths = [math.dist(pts[k - 1], pts[k]) for k in range(len(pts))]
    longest = max(lengths)
    return min(lengths) / longest if longest > 0.0 else 0.0


def shape_quality(xy: np.ndarray, element: Sequence[int]) -> float:
    """The scaled Jacobian capped by :data:`EDGE_WEIGHT` x the edge ratio (-).

    <= 0 for a concave or inverted element, -> 0 as an edge shrinks to nothing (which the
    scaled Jacobian alone does not see).
    """
    return min(element_quality(xy, element), EDGE_WEIGHT * edge_ratio(xy, element))


def _area2(xy: np.ndarray, element: Sequence[int]) -> float:
    """Twice the signed area of a polygon (> 0 counter-clockwise)."""
    p = xy[list(element)]
    return float(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _ccw(xy: np.ndarray, element: Sequence[int]) -> Element:
    return tuple(int(n) for n in (element if _area2(xy, element) > 0 else element[::-1]))


def _edges(e: Element) -> Iterator[tuple[int, int]]:
    for k in range(len(e)):
        yield e[k], e[(k + 1) % len(e)]


def _key(a: int, b: int) -> tuple[int, int]:
    return (a, b) if a < b else (b, a)


class _Mesh:
    """Elements by id and the elements of every edge."""

    def __init__(self, xy: np.ndarray, elements: Sequence[Sequence[int]]) -> None:
        self.xy = xy
        self.elems: dict[int, Element] = {}
        self.by_edge: dict[tuple[int, int], set[int]] = {}
        self._next = 0
        for e in elements:
            self.add(_ccw(xy, e))

    def add(self, e: Element) -> None:
        self.elems[self._next] = e
        for a, b in _edges(e):
            self.by_edge.setdefault(_key(a, b), set()).add(self._next)
        self._next += 1

    def remove(self, k: int) -> None:
        for a, b in _edges(self.elems.pop(k)):
            self.by_edge[_key(a, b)].discard(k)

    def neighbours(self, k: int) -> Iterator[int]:
        for a, b in _edges(self.elems[k]):
            yield from (j for j in self.by_edge[_key(a, b)] if j != k)

    def boundary_nodes(self) -> set[int]:
        return {n for edge, ks in self.by_edge.items() if len(ks) == 1 for n in edge}


def _paths(m: _Mesh, start: int) -> Iterator[list[int]]:
    """Element paths from triangle ``start`` to another triangle, shortest first.

    Each runs through at least one quadrilateral; one per quadrilateral the other triangle is
    reached from.
    """
    prev: dict[int, int | None] = {start: None}
    queue = deque([start])
    while queue:
        k = queue.popleft()
        for j in m.neighbours(k):
            if len(m.elems[j]) == 4:
                if j not in prev:
                    prev[j] = k
                    queue.append(j)
            elif j != start and k != start:
                path, i = [j], k
                while i is not None:
                    path.append(i)
                    i = prev[i]
                yield path[::-1]


def _shared(a: Element, b: Element) -> tuple[int, int]:
    """The edge of ``a`` (as ``a`` runs it) that ``b`` shares."""
    inb = set(_edges(b))
    return next((u, v) for u, v in _edges(a) if (v, u) in inb)


def _insert(e: Element, edge: tuple[int, int], mid: int) -> Element:
    """Triangle ``e`` with node ``mid`` inserted on its ``edge``: a quadrilateral."""
    k = e.index(edge[0])
    return (*e[:k + 1], mid, *e[k + 1:])


def _split_quad(e: Element, ins: dict[tuple[int, int], int], centre: int) -> list[Element]:
    """Quadrilateral ``e`` split at the middle nodes ``ins`` of two of its edges.

    Opposite edges: two quadrilaterals; adjacent edges: three, around node ``centre``.
    """
    s = next(k for k in range(4) if (e[k], e[(k + 1) % 4]) in ins)
    q = [e[(s + t) % 4] for t in range(4)]
    a = ins[(q[0], q[1])]
    if (q[2], q[3]) in ins:
        b = ins[(q[2], q[3])]
        return [(q[0], a, b, q[3]), (a, q[1], q[2], b)]
    if (q[1], q[2]) in ins:
        b = ins[(q[1], q[2])]
        return [(a, q[1], b, centre), (q[0], a, centre, q[3]), (centre, b, q[2], q[3])]
    b = ins[(q[3], q[0])]  # the other edge ends where this one starts
    return [(b, q[0], a, centre), (q[3], b, centre, q[2]), (centre, a, q[1], q[2])]


def _refine(m: _Mesh, path: list[int]) -> tuple[float, list[Element], dict[int, np.ndarray]]:
    """New elements and nodes (id -> coordinates) refining ``path``, and their worst quality."""
    els = [m.elems[k] for k in path]
    n = len(m.xy)
    xy = {}
    ins: dict[tuple[int, int], int] = {}
    for i in range(len(path) - 1):
        u, v = _shared(els[i], els[i + 1])
        ins[(u, v)] = ins[(v, u)] = n + i
        xy[n + i] = 0.5 * (m.xy[u] + m.xy[v])
    new = [_insert(els[0], _shared(els[0], els[1]), n),
           _insert(els[-1], _shared(els[-1], els[-2]), n + len(path) - 2)]
    for e in els[1:-1]:
        centre = n + len(xy)
        edges = set(_edges(e))
        parts = _split_quad(e, {k: v for k, v in ins.items() if k in edges}, centre)
        if len(parts) == 3:
            xy[centre] = np.mean(m.xy[list(e)], axis=0)
        new += parts
    return _place(m.xy, new, xy), new, xy


def _place(base: np.ndarray, new: list[Element], xy: dict[int, np.ndarray]) -> float:
    """Place the new nodes ``xy`` (in place); the worst shape of ``new`` then.

    Laplace smoothing first, then each node moved by a pattern search (8 directions, shrinking
    steps) to raise the worst shape (:func:`shape_quality`) of the elements around it.
    """
    ring: dict[int, set[int]] = {k: set() for k in xy}
    around: dict[int, list[Element]] = {k: [] for k in xy}
    for e in new:
        for u, v in _edges(e):
            for a, b in ((u, v), (v, u)):
                if a in ring:
                    ring[a].add(b)
        for k in e:
            if k in around:
                around[k].append(e)
    pts = np.vstack([base, np.zeros((len(xy), 2))])
    for k, p in xy.items():
        pts[k] = p
    for _ in range(30):
        for k, nb in ring.items():
            pts[k] = np.mean(pts[sorted(nb)], axis=0)

    def worst(k: int) -> float:
        return min(shape_quality(pts, e) for e in around[k])

    dirs = [np.array([math.cos(a), math.sin(a)]) for a in np.arange(8) * math.pi / 4]
    for k, nb in ring.items():
        step = 0.25 * min(np.linalg.norm(pts[j] - pts[k]) for j in nb)
        best = worst(k)
        for _ in range(40):
            start = pts[k].copy()
            for d in dirs:
                pts[k] = start + step * d
                q = worst(k)
                if q > best:
                    best, start = q, pts[k].copy()
            pts[k] = start
            step *= 0.7
    for k in xy:
        xy[k] = pts[k]
    return min(shape_quality(pts, e) for e in new)


def all_quads(xy: np.ndarray, elements: Sequence[Sequence[int]]
              ) -> tuple[np.ndarray, np.ndarray, int]:
    """An all-quadrilateral mesh of the triangles and quadrilaterals ``elements``.

    ``elements``: node ids into ``xy`` ((n, 2), m). Returns the node coordinates (``xy`` and the
    new nodes after it), the quadrilaterals ((m, 4), counter-clockwise) and the number of
    triangle pairs joined. Raises :class:`QuadRepairError` for a tangled mesh (an element
    flat, or turning the other way than the others: a mesher's smoothing can push a node
    across an edge), an odd number of triangles, or when a triangle has no valid partner.
    """
    xy = np.array(xy, dtype=float)
    turns = {math.copysign(1.0, a) if a != 0.0 else 0.0 for a in (_area2(xy, e) for e in elements)}
    if len(turns) > 1 or 0.0 in turns:
        raise QuadRepairError("the mesh is tangled: an element is flat or inverted")
    m = _Mesh(xy, elements)
    tris = [k for k, e in m.elems.items() if len(e) == 3]
    if len(tris) % 2:
        raise QuadRepairError(f"{len(tris)} triangles: an odd number cannot be paired")
    pairs = 0
    while (start := next((k for k, e in m.elems.items() if len(e) == 3), None)) is not None:
        best = None
        for n, path in enumerate(_paths(m, start)):
            q, new, pts = _refine(m, path)
            if q > 0.0 and (best is None or q > best[0]):
                best = (q, new, pts, path)
            if best is not None and (best[0] >= GOOD or n >= TRIES):
                break
        if best is None:
            raise QuadRepairError("no convex refinement pairs a leftover triangle")
        _, new, pts, path = best
        for k in path:
            m.remove(k)
        m.xy = np.vstack([m.xy, [pts[k] for k in sorted(pts)]])
        for e in new:
            m.add(e)
        pairs += 1
    quads = np.array(list(m.elems.values()), dtype=np.int64).reshape(-1, 4)
    return m.xy, quads, pairs
