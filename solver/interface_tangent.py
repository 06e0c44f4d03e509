"""The nodal interface's tangent matrix inserted node by node, without integrating its forms.

With the law at the interface nodes (GLL quadrature, :class:`~pilegroup.solver.interface.
NodalInterface`) the interface's Jacobian forms ``+-int (D du) . v dS`` couple each soil node
``a`` only with the structure node at the same place, by ``A_a D_a``: ``D_a`` the nodal tangent
(kPa/m, global frame), ``A_a`` the node's area (the GLL weights of its facets). Soil-soil and
structure-structure blocks get ``+A_a D_a``, the cross blocks ``-A_a D_a``. Integrating the
interior-facet forms builds and inserts a dense element matrix of both cells per facet, mostly
zeros; these 3 x 3 blocks give the same matrix to round-off (docs/solver.md, "Jacobian
assembly").
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
import ufl
from dolfinx import fem
from petsc4py import PETSc
from scipy.spatial import cKDTree


class NodePairs(NamedTuple):
    """The interface's node pairs on this rank (local node numbers).

    ``soil``: soil nodes on this rank's interface facets; ``struct``: the structure nodes at
    the same places; ``area``: this rank's facets' part of each soil node's area (m^2).
    """

    soil: np.ndarray
    struct: np.ndarray
    area: np.ndarray


def coincident_nodes(Vs: fem.FunctionSpace, V_struct: fem.FunctionSpace, dS: ufl.Measure,
                     entity_maps: list) -> NodePairs:
    """The node pairs of the interface measure ``dS`` (soil on its ``"-"`` side).

    ``Vs``: a scalar space with the soil displacement's nodes. The area is assembled without
    summing over ranks: each rank inserts its own facets' part, as the assembly of the forms
    does. Raises ``RuntimeError`` if a soil node has no structure node at its place (the mesh
    must be conforming across the interface).
    """
    xs_all = Vs.tabulate_dof_coordinates()
    psi = ufl.TestFunction(Vs)
    area = fem.assemble_vector(fem.form(psi("-") * dS, entity_maps=entity_maps)).array.copy()
    s = np.flatnonzero(area > 0.0).astype(np.int32)
    xs = xs_all[s]
    dist, t = cKDTree(V_struct.tabulate_dof_coordinates()).query(xs)
    scale = max(float(np.max(np.abs(xs), initial=0.0)), 1.0)
    if s.size and float(np.max(dist)) > 1e-9 * scale:
        raise RuntimeError("interface soil node without a structure node at its place "
                           f"({float(np.max(dist)):.3g} m apart)")
    return NodePairs(s, t.astype(np.int32), area[s])


def add_node_blocks(A: PETSc.Mat, index_sets: tuple[PETSc.IS, PETSc.IS], pairs: NodePairs,
                    D: np.ndarray, constrained: tuple[np.ndarray, np.ndarray]) -> None:
    """Add ``+-A_a D_a`` to ``A`` (unassembled, ADD_VALUES).

    ``index_sets``: local index sets of the soil and structure displacement blocks in ``A``;
    ``D``: nodal tangents ``(n_soil_nodes, 3, 3)``; ``constrained``: constrained local
    (unrolled) dofs of each block, whose rows and columns get nothing.
    """
    M = pairs.area[:, None, None] * D[pairs.soil]
    k = np.arange(3)
    rows = {"s": (3 * pairs.soil[:, None] + k).astype(PETSc.IntType),
            "t": (3 * pairs.struct[:, None] + k).astype(PETSc.IntType)}
    free = {"s": ~np.isin(rows["s"], constrained[0]), "t": ~np.isin(rows["t"], constrained[1])}
    iset = {"s": index_sets[0], "t": index_sets[1]}
    for r, c, sign in (("s", "s", 1.0), ("s", "t", -1.0), ("t", "s", -1.0), ("t", "t", 1.0)):
        Mb = sign * M * free[r][:, :, None] * free[c][:, None, :]
        sub = A.getLocalSubMatrix(iset[r], iset[c])
        sub.setValuesLocalRCV(rows[r], rows[c], Mb.reshape(-1, 9),
                              addv=PETSc.InsertMode.ADD_VALUES)
        A.restoreLocalSubMatrix(iset[r], iset[c], sub)


__all__ = ["NodePairs", "add_node_blocks", "coincident_nodes"]
