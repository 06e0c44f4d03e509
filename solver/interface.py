"""Zero-thickness pile-soil interface between two bodies meshed on separate sub-meshes.

Piles and cap ("structure") and soil get their own displacement spaces on sub-meshes of the one
conforming parent mesh (``dolfinx.mesh.create_submesh``); they are joined only by the interface
terms, integrated over the parent's pile-surface facets with mixed-domain forms (``entity_maps``),
the structure on the ``"+"`` side and the soil on the ``"-"`` side.

Quadrature (``InterfaceCoupling.quadrature``), measured against each other in docs/solver.md:

* ``"nodal"`` (:class:`NodalInterface`): the Gauss-Lobatto-Legendre rule whose points are the
  displacement element's nodes (2 x 2 for Q1, 3 x 3 for Q2), so the law and its state live at the
  interface *nodes*: the classic remedy for the traction oscillations of Gauss-integrated
  interfaces with stiff penalties (Schellekens & de Borst 1993, IJNME 36:43-66); the coupling
  matrix between structure and soil dofs is node-to-node.
* ``"gauss"`` (:class:`GaussInterface`, Q1 only): the law at the 2 x 2 Gauss points of every
  facet, the nodal forces and the consistent (facet-coupling) tangent summed over them; the
  same GLL forms carry the nodal forces, the tangent is added to the Newton matrix directly.

At a node ``i`` the interface holds one material point per *group* ``m`` it belongs to: shaft
facets in soil layer ``j`` form group ``j``, pile bases in layer ``j`` form group ``L + j``. Each
group has its own local frame (shaft: outward radial normal, vertical t1, circumferential t2;
base: normal -z, t1 = x, t2 = y), its own law (the layer's parameters) and its own state. With the
nodal weights ``W[i, m] = int_group phi_i dS`` the assembled terms are exact sums over groups:
the traction and tangent Functions hold ``sum_m W[i, m] R^T C t_m / A_i`` and
``sum_m W[i, m] R^T C D_m R / A_i`` with ``A_i = sum_m W[i, m]``; ``C = diag(c_n, c_s, c_s)``
scales a shaft's tractions (``NodalGroup``): a pile is meshed as the polygon of its circle's
area, whose perimeter is longer, and ``c_s`` (``InterfaceCoupling.shaft_factor``) gives the
shaft the circle's friction force per unit length.

Signs: the jump is ``[[u]] = u_soil - u_structure``; its local normal component is the opening
(positive = gap), t1 is the soil moving up relative to the pile. The interface traction ``t``
(kPa, tension positive) enters the residual as ``+int t . v_soil dS - int t . v_struct dS``, so
a positive t1 is an upward (supporting) shear on the pile.
"""

from __future__ import annotations

import functools
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np
import ufl
from dolfinx import fem, la
from dolfinx import mesh as dmesh
from petsc4py import PETSc

from pilegroup.constitutive.base import ConstitutiveLaw
from pilegroup.geometry import groups
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.interface_groups import GaussGroup, InterfacePoints, NodalGroup
from pilegroup.solver.interface_tangent import NodePairs, add_node_blocks, coincident_nodes
from pilegroup.solver.layout import BodySplit
from pilegroup.solver.qpstate import guarded_update

#: Subdomain ids of the interface measure.
SHAFT, BASE = 1, 2
#: Distance (m) within which a node lies on a mirror plane (the mesh puts them on it exactly).
MIRROR_TOL = 1e-9


def interface_entities(md: MeshData, split: BodySplit, kind: int) -> np.ndarray:
    """Interior-facet integration entities ``(c+, lf+, c-, lf-)`` of the shafts or the bases.

    ``kind`` is :data:`SHAFT` or :data:`BASE` (facet groups named by
    :mod:`pilegroup.geometry.groups`); the structure cell comes first (``"+"``); only owned
    facets are listed (no double counting in parallel).
    """
    prefix = "shaft_p*" if kind == SHAFT else "base_p*"
    of = groups.shaft_of if kind == SHAFT else groups.base_of
    msh = md.mesh
    tdim = msh.topology.dim
    msh.topology.create_connectivity(tdim - 1, tdim)
    msh.topology.create_connectivity(tdim, tdim - 1)
    values = [v for n, v in md.facet_names.items() if of(n) is not None]
    facets = np.unique(np.concatenate([md.facet_tags.find(v) for v in values])
                       if values else np.zeros(0, np.int32))
    facets = facets[facets < msh.topology.index_map(tdim - 1).size_local]
    f2c = msh.topology.connectivity(tdim - 1, tdim)
    c2f = msh.topology.connectivity(tdim, tdim - 1)
    off = f2c.offsets
    if facets.size and np.any(off[facets + 1] - off[facets] != 2):
        raise ValueError(f"facet groups {prefix} contain boundary facets; an interface facet "
                         "must have a structure cell on one side and a soil cell on the other")
    c0 = f2c.array[off[facets]]
    c1 = f2c.array[off[facets] + 1]
    swap = ~split.is_structure[c0]
    cp = np.where(swap, c1, c0)
    cs = np.where(swap, c0, c1)
    if np.any(~split.is_structure[cp]) or np.any(split.is_structure[cs]):
        raise ValueError(f"facet groups {prefix} are not all between structure and soil")
    nf = c2f.offsets[1] - c2f.offsets[0]
    cf = c2f.array.reshape(-1, nf)
    lfp = np.argmax(cf[cp] == facets[:, None], axis=1)
    lfs = np.argmax(cf[cs] == facets[:, None], axis=1)
    return np.column_stack([cp, lfp, cs, lfs]).astype(np.int32).ravel()


class NodalInterface:
    """The interface terms of the coupled problem, with nodal state per (node, group).

    The law is evaluated at the interface nodes (GLL quadrature); see
    :class:`GaussInterface` for the variant with the law at the facets' Gauss points.

    Args:
        md: the parent mesh and tags (facet groups ``shaft_*`` and ``base_*``).
        split: structure/soil sub-meshes from :func:`split_bodies`.
        V_struct: displacement space on ``split.structure``.
        V_soil: displacement space on ``split.soil`` (same element).
        laws: one interface law per group: ``laws[j]`` for the shaft in layer ``j`` and
            ``laws[L + j]`` for pile bases in layer ``j`` (``None`` where no facet exists).
        traction0: ``traction0(x, z, m) -> (n, 3)`` initial local traction ``[sigma_n, tau1,
            tau2]`` (kPa, compression negative) of group ``m`` at the nodes ``x`` ((n, 3), m),
            a stress linear in depth taken at the heights ``z`` (the nodes' weighted heights).
    """

    #: Where the law is evaluated (``InterfaceCoupling.quadrature``).
    quadrature = "nodal"
    #: Whether :meth:`add_jacobian` contributes to the Newton matrix (else the forms do all).
    has_matrix = False

    def __init__(self, md: MeshData, split: BodySplit, V_struct: fem.FunctionSpace,
                 V_soil: fem.FunctionSpace, laws: Sequence[ConstitutiveLaw | None],
                 traction0: Callable[[np.ndarray, np.ndarray, int], np.ndarray],
                 shaft_factor: float = 1.0) -> None:
        self.split, self.shaft_factor = split, shaft_factor
        self.V_struct, self.V_soil = V_struct, V_soil
        L = split.n_layers
        if len(laws) != 2 * L:
            raise ValueError(f"need 2 x {L} laws (shaft and base per layer), got {len(laws)}")
        self.laws = list(laws)
        degree = V_soil.ufl_element().embedded_superdegree
        ents = [(SHAFT, interface_entities(md, split, SHAFT)),
                (BASE, interface_entities(md, split, BASE))]
        self.dS = ufl.Measure("dS", domain=md.mesh, subdomain_data=ents,
                              metadata={"quadrature_rule": "GLL",
                                        "quadrature_degree": 2 * degree - 1})
        self.entity_maps = [split.structure_map, split.soil_map]
        soil = split.soil
        # Nodal weights per group: W[i, m] = int_{group m} phi_i dS, one assembly for all groups.
        Q = fem.functionspace(soil, ("DG", 0, (2 * L,)))
        chi = fem.Function(Q)
        layer_of_sub = split.soil_layer[split.soil_map.sub_topology_to_topology(
            np.arange(_n_local_cells(soil), dtype=np.int32), inverse=False)]
        chi.x.array.reshape(-1, 2 * L)[np.arange(layer_of_sub.size), layer_of_sub] = 1.0
        chi.x.array.reshape(-1, 2 * L)[np.arange(layer_of_sub.size), L + layer_of_sub] = 1.0
        Wsp = fem.functionspace(soil, ("Lagrange", degree, (2 * L,)))
        self._check_same_nodes(Wsp, V_soil)
        psi = ufl.TestFunction(Wsp)
        shaft_part = ufl.as_vector([chi[k] for k in range(L)] + [0.0] * L)
        base_part = ufl.as_vector([0.0] * L + [chi[L + k] for k in range(L)])
        W = self._assemble_nodal(
            ufl.inner(shaft_part("-"), psi("-")) * self.dS(SHAFT)
            + ufl.inner(base_part("-"), psi("-")) * self.dS(BASE), Wsp)
        self.W = W.reshape(-1, 2 * L)
        self.A = self.W.sum(axis=1)
        self.groups: list[NodalGroup] | list[GaussGroup] = self._build_groups(
            md, ents, traction0, (shaft_part, base_part, psi, Wsp))
        # Coefficients of the forms: nodal traction and tangent (global frame).
        self.T = fem.Function(V_soil, name="interface_traction")
        Tsp = fem.functionspace(soil, ("Lagrange", degree, (3, 3)))
        self._check_same_nodes(Tsp, V_soil)
        self.D = fem.Function(Tsp, name="interface_tangent")
        self.jump = fem.Function(V_soil, name="interface_jump")
        self._jump_committed = np.zeros_like(self.jump.x.array)
        #: the jump when the laws were engaged (:meth:`activate`); outputs count from it
        self._jump_origin = np.zeros_like(self._jump_committed)
        #: whether the laws act (else only the committed traction: a structure not yet installed)
        self.active = True
        self._u_struct: fem.Function | None = None
        self._jump_form: fem.Form | None = None
        self.last_error = ""  # message of the last law failure on this rank
        self.degree = degree
        self._pairs: NodePairs | None = None

    # ---------- setup helpers ----------
    def _build_groups(self, md: MeshData, ents: list, traction0: Callable,
                      parts: tuple) -> list[NodalGroup] | list[GaussGroup]:
        """One material point per (interface node, group): nodes, frames, weights, states."""
        L = self.split.n_layers
        degree = self.V_soil.ufl_element().embedded_superdegree
        shaft_part, base_part, psi, Wsp = parts
        V_soil = self.V_soil
        # Shaft frame: area-weighted outward (structure) normal, made horizontal.
        v = ufl.TestFunction(V_soil)
        n_plus = ufl.FacetNormal(md.mesh)("+")
        N = self._assemble_nodal(ufl.inner(n_plus, v("-")) * self.dS(SHAFT), V_soil).reshape(-1, 3)
        # On a mirror plane of a reduced model a node sees the facets of one side only; the
        # whole ring's normal lies in the plane, so its component across the plane is zero.
        xs = V_soil.tabulate_dof_coordinates()
        for axis, plane in ((0, groups.SYM_X), (1, groups.SYM_Y)):
            if plane in md.facet_names:
                N[np.abs(xs[:, axis]) <= MIRROR_TOL, axis] = 0.0
        points: list[NodalGroup] = []
        # Consistent initial tractions: traction0 is linear in z within a group, so its
        # phi_i-weighted mean over the group's facets is its value at the weighted height
        # zbar[i, m] = int_m z phi_i dS / W[i, m] (Gauss rule here: exact), and the lumped
        # (nodal) interface force then equals int_m traction0 phi_i dS exactly; a pressure
        # integrated as the lumped pressure term is, at the node itself (traction0's x).
        dS_gauss = ufl.Measure("dS", domain=md.mesh, subdomain_data=ents,
                               metadata={"quadrature_degree": 2 * degree + 1})
        zc = ufl.SpatialCoordinate(md.mesh)[2]
        Zw = self._assemble_nodal(
            ufl.inner(zc * shaft_part("-"), psi("-")) * dS_gauss(SHAFT)
            + ufl.inner(zc * base_part("-"), psi("-")) * dS_gauss(BASE), Wsp).reshape(-1, 2 * L)
        # Normal force factor: on a faceted (polygonal) shaft the consistent resultant of a
        # normal pressure s at node i is s |N_i| (N_i = int n phi_i dS, horizontal part), not
        # s A_i; the normal traction is scaled by |N_i| / A_i so that an in-situ pressure is in
        # equilibrium with the soil's Gauss-integrated stress (-> 1 as the mesh is refined).
        a_shaft = self.W[:, :L].sum(axis=1)
        n_h = np.linalg.norm(N[:, :2], axis=1)
        c_n = np.divide(n_h, a_shaft, out=np.ones_like(n_h), where=a_shaft > 0)
        tol = 1e-12 * max(float(np.max(self.A, initial=0.0)), 1e-300)
        for m in range(2 * L):
            nodes = np.flatnonzero(self.W[:, m] > tol).astype(np.int32)
            if nodes.size and self.laws[m] is None:
                raise ValueError(f"interface group {m} has facets but no law")
            R = self._frames(N[nodes], base=m >= L)
            law = self.laws[m]
            zbar = Zw[nodes, m] / self.W[nodes, m]
            state = law.initial_state(nodes.size, traction0(xs[nodes], zbar, m)) \
                if nodes.size else None
            points.append(NodalGroup(nodes=nodes, R=R, w=self.W[nodes, m] / self.A[nodes],
                                     c_n=c_n[nodes] if m < L else np.ones(nodes.size),
                                     c_s=self.shaft_factor if m < L else 1.0,
                                     law=law, state=state, trial=state))
        return points

    @staticmethod
    def _check_same_nodes(a: fem.FunctionSpace, b: fem.FunctionSpace) -> None:
        xa, xb = a.tabulate_dof_coordinates(), b.tabulate_dof_coordinates()
        if xa.shape != xb.shape or not np.array_equal(xa, xb):
            raise RuntimeError("blocked spaces of one element do not share their node numbering")

    def _assemble_nodal(self, form: ufl.Form, V: fem.FunctionSpace) -> np.ndarray:
        vec = fem.assemble_vector(fem.form(form, entity_maps=self.entity_maps))
        vec.scatter_reverse(la.InsertMode.add)
        vec.scatter_forward()
        return vec.array.copy()

    @staticmethod
    def _frames(normals: np.ndarray, base: bool) -> np.ndarray:
        n = normals.shape[0]
        R = np.zeros((n, 3, 3))
        if base:
            R[:, 0] = (0.0, 0.0, -1.0)
            R[:, 1] = (1.0, 0.0, 0.0)
            R[:, 2] = (0.0, 1.0, 0.0)
            return R
        nh = normals.copy()
        nh[:, 2] = 0.0
        nrm = np.linalg.norm(nh, axis=1)
        if np.any(nrm <= 0.0):
            raise ValueError("a shaft node has no horizontal normal")
        nh /= nrm[:, None]
        R[:, 0] = nh
        R[:, 1] = (0.0, 0.0, 1.0)
        R[:, 2] = np.cross(nh, (0.0, 0.0, 1.0))
        return R

    # ---------- forms ----------
    def surface_measure(self) -> ufl.Measure:
        """The interface measure over every shaft and base facet (nodal quadrature)."""
        return self.dS(SHAFT) + self.dS(BASE)

    def residual_forms(self, v_struct: ufl.Argument, v_soil: ufl.Argument
                       ) -> tuple[ufl.Form, ufl.Form]:
        """Interface contributions to the structure and soil momentum residuals."""
        t = self.T("-")
        dS = self.dS(SHAFT) + self.dS(BASE)
        return -ufl.inner(t, v_struct("+")) * dS, ufl.inner(t, v_soil("-")) * dS

    def jacobian_forms(self, du_struct: ufl.Argument, du_soil: ufl.Argument,
                       v_struct: ufl.Argument, v_soil: ufl.Argument
                       ) -> list[list[ufl.Form]]:
        """Interface blocks ``[[J_ss', J_s's], ...]`` ordered (structure, soil)."""
        D = self.D("-")
        dS = self.dS(SHAFT) + self.dS(BASE)
        ap, as_ = du_struct("+"), du_soil("-")
        bp, bs = v_struct("+"), v_soil("-")
        return [[ufl.inner(D * ap, bp) * dS, -ufl.inner(D * as_, bp) * dS],
                [-ufl.inner(D * ap, bs) * dS, ufl.inner(D * as_, bs) * dS]]

    def add_nodal_tangent(self, A: PETSc.Mat, is_soil: PETSc.IS, is_struct: PETSc.IS,
                          bc_soil: np.ndarray, bc_struct: np.ndarray) -> None:
        """Add the matrix of :meth:`jacobian_forms` to ``A`` node by node (unassembled).

        With the GLL rule the forms couple each soil node only with the structure node at the
        same place (:func:`~pilegroup.solver.interface_tangent.add_node_blocks`), at a small
        part of the cost of integrating the interior-facet forms. Arguments as
        :meth:`GaussInterface.add_jacobian`, whose tangent lives in its own matrix (``D``
        zero): nothing is added then.
        """
        if self.has_matrix:
            return
        if self._pairs is None:
            Vs = fem.functionspace(self.split.soil, ("Lagrange", self.degree))
            self._check_same_nodes(Vs, self.V_soil)
            self._pairs = coincident_nodes(Vs, self.V_struct, self.surface_measure(),
                                           self.entity_maps)
        add_node_blocks(A, (is_soil, is_struct), self._pairs, self.D.x.array.reshape(-1, 3, 3),
                        (bc_soil, bc_struct))

    # ---------- state ----------
    def compute_jump(self, u_struct: fem.Function, u_soil: fem.Function) -> np.ndarray:
        """Nodal jump ``u_soil - u_struct`` (m, global frame), by lumped nodal projection."""
        if self._jump_form is None or self._u_struct is not u_struct:
            v = ufl.TestFunction(self.V_soil)
            dS = self.dS(SHAFT) + self.dS(BASE)
            self._jump_form = fem.form(ufl.inner(u_soil("-") - u_struct("+"), v("-")) * dS,
                                       entity_maps=self.entity_maps)
            self._u_struct = u_struct
        vec = fem.assemble_vector(self._jump_form)
        vec.scatter_reverse(la.InsertMode.add)
        vec.scatter_forward()
        A3 = np.repeat(self.A, 3)
        jump = np.divide(vec.array, A3, out=np.zeros_like(vec.array), where=A3 > 0)
        self.jump.x.array[:] = jump
        return jump

    def update(self, u_struct: fem.Function, u_soil: fem.Function, dt: float) -> None:
        """Evaluate every group's law at the current jump; fill the traction and tangent."""
        self.last_error = ""
        jump = self.compute_jump(u_struct, u_soil).reshape(-1, 3)
        d_jump = jump - self._jump_committed.reshape(-1, 3)
        T = np.zeros_like(jump)
        D = np.zeros((jump.shape[0], 3, 3))
        for m, g in enumerate(self.groups):
            nodes = g.nodes
            if nodes.size == 0:
                continue
            R = g.R
            d_loc = np.einsum("nij,nj->ni", R, d_jump[nodes])
            t_loc, trial, D_loc, error = self._law(g, d_loc, dt)
            if error:
                self.last_error = f"interface group {m}: {error}"
            g.trial = trial
            w = g.w
            c = np.column_stack([g.c_n, np.full((nodes.size, 2), g.c_s)])
            np.add.at(T, nodes, w[:, None] * np.einsum("nji,nj->ni", R, c * t_loc))
            np.add.at(D, nodes, w[:, None, None] * np.einsum("nki,nkl,nlj->nij", R,
                                                             c[:, :, None] * D_loc, R))
        self.T.x.array[:] = T.ravel()
        self.D.x.array[:] = D.ravel()

    def _law(self, g: Any, d_loc: np.ndarray, dt: float
             ) -> tuple[np.ndarray, dict[str, np.ndarray], np.ndarray, str]:
        """Group ``g``'s law at local jump increments ``d_loc``.

        Returns traction, trial state, tangent and error; inactive: the committed traction and
        state, no stiffness.
        """
        if self.active:
            return guarded_update(g.law, d_loc, g.state, dt)
        return (g.state["traction"].copy(), g.state, np.zeros((d_loc.shape[0], 3, 3)), "")

    def law_points(self, m: int) -> np.ndarray:
        """Coordinates (m) of group ``m``'s law points (here: its interface nodes)."""
        return self._soil_coords[self.groups[m].nodes]

    def activate(self, extra_normal: Callable[[np.ndarray], np.ndarray]) -> None:
        """Engage the laws from now on (a structure installed after the start).

        Each law starts afresh (no slip) at the traction it carried, its normal component plus
        ``extra_normal(x)`` (kPa, tension positive; e.g. the installation's excess pore
        pressure, which the soil's effective stress loses at the same instant); jump increments
        and the output jumps count from the current jump.
        """
        self._jump_origin[:] = self._jump_committed
        for m, g in enumerate(self.groups):
            if g.state is None:
                continue
            t = np.array(g.state["traction"], dtype=float)
            t[:, 0] += extra_normal(self.law_points(m))
            g.state = g.trial = g.law.initial_state(t.shape[0], t)
        self.active = True

    def committed_jump(self) -> np.ndarray:
        """The committed jump ``u_soil - u_structure`` since the laws were engaged, ``(n, 3)``."""
        return (self._jump_committed - self._jump_origin).reshape(-1, 3)

    def commit(self) -> None:
        """Adopt the trial state of the last :meth:`update` (after a converged step)."""
        for g in self.groups:
            g.state = g.trial
        self._jump_committed[:] = self.jump.x.array

    def rollback(self) -> None:
        """Forget the trial state (after a failed step)."""
        for g in self.groups:
            g.trial = g.state

    def saved_state(self) -> dict[str, np.ndarray]:
        """The committed state as arrays (checkpoint): each group's law state and the jump.

        Names: ``<group>/<key>`` for the law states, ``jump`` for the committed jump; the
        arrays are this rank's points (nodes or Gauss points).
        """
        out = {f"{m}/{k}": v for m, g in enumerate(self.groups) if g.state is not None
               for k, v in g.state.items()}
        out["jump"] = self._jump_committed.copy()
        out["jump_origin"] = self._jump_origin.copy()
        return out

    def restore_state(self, arrays: dict[str, np.ndarray]) -> None:
        """Set the committed state from :meth:`saved_state`'s arrays (same mesh partition)."""
        if arrays["jump"].shape != self._jump_committed.shape:
            raise ValueError("saved interface jump does not fit this rank's interface nodes")
        for m, g in enumerate(self.groups):
            if g.state is None:
                continue
            n = next(iter(g.state.values())).shape[0]
            state = {k.split("/", 1)[1]: np.array(a) for k, a in arrays.items()
                     if k.split("/", 1)[0] == str(m)}
            if set(state) != set(g.state) or any(a.shape[0] != n for a in state.values()):
                raise ValueError(f"saved state of interface group {m} does not fit its {n} "
                                 "points on this rank")
            g.state = g.trial = state
        self._jump_committed[:] = arrays["jump"]
        self.jump.x.array[:] = arrays["jump"]
        self._jump_origin[:] = arrays.get("jump_origin", 0.0)

    # ---------- output ----------
    FIELDS = {"normal_traction": 1, "shear_traction_vertical": 1,
              "shear_traction_circumferential": 1, "opening": 1, "slip_vertical": 1,
              "slip_circumferential": 1, "viscoplastic_slip": 1, "detached": 1, "jump": 3}

    def nodal_field_layout(self) -> dict[str, int]:
        """Names and component counts of :meth:`nodal_fields`."""
        return dict(self.FIELDS)

    def nodal_fields(self) -> dict[str, np.ndarray]:
        """Committed interface state per soil node (area-weighted over the node's groups).

        Local frame values: ``normal_traction`` (effective, kPa, tension positive),
        ``shear_traction_vertical`` (kPa, positive = upward shear on the pile),
        ``shear_traction_circumferential``, ``opening`` (m, positive = gap), ``slip_vertical``
        (m, positive = soil moves up relative to the pile), ``slip_circumferential``,
        ``viscoplastic_slip`` (m, magnitude), ``detached`` (0..1); ``jump`` is the global
        ``u_soil - u_structure`` (m). Jumps count from the laws' engagement (the start, or a
        later installation). Zero away from the interface.
        """
        n = self.A.size
        out = {k: np.zeros((n, c)) for k, c in self.FIELDS.items()}
        jump = self.committed_jump()
        out["jump"][:] = jump
        for g in self.groups:
            nodes = g.nodes
            if nodes.size == 0:
                continue
            st, w = g.state, g.w[:, None]
            loc = np.einsum("nij,nj->ni", g.R, jump[nodes])
            for key, val in (("normal_traction", st["traction"][:, :1]),
                             ("shear_traction_vertical", st["traction"][:, 1:2]),
                             ("shear_traction_circumferential", st["traction"][:, 2:3]),
                             ("opening", loc[:, :1]), ("slip_vertical", loc[:, 1:2]),
                             ("slip_circumferential", loc[:, 2:3]),
                             ("viscoplastic_slip",
                              np.linalg.norm(st["slip_vp"], axis=1, keepdims=True)),
                             ("detached", st["detached"])):
                np.add.at(out[key], nodes, w * val)
        return out

    @functools.cached_property
    def _soil_coords(self) -> np.ndarray:
        """Coordinates (m) of the soil displacement nodes (local numbering)."""
        return self.V_soil.tabulate_dof_coordinates()

    def material_points(self, m: int) -> InterfacePoints:
        """The committed material points of group ``m`` (here: its interface nodes).

        Keys: ``weight`` (m^2, the point's integration weight times ``c_s``; 0 on a rank that
        does not own the point, so sums over ranks count every point once), ``x`` (m),
        ``node`` (a soil node of the point, local numbering), ``state`` (the law state, or
        ``None`` without points), ``jump_local`` (m, ``[opening, slip1, slip2]``).
        """
        g = self.groups[m]
        nodes = g.nodes
        own = nodes < self.V_soil.dofmap.index_map.size_local
        jump = self.committed_jump()[nodes]
        return InterfacePoints(weight=np.where(own, self.W[nodes, m] * g.c_s, 0.0),
                               x=self._soil_coords[nodes], node=nodes, state=g.state,
                               jump_local=np.einsum("nij,nj->ni", g.R, jump))

    def reset_jump(self) -> None:
        """Take the current displacements as the reference (after the geostatic stage).

        The committed law states (tractions) are kept; only the committed jump, from which the
        next increments are measured, is set to zero with the displacements.
        """
        self._jump_committed[:] = 0.0
        self.jump.x.array[:] = 0.0


def _n_local_cells(msh: dmesh.Mesh) -> int:
    imap = msh.topology.index_map(msh.topology.dim)
    return imap.size_local + imap.num_ghosts


__all__ = ["BASE", "SHAFT", "NodalInterface", "interface_entities"]
