"""Pile sections at the head and at every element-layer boundary, from nodal forces.

The action of the part of a pile above a horizontal plane of its mesh on the part below is the
sum over the plane's nodes of the forces the cells above the plane exert on them: minus those
cells' internal force ``int sigma : eps(v)`` at the plane's nodes, plus the loads on a face in
the plane (a pile head without a cap). The plane's own nodes belong to the part below, so the
soil's force on them (through the interface, or the soil cells of tied piles) is the part
below's. The cells above the head plane (depth 0) are the pile's embedded part and the cap;
above a plane below the ground, the pile's element layer above it.

This is the finite element's own equilibrium, node by node: with the part below as a free
body, the section action balances the soil's forces on the part below, to the Newton residual,
whatever the cells' size, shape or element. The structure's weight is left out of the nodal
forces: it never changes, and the sections are read as changes since the geostatic state.
Moments are taken about the plane's centre on the pile axis; the nodal forces' moment is exact
for any element (``sum_n x_n x f_n = 0`` over a cell's nodes for a symmetric stress). Values
are of the meshed part of each meshed pile, all-reduced over the ranks;
:mod:`pilegroup.studies.run.section_probe` makes them the whole pile's and changes since the
geostatic state.

Two assemblies give every plane: one over the pile element layers with an odd index (the
embedded part and the cap counted as layer -1), one over the even ones; a plane's cells above
are the layer above it, so the two sides of a plane are never in the same assembly.
"""

from __future__ import annotations

import numpy as np
import ufl
from dolfinx import fem, la
from mpi4py import MPI

from pilegroup.geometry import groups
from pilegroup.model import Scenario
from pilegroup.solver import BiotProblem
from pilegroup.solver.forms import FormBuilder
from pilegroup.solver.layout import eps_mandel
from pilegroup.solver.probes import PointSampler

#: Distance (m) within which a node is on a plane (nodes and planes share their coordinates).
Z_TOL = 1e-6
#: A node is on pile ``i`` within its meshed radius times this (piles do not overlap).
RADIUS_FACTOR = 1.001


class PlaneForces:
    """Section actions of every meshed pile at its head and element-layer boundaries.

    Args:
        sc: the scenario (pile positions).
        pb: the problem (the structure's stress, displacement and loads).
        kept: the meshed piles (numbers from 1).
        radii: every pile's meshed circumradius (m;
            :func:`~pilegroup.geometry.plan.meshed_radii`).
    """

    def __init__(self, sc: Scenario, pb: BiotProblem, kept: list[int],
                 radii: list[float]) -> None:
        self.comm = pb.comm
        self.kept = list(kept)
        body = pb.body("structure")  # the whole mesh when tied
        mesh, V = body.mesh, body.V
        xy = [tuple(map(float, p)) for p in sc.piles.xy]
        radius = list(radii)
        D0 = fem.functionspace(mesh, ("DG", 0))
        self._w = fem.Function(D0)
        odd, even, planes = np.zeros(self._w.x.array.size), np.zeros(self._w.x.array.size), {}
        cells_of = {groups.pile_of(g.name): g.cells for g in body.qp.groups}
        for g in body.qp.groups:
            if g.name == groups.CAP:
                odd[g.cells] = 1.0
        for i in self.kept:
            cells = cells_of.get(i, np.zeros(0, np.int32))
            zmin, zmax = _cell_z_range(mesh, cells)
            planes[i] = _planes(self.comm, zmin, zmax)
            layer = np.searchsorted(-planes[i], -np.round(zmax, 6))  # the plane on top: k
            layer = np.where(zmin >= -Z_TOL, -1, layer)  # above the ground: layer -1
            odd[cells[layer % 2 == 1]] = 1.0
            even[cells[layer % 2 == 0]] = 1.0
        self._weights = (odd, even)
        v = ufl.TestFunction(V)
        dx = ufl.Measure("dx", domain=mesh, metadata={"quadrature_degree": body.qp.degree})
        self._form = fem.form(self._w * ufl.inner(body.qp.stress, eps_mandel(v)) * dx)
        self._loads = _head_loads(pb, body)
        n = V.dofmap.index_map.size_local
        self._n = n
        x = V.tabulate_dof_coordinates()[:n]
        #: meshed pile -> plane elevations (m, top down: 0 the head, the last the toe)
        self.planes = planes
        self._nodes: dict[int, list[tuple[np.ndarray, np.ndarray]]] = {}
        pts = []
        for i in self.kept:
            xp, yp = xy[i - 1]
            on = np.hypot(x[:, 0] - xp, x[:, 1] - yp) <= radius[i - 1] * RADIUS_FACTOR + Z_TOL
            self._nodes[i] = []
            for z in planes[i]:
                idx = np.flatnonzero(on & (np.abs(x[:, 2] - z) <= Z_TOL))
                self._nodes[i].append((idx, x[idx] - np.array([xp, yp, z])))
                pts.append((xp, yp, z))
        self._axis = PointSampler(body.u, np.array(pts, dtype=float).reshape(-1, 3))

    def _nodal(self, weight: np.ndarray) -> np.ndarray:
        """The internal force of the cells of ``weight`` at every owned node, ``(n, 3)``."""
        self._w.x.array[:] = weight
        vec = fem.assemble_vector(self._form)
        vec.scatter_reverse(la.InsertMode.add)
        return vec.array[: 3 * self._n].reshape(self._n, 3).copy()

    def __call__(self) -> dict[int, tuple[np.ndarray, np.ndarray, np.ndarray]]:
        """Meshed pile -> (depths, (n, 6) ``Vx, Vy, Fz, Mx, My, T``, (n, 2) ``ux, uy``).

        ``Fz = -N``; depths m below the ground surface, the head (0) first, the toe last;
        deflections of the pile axis at each plane. Collective.
        """
        above = [-self._nodal(w) for w in self._weights]  # force of each side on the nodes
        if self._loads is not None:
            ext = self._loads()
            above[0] = above[0] + ext  # only the head plane has a loaded face among its nodes
        local = []
        for i in self.kept:
            acc = np.zeros((len(self._nodes[i]), 6))
            for k, (idx, arm) in enumerate(self._nodes[i]):
                F = above[k % 2][idx]  # the layer above plane k has index k - 1
                acc[k, :3] = F.sum(axis=0)
                acc[k, 3:] = np.cross(arm, F).sum(axis=0)
            local.append(acc)
        sums = np.split(self.comm.allreduce(np.concatenate(local), op=MPI.SUM),
                        np.cumsum([a.shape[0] for a in local])[:-1])
        u = np.asarray(self._axis()).reshape(-1, 3)
        out, start = {}, 0
        for i, acc in zip(self.kept, sums, strict=True):
            n = acc.shape[0]
            out[i] = (0.0 - self.planes[i], acc, u[start:start + n, :2])
            start += n
        return out


def _cell_z_range(mesh: object, cells: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(lowest, highest) z of the geometry nodes of each of ``cells``."""
    if cells.size == 0:
        return np.zeros(0), np.zeros(0)
    z = mesh.geometry.x[mesh.geometry.dofmaps[0][cells], 2]
    return z.min(axis=1), z.max(axis=1)


def _planes(comm: MPI.Comm, zmin: np.ndarray, zmax: np.ndarray) -> np.ndarray:
    """The element-layer boundaries at and below the ground, top down, over all ranks."""
    z = np.round(np.concatenate([zmin, zmax]), 6)
    allz = np.unique(np.concatenate(comm.allgather(z[z <= Z_TOL])))
    return allz[::-1]


class _HeadLoads:
    """The loads on the pile heads (no cap) as nodal forces of the structure (``(n, 3)``)."""

    def __init__(self, form: fem.Form, pairs: list[tuple[fem.Constant, fem.Constant]],
                 n: int) -> None:
        self.form, self.pairs, self.n = form, pairs, n

    def __call__(self) -> np.ndarray:
        for mine, theirs in self.pairs:
            mine.value = theirs.value
        vec = fem.assemble_vector(self.form)
        vec.scatter_reverse(la.InsertMode.add)
        return -vec.array[: 3 * self.n].reshape(self.n, 3)  # the residual holds -load


def _head_loads(pb: BiotProblem, body: object) -> _HeadLoads | None:
    """The head faces' loads (``None`` with a cap: no load acts on a pile's head plane).

    The same terms as the problem's residual (:meth:`FormBuilder.surface_loads`), their
    amplitudes copied from the problem's at each call.
    """
    heads = set(groups.heads(pb.md.facet_names))
    theirs = [(ld, c) for ld, c in pb.surface_loads if ld.facet in heads]
    if not theirs:
        return None
    fb = FormBuilder(pb.layout, pb.disc, pb.coef)
    mine = fb.surface_loads([ld for ld, _ in theirs])
    form = fem.form(fb.forms.F[pb.layout.block_of(body)], entity_maps=pb.layout.emaps)
    pairs = [(c, d) for (_, c), (_, d) in zip(mine, theirs, strict=True)]
    return _HeadLoads(form, pairs, body.V.dofmap.index_map.size_local)


__all__ = ["PlaneForces"]
