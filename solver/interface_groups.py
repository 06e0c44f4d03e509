"""The material points of the pile-soil interface, group by group (data, no DOLFINx calls).

A *group* is the interface of one soil layer with the shafts (``m < L``) or with the pile bases
(``m >= L``); it has its own law (that layer's parameters) and state. :class:`NodalGroup` holds
its points at the interface nodes (:class:`~pilegroup.solver.interface.NodalInterface`),
:class:`GaussGroup` at the 2 x 2 Gauss points of its facets
(:class:`~pilegroup.solver.interface_gauss.GaussInterface`). ``state`` is the committed law
state, ``trial`` the state of the step being solved (``None`` for a group without points on
this rank). :class:`InterfacePoints` is what the outputs read of a group's points.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, TypedDict

import numpy as np

#: A law state: named arrays with one row per point (see ``constitutive.interface_law``).
LawState = dict[str, np.ndarray]


@dataclass
class NodalGroup:
    """The points of one interface group at its nodes."""

    nodes: np.ndarray
    """Soil nodes of the group (local numbering), int32."""
    R: np.ndarray
    """``(n, 3, 3)`` local frames: rows normal, vertical t1, circumferential t2 (bases -z, x, y)."""
    w: np.ndarray
    """The group's share of each node's interface area, ``W[i, m] / A_i``."""
    c_n: np.ndarray
    """Factor on the normal traction of a faceted shaft, ``|N_i| / A_i`` (1 on bases)."""
    c_s: float
    """Factor on the shear tractions: ``InterfaceCoupling.shaft_factor`` on shafts, 1 on bases."""
    law: Any
    """The layer's interface law (``constitutive.interface_law.PileSoilInterface``)."""
    state: LawState | None
    trial: LawState | None


@dataclass
class GaussGroup:
    """The points of one interface group at the Gauss points of its facets (Q1)."""

    fnodes: np.ndarray
    """``(nf, 4)`` soil nodes of each facet (local numbering)."""
    dofs_soil: np.ndarray
    """``(nf, 12)`` soil displacement dofs of each facet."""
    dofs_struct: np.ndarray
    """``(nf, 12)`` structure displacement dofs of each facet."""
    wJ: np.ndarray
    """``(nf, 4)`` quadrature weight times the facet Jacobian, m^2."""
    x: np.ndarray
    """``(4 nf, 3)`` coordinates of the Gauss points, m."""
    R: np.ndarray
    """``(4 nf, 3, 3)`` local frames of the points."""
    law: Any
    """The layer's interface law."""
    state: LawState | None
    trial: LawState | None
    c_s: float
    """Factor on the shear tractions (as :attr:`NodalGroup.c_s`)."""
    K: np.ndarray
    """``(nf, 12, 12)`` facet tangents of the last evaluation, kPa m."""


class InterfacePoints(TypedDict):
    """The committed material points of one group, as the outputs read them."""

    weight: np.ndarray
    """Integration weight of each point, m^2, times the group's ``c_s`` (a shaft's point stands
    for its share of the circle's surface); 0 on a rank that does not own the point."""
    x: np.ndarray
    """Coordinates, m."""
    node: np.ndarray
    """A soil node of each point (local numbering)."""
    state: LawState | None
    """The committed law state."""
    jump_local: np.ndarray
    """``[opening, slip1, slip2]`` of each point, m."""
