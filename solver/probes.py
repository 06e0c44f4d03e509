"""Probes of a problem's state: facet areas, mean displacements over facet groups, point values.

Every value is all-reduced over ``mesh.comm``; units m and m^2.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np
import ufl
from dolfinx import fem, geometry
from mpi4py import MPI

from pilegroup.geometry.meshdata import MeshData

if TYPE_CHECKING:
    from pilegroup.solver.problem import BiotProblem


def facet_area(md: MeshData, names: Sequence[str], interior: bool = False) -> float:
    """Area (m^2) of the facet groups ``names`` (exterior ``ds``, or interior ``dS``)."""
    kind = "dS" if interior else "ds"
    measure = ufl.Measure(kind, domain=md.mesh, subdomain_data=md.facet_tags)
    form = sum((1.0 * measure(md.facet_tag(n)) for n in names), start=0.0 * measure)
    return md.mesh.comm.allreduce(fem.assemble_scalar(fem.form(form)), op=MPI.SUM)


def face_measure(md: MeshData, names: Sequence[str]) -> ufl.Measure:
    """The exterior measure over the facet groups ``names`` (one face, e.g. the cap top)."""
    ds = ufl.Measure("ds", domain=md.mesh, subdomain_data=md.facet_tags)
    return sum((ds(md.facet_tag(n)) for n in names[1:]), start=ds(md.facet_tag(names[0])))


def face_geometry(md: MeshData, names: Sequence[str], centre: Sequence[float]
                  ) -> tuple[float, float, float]:
    """(area m^2, I_xx, I_yy m^4 about ``centre``) of the meshed facet groups ``names``."""
    face = face_measure(md, names)
    x = ufl.SpatialCoordinate(md.mesh)
    loc = [fem.assemble_scalar(fem.form(f * face)) for f in
           (1.0 + 0.0 * x[0], (x[1] - centre[1]) ** 2, (x[0] - centre[0]) ** 2)]
    area, ixx, iyy = md.mesh.comm.allreduce(np.array(loc), op=MPI.SUM)
    return float(area), float(ixx), float(iyy)


class SettlementProbe:
    """Mean vertical displacement (m, down positive) over exterior facet groups.

    Args:
        problem: a :class:`~pilegroup.solver.problem.BiotProblem`; the groups' displacement is
            that of the body that carries them (:meth:`BiotProblem.body_of_facet`).
        names: exterior facet groups (e.g. the cap top or the pile heads).
    """

    def __init__(self, problem: BiotProblem, names: Sequence[str]) -> None:
        md = problem.md
        body = problem.body_of_facet(names[0])
        em = [body.emap] if body.emap is not None else None
        self._num = fem.form(-body.u[2] * face_measure(md, names), entity_maps=em)
        self._area = facet_area(md, names)
        self._comm = md.mesh.comm

    def __call__(self) -> float:
        """Current settlement, m (down positive), all-reduced."""
        val = fem.assemble_scalar(self._num)
        return self._comm.allreduce(val, op=MPI.SUM) / self._area


class FaceMotion:
    """Rigid-body motion of a plane horizontal face fitted to a body's displacement over it.

    ``(u_x, u_y, u_z, theta_x, theta_y, theta_z)`` (m, rad) about ``centre``: the mean
    displacement over the face, ``theta_x = int (y - y_c) u_z / I_xx``, ``theta_y = -int
    (x - x_c) u_z / I_yy``, ``theta_z = int ((x - x_c) u_y - (y - y_c) u_x) / (I_xx + I_yy)``
    (the least-squares rigid motion of a face with ``I_xy = 0`` about the centre: rectangles
    and regular polygons centred on it). Integrals over the meshed part of the face; in a
    symmetry-reduced mesh the components the mirror planes make zero are not meaningful (the
    caller sets them to zero).
    """

    def __init__(self, problem: BiotProblem, names: Sequence[str],
                 centre: Sequence[float]) -> None:
        md = problem.md
        face = face_measure(md, names)
        body = problem.body_of_facet(names[0])
        em = [body.emap] if body.emap is not None else None
        x, u = ufl.SpatialCoordinate(md.mesh), body.u
        dx_, dy_ = x[0] - centre[0], x[1] - centre[1]
        self._comm = md.mesh.comm
        self._geo = face_geometry(md, names, centre)
        self._forms = [fem.form(f * face, entity_maps=em) for f in
                       (u[0], u[1], u[2], dy_ * u[2], dx_ * u[2], dx_ * u[1] - dy_ * u[0])]

    def _sum(self, forms: Sequence[fem.Form]) -> np.ndarray:
        loc = np.array([fem.assemble_scalar(f) for f in forms])
        return self._comm.allreduce(loc, op=MPI.SUM)

    def __call__(self) -> np.ndarray:
        """The six components (m, rad), all-reduced (collective)."""
        area, ixx, iyy = self._geo
        v = self._sum(self._forms)
        return np.array([v[0] / area, v[1] / area, v[2] / area, v[3] / ixx, -v[4] / iyy,
                         v[5] / (ixx + iyy)])


class PointSampler:
    """Values of a function at fixed points, located once, gathered on every rank.

    Each point is evaluated in one of the cells owned by a rank that contains it; a point that
    lies in cells of several ranks gets the mean of their values, a point in no cell of the
    function's mesh NaN (e.g. a soil point inside a pile on the soil's sub-mesh).

    Args:
        f: the function (its mesh locates the points).
        pts: ``(n, 3)`` points, m.
    """

    def __init__(self, f: fem.Function, pts: np.ndarray) -> None:
        mesh = f.function_space.mesh
        self.f, self.comm = f, mesh.comm
        self.pts = np.asarray(pts, dtype=float).reshape(-1, 3)
        tree = geometry.bb_tree(mesh, mesh.topology.dim)
        cand = geometry.compute_collisions_points(tree, self.pts)
        coll = geometry.compute_colliding_cells(mesh, cand, self.pts)
        nloc = mesh.topology.index_map(mesh.topology.dim).size_local
        self.cells = np.full(self.pts.shape[0], -1, dtype=np.int32)
        for i in range(self.pts.shape[0]):
            cells = coll.links(i)
            cells = cells[cells < nloc]
            if cells.size:
                self.cells[i] = cells[0]
        self.found = self.comm.allreduce((self.cells >= 0).astype(float), op=MPI.SUM)

    def __call__(self) -> np.ndarray:
        """Current values, ``(n, bs)`` squeezed (collective)."""
        bs = self.f.function_space.dofmap.bs
        vals = np.zeros((self.pts.shape[0], bs))
        mine = self.cells >= 0
        if mine.any():
            vals[mine] = self.f.eval(self.pts[mine], self.cells[mine])
        vals = self.comm.allreduce(vals, op=MPI.SUM)
        with np.errstate(invalid="ignore", divide="ignore"):
            out = np.where(self.found[:, None] > 0, vals / self.found[:, None], np.nan)
        return out.squeeze()


def eval_points(f: fem.Function, pts: np.ndarray) -> np.ndarray:
    """Values of ``f`` at the points ``pts`` (``(n, 3)``, m) on every rank (:class:`PointSampler`).

    A point outside the function's mesh gets NaN.
    """
    return PointSampler(f, pts)()
