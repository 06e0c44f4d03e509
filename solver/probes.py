"""Scalar probes of a problem's state: facet areas and mean displacements over facet groups.

Every value is all-reduced over ``mesh.comm``; units m and m^2.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import TYPE_CHECKING

import ufl
from dolfinx import fem
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


class SettlementProbe:
    """Mean vertical displacement (m, down positive) over exterior facet groups.

    Args:
        problem: a :class:`~pilegroup.solver.problem.BiotProblem`; the groups' displacement is
            that of the body that carries them (:meth:`BiotProblem.body_of_facet`).
        names: exterior facet groups (e.g. the cap top or the pile heads).
    """

    def __init__(self, problem: BiotProblem, names: Sequence[str]) -> None:
        md = problem.md
        ds = ufl.Measure("ds", domain=md.mesh, subdomain_data=md.facet_tags)
        area = sum((ds(md.facet_tag(n)) for n in names[1:]), start=ds(md.facet_tag(names[0])))
        body = problem.body_of_facet(names[0])
        em = [body.emap] if body.emap is not None else None
        self._num = fem.form(-body.u[2] * area, entity_maps=em)
        self._area = facet_area(md, names)
        self._comm = md.mesh.comm

    def __call__(self) -> float:
        """Current settlement, m (down positive), all-reduced."""
        val = fem.assemble_scalar(self._num)
        return self._comm.allreduce(val, op=MPI.SUM) / self._area
