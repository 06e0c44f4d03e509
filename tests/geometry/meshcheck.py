"""Independent numpy checks of a MeshData (volumes, areas, scaled Jacobian, tag sums).

Used by the tests and, under ``mpirun``, as a script: ``python meshcheck.py SPEC H`` prints a
JSON line of global counts and tag sums (rank 0).
"""

from __future__ import annotations

import json
import math
import sys

import numpy as np

import pilegroup  # noqa: F401  (dolfinx_solver before dolfinx: keep it first when run as a script)

# isort: split
import dolfinx
from mpi4py import MPI

from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.groups import tag_of
from pilegroup.geometry.spec import (
    BlockSpec,
    CapSpec,
    GeometrySpec,
    LayerSpec,
    MeshSizing,
    grid_piles,
    pier667_default,
)

# corners of the reference hexahedron in DOLFINx (tensor-product) vertex order
_REF = np.array([[i, j, k] for k in (0, 1) for j in (0, 1) for i in (0, 1)], dtype=float)


def cell_coords(mesh):
    """(num_local_cells, 8, 3) corner coordinates of the owned cells."""
    n = mesh.topology.index_map(3).size_local
    return mesh.geometry.x[mesh.geometry.dofmaps[0][:n]]


def _dN(xi):
    """Derivatives of the 8 trilinear shape functions at xi (3,) -> (8, 3)."""
    out = np.empty((8, 3))
    for a, (i, j, k) in enumerate(_REF):
        f = [(1 - xi[0]) if i == 0 else xi[0], (1 - xi[1]) if j == 0 else xi[1],
             (1 - xi[2]) if k == 0 else xi[2]]
        d = [-1.0 if i == 0 else 1.0, -1.0 if j == 0 else 1.0, -1.0 if k == 0 else 1.0]
        out[a] = [d[0] * f[1] * f[2], f[0] * d[1] * f[2], f[0] * f[1] * d[2]]
    return out


def hex_volumes(x):
    """Exact volumes of trilinear hexahedra (2x2x2 Gauss is exact for det J)."""
    g = 0.5 + np.array([-1.0, 1.0]) / (2 * math.sqrt(3.0))
    vol = np.zeros(x.shape[0])
    for a in g:
        for b in g:
            for c in g:
                J = np.einsum("cai,aj->cij", x, _dN(np.array([a, b, c])))
                vol += np.linalg.det(J) / 8.0
    return vol


def min_scaled_jacobian(x):
    """Minimum over the 8 corners of det of the unit edge vectors (Verdict's hex SJ)."""
    sj = np.full(x.shape[0], np.inf)
    for a, (i, j, k) in enumerate(_REF):
        nb = []
        for d in range(3):
            t = np.array([i, j, k], dtype=int)
            t[d] = 1 - t[d]
            b = int(np.flatnonzero((_REF == t).all(axis=1))[0])
            sign = 1.0 if _REF[a][d] == 0 else -1.0
            e = sign * (x[:, b] - x[:, a])
            nb.append(e / np.linalg.norm(e, axis=1)[:, None])
        sj = np.minimum(sj, np.einsum("ci,ci->c", nb[0], np.cross(nb[1], nb[2])))
    return sj


def facet_areas(mesh, facets):
    """Areas of planar quadrilateral facets (half the cross product of the diagonals)."""
    if len(facets) == 0:
        return np.zeros(0)
    geo = dolfinx.mesh.entities_to_geometry(mesh, 2, np.asarray(facets, dtype=np.int32))
    x = mesh.geometry.x[geo]
    return 0.5 * np.linalg.norm(np.cross(x[:, 3] - x[:, 0], x[:, 2] - x[:, 1]), axis=1)


def owned_facets(mesh, facets):
    return facets[facets < mesh.topology.index_map(2).size_local]


def group_measures(md):
    """Global volume per cell group and area per facet group, counts and tag sums.

    Asserts first that every group's name and tag follow :mod:`pilegroup.geometry.groups`.
    """
    for name, tag in [*md.cell_names.items(), *md.facet_names.items()]:
        assert tag_of(name) == tag, (name, tag)
    mesh = md.mesh
    comm = mesh.comm
    mesh.topology.create_connectivity(2, 3)
    n_own = mesh.topology.index_map(3).size_local
    ct = md.cell_tags
    own = ct.indices < n_own
    vols = hex_volumes(cell_coords(mesh))
    out = {"cells": {}, "facets": {}}
    for name, tag in md.cell_names.items():
        idx = ct.indices[own][ct.values[own] == tag]
        out["cells"][name] = (comm.allreduce(int(idx.size)), comm.allreduce(float(vols[idx].sum())))
    ft = md.facet_tags
    for name, tag in md.facet_names.items():
        f = owned_facets(mesh, ft.indices[ft.values == tag])
        out["facets"][name] = (comm.allreduce(int(f.size)),
                               comm.allreduce(float(facet_areas(mesh, f).sum())))
    out["num_cells"] = mesh.topology.index_map(3).size_global
    out["num_vertices"] = mesh.topology.index_map(0).size_global
    out["num_facets"] = mesh.topology.index_map(2).size_global
    out["cell_tag_sum"] = comm.allreduce(int(ct.values[own].sum()))
    fo = ft.indices < mesh.topology.index_map(2).size_local
    out["facet_tag_sum"] = comm.allreduce(int(ft.values[fo].sum()))
    out["total_volume"] = comm.allreduce(float(vols.sum()))
    return out


def mini_pier(h=0.5):
    """A small 2 x 2 pile group with cap in three layers (fast, used for MPI)."""
    return GeometrySpec(
        block=BlockSpec(24.0, 20.0, 20.0),
        layers=(LayerSpec("a", 1.0), LayerSpec("b", 6.0), LayerSpec("c", None)),
        piles=grid_piles(2, 2, 3.0, 2.5, 0.8, 9.0, 0.5),
        cap=CapSpec.centred(6.0, 5.0, 1.5),
        sizing=MeshSizing(h_pile=h, h_far=4.0, dz_max=2.0, dz_max_deep=4.0),
    )


def main(argv):
    which, h = argv[1], float(argv[2])
    spec = mini_pier(h) if which == "mini" else pier667_default(h)
    md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=argv[3] if len(argv) > 3 else False)
    res = group_measures(md)
    if MPI.COMM_WORLD.rank == 0:
        print("RESULT " + json.dumps(res, sort_keys=True))


if __name__ == "__main__":
    main(sys.argv)
