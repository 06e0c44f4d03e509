"""geometry/quadfix.py: leftover triangles of a quad-dominant mesh paired into quadrilaterals.

Every result is checked against its input independently: all elements convex quadrilaterals,
the same total area, the same boundary edges (the input nodes keep their ids and places), every
interior edge shared by exactly two elements (conforming).
"""

from collections import Counter

import numpy as np
import pytest

from pilegroup.geometry.quadfix import QuadRepairError, all_quads, element_quality


def _area(xy, e):
    p = xy[list(e)]
    return 0.5 * abs(np.sum(p[:, 0] * np.roll(p[:, 1], -1) - np.roll(p[:, 0], -1) * p[:, 1]))


def _edges(elements):
    return Counter(tuple(sorted((e[k], e[(k + 1) % len(e)]))) for e in elements
                   for k in range(len(e)))


def _check(xy, elements, out):
    xy2, quads, pairs = out
    assert quads.shape[1] == 4
    assert np.array_equal(xy2[: len(xy)], xy)
    assert min(element_quality(xy2, q) for q in quads) > 0.05
    assert sum(_area(xy2, q) for q in quads) == pytest.approx(sum(_area(xy, e) for e in elements),
                                                              rel=1e-12)
    before, after = _edges(elements), _edges([tuple(q) for q in quads])
    assert {e for e, n in after.items() if n == 1} == {e for e, n in before.items() if n == 1}
    assert set(after.values()) <= {1, 2}
    return pairs


def _grid(nx, ny):
    """Unit squares over [0, nx] x [0, ny]: node (i, j) has id j (nx + 1) + i."""
    xy = np.array([(i, j) for j in range(ny + 1) for i in range(nx + 1)], dtype=float)
    quads = {(i, j): (j * (nx + 1) + i, j * (nx + 1) + i + 1, (j + 1) * (nx + 1) + i + 1,
                      (j + 1) * (nx + 1) + i) for j in range(ny) for i in range(nx)}
    return xy, quads


def test_a_fan_of_two_triangles_at_a_straight_boundary_node():
    """Two triangles fanned at boundary node (1, 0): merged they would have a 180 degree corner."""
    xy, quads = _grid(5, 4)
    del quads[(0, 0)], quads[(1, 0)]
    c = len(xy)
    xy = np.vstack([xy, [(1.0, 0.6)]])
    b0, b1, b2, a0, a1, a2 = 0, 1, 2, 6, 7, 8
    elements = [*quads.values(), (b0, b1, c), (b1, b2, c), (b0, c, a1, a0), (c, b2, a2, a1)]
    assert element_quality(xy, (b0, b1, b2, c)) <= 0.0
    assert _check(xy, elements, all_quads(xy, elements)) == 1


def test_triangle_pairs_in_distant_cells():
    xy, quads = _grid(8, 6)
    elements = list(quads.values())
    for cell in ((1, 1), (6, 4)):
        q = quads[cell]
        elements.remove(q)
        elements += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    rng = np.random.default_rng(3)
    inner = [k for k, (x, y) in enumerate(xy) if 0 < x < 8 and 0 < y < 6]
    xy[inner] += rng.uniform(-0.2, 0.2, (len(inner), 2))
    assert _check(xy, elements, all_quads(xy, elements)) == 2


def test_an_all_quad_mesh_is_returned_unchanged():
    xy, quads = _grid(3, 2)
    xy2, out, pairs = all_quads(xy, list(quads.values()))
    assert pairs == 0 and np.array_equal(xy2, xy)
    assert {tuple(q) for q in out} == set(quads.values())


def test_an_odd_number_of_triangles_is_refused():
    xy = np.array([(0.0, 0.0), (1.0, 0.0), (0.0, 1.0)])
    with pytest.raises(QuadRepairError, match="odd"):
        all_quads(xy, [(0, 1, 2)])


def test_a_tangled_mesh_is_refused():
    """A node pushed across an edge (as a mesher's smoothing once did) inverts a triangle."""
    xy, quads = _grid(3, 2)
    q = quads[(1, 1)]
    elements = [e for cell, e in quads.items() if cell != (1, 1)]
    elements += [(q[0], q[1], q[2]), (q[0], q[2], q[3])]
    xy[q[0]] = (2.5, 1.2)  # node (1, 1) beyond the edge (2, 1)-(2, 2) of its triangle
    with pytest.raises(QuadRepairError, match="tangled"):
        all_quads(xy, elements)
