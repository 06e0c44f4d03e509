"""geometry/convert.py (check_mesh): a mesh DOLFINx would crash on is refused before it gets it.

Small hexahedral meshes made by hand (numpy, and a discrete gmsh model), each broken in one
way: a repeated vertex, a duplicate cell (which segfaults ``dolfinx.io.gmsh.model_to_mesh``),
a flat or inverted cell, a collapsed edge, a duplicate node, a facet node in no cell, a hanging
node. Also quadfix's shape measure, which sees a collapsing edge the scaled Jacobian does not.
"""

import numpy as np
import pytest

from pilegroup.errors import ScenarioError
from pilegroup.geometry import spec as gs
from pilegroup.geometry.convert import (
    MeshDefect,
    check_arrays,
    check_mesh,
    corner_jacobians,
    gmsh_session,
)
from pilegroup.geometry.groups import SIDES
from pilegroup.geometry.quadfix import (
    EDGE_WEIGHT,
    edge_ratio,
    element_quality,
    shape_quality,
)


def grid(nx, ny=1, nz=1):
    """Unit cubes over [0, nx] x [0, ny] x [0, nz]: nodes, hexahedra (gmsh order), faces."""
    ids = np.arange((nx + 1) * (ny + 1) * (nz + 1)).reshape(nz + 1, ny + 1, nx + 1)
    x = np.array([(i, j, k) for k in range(nz + 1) for j in range(ny + 1)
                  for i in range(nx + 1)], dtype=float)
    cells = np.array([[ids[k, j, i], ids[k, j, i + 1], ids[k, j + 1, i + 1], ids[k, j + 1, i],
                       ids[k + 1, j, i], ids[k + 1, j, i + 1], ids[k + 1, j + 1, i + 1],
                       ids[k + 1, j + 1, i]]
                      for k in range(nz) for j in range(ny) for i in range(nx)])
    return x, cells, boundary_faces(cells)


def boundary_faces(cells):
    faces = np.sort(cells[:, [[0, 3, 2, 1], [0, 1, 5, 4], [0, 4, 7, 3], [1, 2, 6, 5],
                              [2, 3, 7, 6], [4, 5, 6, 7]]].reshape(-1, 4), axis=1)
    uniq, counts = np.unique(faces, axis=0, return_counts=True)
    return uniq[counts == 1]


def test_a_valid_mesh_passes():
    x, cells, bnd = grid(3, 2, 2)
    check_arrays(x, cells, bnd, bnd)
    assert np.allclose(corner_jacobians(x[cells]), 1.0)


@pytest.mark.parametrize(("broken", "match"), [
    ("repeated", "repeated vertex"), ("duplicate_cell", "duplicate cell"),
    ("flat", "degenerate or inverted"), ("tangled", "degenerate or inverted"),
    ("collapsed_edge", "degenerate or inverted"), ("duplicate_node", "duplicate nodes"),
    ("loose_facet_node", "facet node"), ("hanging", "hanging nodes")])
def test_each_defect_is_named(broken, match):
    x, cells, bnd = grid(2)
    facets = bnd
    if broken == "repeated":
        cells[1, 6] = cells[1, 5]
    elif broken == "duplicate_cell":
        cells = np.vstack([cells, cells[:1]])
    elif broken == "flat":
        x[cells[1, 4:], 2] = 0.0
    elif broken == "tangled":  # a bow-tie: corner Jacobians of both signs
        cells[1] = cells[1][[0, 1, 3, 2, 4, 5, 6, 7]]
    elif broken == "collapsed_edge":
        x[cells[1, 6]] = x[cells[1, 5]] + [0.0, 1e-9, 0.0]
    elif broken == "duplicate_node":  # the second cell has a copy of a shared node
        x = np.vstack([x, x[cells[1, 0]]])
        cells[1, 0] = len(x) - 1
    elif broken == "loose_facet_node":
        x = np.vstack([x, [5.0, 5.0, 5.0]])
        facets = np.vstack([bnd, [[0, 1, 2, len(x) - 1]]])
    elif broken == "hanging":  # a 2 x 2 x 2 refined cube beside a single cube
        xf, cf, _ = grid(2, 2, 2)
        x = np.vstack([xf * 0.5 + [1.0, 0.0, 0.0], xf[:0]])
        x = np.vstack([x, [[0, 0, 0], [0, 1, 0], [0, 0, 1], [0, 1, 1]]])
        n = len(xf)
        node = {tuple(p): k for k, p in enumerate(x)}
        left = [n, node[(1.0, 0.0, 0.0)], node[(1.0, 1.0, 0.0)], n + 1, n + 2,
                node[(1.0, 0.0, 1.0)], node[(1.0, 1.0, 1.0)], n + 3]
        cells = np.vstack([cf, [left]])
        facets = bnd = np.vstack([f for f in boundary_faces(cells)
                                  if not np.all(x[f, 0] == 1.0)])  # the interface is not
    with pytest.raises(MeshDefect, match=match):
        check_arrays(x, cells, facets, bnd)


def _spec():
    return gs.GeometrySpec(block=gs.BlockSpec(10.0, 10.0, 1.0), layers=(gs.LayerSpec("a", None),),
                           piles=(gs.PileSpec(0.0, 0.0, 0.2, 0.5),),
                           sizing=gs.MeshSizing(h_pile=0.5, h_far=1.0))


@pytest.mark.parametrize("duplicate", [False, True])
def test_check_mesh_reads_the_gmsh_model(duplicate):
    """A duplicate cell in the gmsh model (it segfaults DOLFINx): a ScenarioError naming the
    mesh keys and the layout."""
    x, cells, bnd = grid(2)
    if duplicate:
        cells = np.vstack([cells, cells[:1]])
    with gmsh_session() as gmsh:
        gmsh.model.add("validity")
        try:
            v = gmsh.model.addDiscreteEntity(3)
            gmsh.model.mesh.addNodes(3, v, list(range(1, len(x) + 1)), x.ravel())
            gmsh.model.mesh.addElements(3, v, [5], [list(range(1, len(cells) + 1))],
                                        [(cells + 1).ravel().tolist()])
            s = gmsh.model.addDiscreteEntity(2)
            gmsh.model.mesh.addElements(2, s, [3], [list(range(100, 100 + len(bnd)))],
                                        [(bnd + 1).ravel().tolist()])
            gmsh.model.addPhysicalGroup(3, [v], 101, "soil_layer_01")
            gmsh.model.addPhysicalGroup(2, [s], 1, SIDES[0])
            if not duplicate:
                check_mesh(_spec())
                return
            with pytest.raises(ScenarioError, match=r"numerics\.mesh = .*'n_circ_min': 32.*"
                               r"piles: 1 in 1 x 1 rows.*1 duplicate cell"):
                check_mesh(_spec())
        finally:
            gmsh.model.remove()


def test_shape_quality_sees_a_collapsing_edge():
    """A node pushed onto its neighbour: every corner stays square (scaled Jacobian 1), but
    the edge ratio, and so the shape quality, goes to 0."""
    for eps in (1e-1, 1e-4, 1e-7):
        xy = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, eps], [0.0, 1.0]])
        assert element_quality(xy, (0, 1, 2, 3)) > 0.7
        assert edge_ratio(xy, (0, 1, 2, 3)) == pytest.approx(eps / np.hypot(1.0, 1.0 - eps))
        assert shape_quality(xy, (0, 1, 2, 3)) == pytest.approx(min(
            element_quality(xy, (0, 1, 2, 3)), EDGE_WEIGHT * eps / np.hypot(1.0, 1.0 - eps)))
    assert shape_quality(xy, (0, 1, 2, 3)) < 1e-6
