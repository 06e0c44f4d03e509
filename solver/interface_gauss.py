"""The pile-soil interface law at the 2 x 2 Gauss points of every interface facet (Q1 only).

The variant of :class:`~pilegroup.solver.interface.NodalInterface` selected by
``InterfaceCoupling.quadrature = "gauss"``; the measured comparison of both is in
docs/solver.md ("Interface quadrature").
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import basix
import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx import mesh as dmesh
from petsc4py import PETSc

from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.interface import BASE, SHAFT, NodalInterface
from pilegroup.solver.interface_groups import GaussGroup, InterfacePoints

# 2 x 2 Gauss rule on the unit square (s, t) in [0, 1]^2, weights 1/4, and the bilinear shape
# functions of the facet nodes in basix's tensor order (s, t) = (0,0), (1,0), (0,1), (1,1).
_GP = 0.5 * (1.0 + np.array([-1.0, 1.0]) / np.sqrt(3.0))
_ST = np.array([(s, t) for t in _GP for s in _GP])


def _bilinear(st: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Values and (s, t) derivatives ``(g, 4)`` of the bilinear facet shape functions."""
    s, t = st[:, 0], st[:, 1]
    N = np.column_stack([(1 - s) * (1 - t), s * (1 - t), (1 - s) * t, s * t])
    dNs = np.column_stack([-(1 - t), 1 - t, -t, t])
    dNt = np.column_stack([-(1 - s), -s, 1 - s, s])
    return N, dNs, dNt


_NG, _DNS, _DNT = _bilinear(_ST)


class GaussInterface(NodalInterface):
    """The interface law at the 2 x 2 Gauss points of every interface facet (Q1 only).

    Same groups, laws, frames and signs as :class:`NodalInterface`; the state lives per
    (facet, Gauss point) of the facet's group, and the shaft frame uses the facet's own normal
    (horizontal part). At a Gauss point ``g`` of a facet with nodes ``a`` (bilinear ``N_a``):

    * jump: ``[[u]]_g = sum_a N_a(x_g) [[u]]_a`` (the nodal jump of :meth:`compute_jump`, exact
      at the nodes for Q1);
    * nodal interface force (kN, on the soil; minus on the structure):
      ``f_a = sum_g N_a(x_g) w_g |J_g| R_g^T t_g``. The residual forms are the nodal ones
      (GLL: ``int T phi_a dS = T_a A_a``), so the traction Function holds ``T_a = f_a / A_a``
      and the assembled residual is exactly ``f_a``;
    * tangent (kN/m): ``K_ab = sum_g N_a N_b w_g |J_g| R_g^T D_g R_g`` couples all nodes of a
      facet; it is added to the Newton matrix by :meth:`add_jacobian` (the nodal tangent
      Function ``D`` stays zero).

    Only facets owned by this rank are listed (as in :func:`interface_entities`), so each
    facet contributes once in parallel.
    """

    quadrature = "gauss"
    has_matrix = True

    def surface_measure(self) -> ufl.Measure:
        """Shaft and base facets with the 2 x 2 Gauss rule of the law's points.

        The excess pore pressure beside the law (``solver/forms.py::interface``) is integrated
        as the law's traction is, so that a pressure the initial traction holds cancels exactly.
        """
        dS = self.dS.reconstruct(metadata={"quadrature_degree": 3})
        return dS(SHAFT) + dS(BASE)

    def _build_groups(self, md: MeshData, ents: list, traction0: Callable,
                      parts: tuple) -> list[GaussGroup]:
        """Facet data per group: soil/structure nodes, Gauss weights, frames, states."""
        if self.V_soil.ufl_element().embedded_superdegree != 1:
            raise ValueError("interface quadrature 'gauss' needs degree-1 (Q1) displacements; "
                             "use quadrature 'nodal' with Q2")
        if md.mesh.topology.cell_type != dmesh.CellType.hexahedron:
            raise ValueError("interface quadrature 'gauss' needs hexahedral cells")
        L = self.split.n_layers
        split = self.split
        vdof = np.array([self.V_soil.dofmap.dof_layout.entity_dofs(0, v)[0] for v in range(8)])
        fvert = vdof[np.array(basix.topology(basix.CellType.hexahedron)[2])]  # (6, 4)
        xs = self.V_soil.tabulate_dof_coordinates()
        xt = self.V_struct.tabulate_dof_coordinates()
        e = np.concatenate([ents[0][1], ents[1][1]]).reshape(-1, 4)
        kind = np.repeat([SHAFT, BASE], [ents[0][1].size // 4, ents[1][1].size // 4])
        sc = split.soil_map.sub_topology_to_topology(e[:, 2].copy(), inverse=True)
        tc = split.structure_map.sub_topology_to_topology(e[:, 0].copy(), inverse=True)
        dm_s, dm_t = self.V_soil.dofmap.list, self.V_struct.dofmap.list
        fn_s = np.take_along_axis(dm_s[sc], fvert[e[:, 3]], axis=1)
        fn_t = np.take_along_axis(dm_t[tc], fvert[e[:, 1]], axis=1)
        # the structure's copy of each soil node, by position (the same parent vertex)
        dist = np.linalg.norm(xs[fn_s][:, :, None] - xt[fn_t][:, None, :], axis=3)
        fn_t = np.take_along_axis(fn_t, np.argmin(dist, axis=2), axis=1)
        X = xs[fn_s]  # (f, 4, 3)
        size = np.linalg.norm(X[:, 3] - X[:, 0], axis=1)
        if fn_s.size and np.max(np.min(dist, axis=2).max(axis=1) / size) > 1e-8:
            raise RuntimeError("structure and soil facet nodes do not coincide")
        dxs = np.einsum("ga,fai->fgi", _DNS, X)
        dxt = np.einsum("ga,fai->fgi", _DNT, X)
        wJ = 0.25 * np.linalg.norm(np.cross(dxs, dxt), axis=2)  # (f, 4), m^2
        xg = np.einsum("ga,fai->fgi", _NG, X)
        # facet normal at the centre, oriented out of the structure (into the soil cell)
        _, dNs, dNt = _bilinear(np.array([[0.5, 0.5]]))
        nc = np.cross(np.einsum("a,fai->fi", dNs[0], X), np.einsum("a,fai->fi", dNt[0], X))
        into = xs[dm_s[sc]].mean(axis=1) - X.mean(axis=1)
        nc *= np.where(np.einsum("fi,fi->f", nc, into) < 0.0, -1.0, 1.0)[:, None]
        layer = split.soil_layer[e[:, 2]]
        gid = np.where(kind == SHAFT, layer, L + layer)
        groups: list[GaussGroup] = []
        for m in range(2 * L):
            sel = np.flatnonzero(gid == m)
            nf = sel.size
            if nf and self.laws[m] is None:
                raise ValueError(f"interface group {m} has facets but no law")
            R = np.repeat(self._frames(nc[sel], base=m >= L), 4, axis=0)
            x = xg[sel].reshape(-1, 3)
            law = self.laws[m]
            state = law.initial_state(4 * nf, traction0(x, x[:, 2], m)) if nf else None
            dofs = [(3 * f[:, :, None] + np.arange(3)).reshape(nf, 12).astype(np.int32)
                    for f in (fn_s[sel], fn_t[sel])]
            groups.append(GaussGroup(fnodes=fn_s[sel], dofs_soil=dofs[0], dofs_struct=dofs[1],
                                     wJ=wJ[sel], x=x, R=R, law=law, state=state, trial=state,
                                     c_s=self.shaft_factor if m < L else 1.0,
                                     K=np.zeros((nf, 12, 12))))
        return groups

    def _scatter_add(self, a: np.ndarray) -> np.ndarray:
        """Sum nodal contributions ``(n_nodes, c)`` over ranks (owners and ghosts updated)."""
        vec = la.vector(self.V_soil.dofmap.index_map, bs=a.shape[1])
        vec.array[:] = a.ravel()
        vec.scatter_reverse(la.InsertMode.add)
        vec.scatter_forward()
        return vec.array.reshape(a.shape).copy()

    def _at_points(self, g: dict[str, Any], nodal: np.ndarray) -> np.ndarray:
        """Nodal vectors ``(n_nodes, 3)`` interpolated to the group's Gauss points."""
        return np.einsum("ga,fai->fgi", _NG, nodal[g.fnodes]).reshape(-1, 3)

    def update(self, u_struct: fem.Function, u_soil: fem.Function, dt: float) -> None:
        """Evaluate every group's law at its Gauss points; fill ``T`` and the facet tangents."""
        self.last_error = ""
        jump = self.compute_jump(u_struct, u_soil).reshape(-1, 3)
        d_jump = jump - self._jump_committed.reshape(-1, 3)
        F = np.zeros_like(jump)
        for m, g in enumerate(self.groups):
            nf = g.fnodes.shape[0]
            if nf == 0:
                continue
            R = g.R
            d_loc = np.einsum("nij,nj->ni", R, self._at_points(g, d_jump))
            t_loc, trial, D_loc, error = self._law(g, d_loc, dt)
            if error:
                self.last_error = f"interface group {m}: {error}"
            g.trial = trial
            c = np.array([1.0, g.c_s, g.c_s])  # the shaft's shear on the circle's perimeter
            t = np.einsum("nji,nj->ni", R, c * t_loc).reshape(nf, 4, 3) * g.wJ[:, :, None]
            np.add.at(F, g.fnodes, np.einsum("ga,fgi->fai", _NG, t))
            D = np.einsum("nki,nkl,nlj->nij", R, c[:, None] * D_loc, R).reshape(nf, 4, 3, 3)
            g.K = np.einsum("ga,gb,fgij->faibj", _NG, _NG,
                            D * g.wJ[:, :, None, None]).reshape(nf, 12, 12)
        F = self._scatter_add(F)
        A = self.A[:, None]
        self.T.x.array[:] = np.divide(F, A, out=np.zeros_like(F), where=A > 0).ravel()

    def add_jacobian(self, A: PETSc.Mat, is_soil: PETSc.IS, is_struct: PETSc.IS,
                     bc_soil: np.ndarray, bc_struct: np.ndarray) -> None:
        """Add the facet tangents of the last :meth:`update` to the assembled matrix ``A``.

        ``is_soil``/``is_struct``: local index sets of the soil and structure displacement
        blocks in ``A`` (as ``dolfinx.fem.petsc.assemble_matrix`` uses them);
        ``bc_soil``/``bc_struct``: constrained local (unrolled) dofs of each block, whose rows
        and columns get nothing (they keep the unit diagonal of the boundary conditions).
        Blocks: soil-soil ``+K``, soil-structure ``-K``, structure-soil ``-K``,
        structure-structure ``+K`` (the residual is ``+f`` on the soil, ``-f`` on the pile and
        ``f`` depends on ``u_soil - u_struct``). Calls ``A.assemble()``.
        """
        gs = [g for g in self.groups if g.fnodes.shape[0]]
        if gs:
            K = np.concatenate([g.K for g in gs])
            ds = np.concatenate([g.dofs_soil for g in gs])
            dt = np.concatenate([g.dofs_struct for g in gs])
        else:
            K, ds, dt = np.zeros((0, 12, 12)), np.zeros((0, 12), np.int32), np.zeros((0, 12),
                                                                                   np.int32)
        free = {"s": ~np.isin(ds, bc_soil), "t": ~np.isin(dt, bc_struct)}
        dofs = {"s": ds.astype(PETSc.IntType), "t": dt.astype(PETSc.IntType)}
        iset = {"s": is_soil, "t": is_struct}
        for r, c, sign in (("s", "s", 1.0), ("s", "t", -1.0), ("t", "s", -1.0),
                           ("t", "t", 1.0)):
            Kb = sign * K * free[r][:, :, None] * free[c][:, None, :]
            sub = A.getLocalSubMatrix(iset[r], iset[c])
            sub.setValuesLocalRCV(dofs[r], dofs[c], Kb.reshape(K.shape[0], 144),
                                  addv=PETSc.InsertMode.ADD_VALUES)
            A.restoreLocalSubMatrix(iset[r], iset[c], sub)
        A.assemble()

    def touched_dofs(self, body: str) -> np.ndarray:
        """Local unrolled dofs of ``body`` (``"soil"``/``"structure"``) on interface facets."""
        return np.unique(np.concatenate([(g.dofs_soil if body == "soil" else g.dofs_struct).ravel()
                                         for g in self.groups]))

    def material_points(self, m: int) -> InterfacePoints:
        """The committed Gauss points of group ``m``.

        Keys as :meth:`NodalInterface.material_points`; ``node`` is the first node of the
        point's facet.
        """
        g = self.groups[m]
        jump = self._at_points(g, self.committed_jump())
        return InterfacePoints(weight=g.wJ.ravel() * g.c_s, x=g.x,
                               node=np.repeat(g.fnodes[:, 0], 4), state=g.state,
                               jump_local=np.einsum("nij,nj->ni", g.R, jump))

    def nodal_fields(self) -> dict[str, np.ndarray]:
        """Committed state per soil node: area-weighted averages of the Gauss-point values.

        ``value_a = sum_{f,g} N_a(x_g) w_g |J_g| value_g / sum_{f,g} N_a(x_g) w_g |J_g|`` over
        the facets (all groups, all ranks) around node ``a``; fields and signs as in
        :meth:`NodalInterface.nodal_fields` (``jump`` is the nodal jump).
        """
        n = self.A.size
        keys = [k for k in self.FIELDS if k != "jump"]
        acc = np.zeros((n, len(keys) + 1))
        for m, g in enumerate(self.groups):
            nf = g.fnodes.shape[0]
            if nf == 0:
                continue
            p = self.material_points(m)
            st = p["state"]
            vals = np.column_stack([st["traction"], p["jump_local"],
                                    np.linalg.norm(st["slip_vp"], axis=1), st["detached"][:, 0],
                                    np.ones(4 * nf)]).reshape(nf, 4, -1)
            np.add.at(acc, g.fnodes, np.einsum("ga,fg,fgk->fak", _NG, g.wJ, vals))
        acc = self._scatter_add(acc)
        w = acc[:, -1:]
        avg = np.divide(acc[:, :-1], w, out=np.zeros((n, len(keys))), where=w > 0)
        out = {k: avg[:, i:i + 1].copy() for i, k in enumerate(keys)}
        out["jump"] = self.committed_jump().copy()
        return out

    def law_points(self, m: int) -> np.ndarray:
        """Coordinates (m) of group ``m``'s law points (its Gauss points)."""
        return self.groups[m].x
