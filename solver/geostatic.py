"""The geostatic initial state: K0 effective stress of horizontal soil layers.

``sigma'_v(z) = -int_z^{z_top} (gamma_sat - GAMMA_W) dz`` over the soil layers (their elevation
ranges, all-reduced over the ranks), ``sigma'_h = K0 sigma'_v``; ``z_top`` is the highest soil
elevation (water table at the ground surface). Solids ("wished in place") take the stress and
the buoyant weight of the soil layer they replace (zero above ground). Units kPa, m; tension
positive, so the in-situ stresses are negative.

A layer still consolidating starts with an excess pore pressure ``u0(z) >= 0``
(``SoilMaterial.excess_ratio`` of ``-sigma'_v`` or ``excess_kPa``): it carries part of the
weight, so the effective stress is that of the soil at the current stress,
``sigma'_v + u0`` vertically and ``K0 (sigma'_v + u0)`` horizontally, and the total stress
(effective minus ``u0``) is ``sigma'_v`` vertically and ``K0 (sigma'_v + u0) - u0``
horizontally; solids take that total stress, the interface law its effective part (the
excess pore pressure acts on the pile besides the law's traction). Every term depends on ``z``
only, so the state is in equilibrium. ``u0`` is used as the piecewise-linear interpolant
through the pressure nodes' elevations (:meth:`SoilColumn.set_excess_levels`), the same
function the pressure field holds, so that the discrete state starts in equilibrium too.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.inputs import GAMMA_W, ElasticSolid, SoilMaterial
from pilegroup.solver.qpstate import QuadratureState


@dataclass(frozen=True)
class GeostaticLayer:
    """Elevation range (m), buoyant unit weight (kN/m^3) and K0 of one soil group."""

    z_min: float
    z_max: float
    gamma_b: float
    k0: float
    excess_ratio: float = 0.0
    excess_kPa: float = 0.0


class SoilColumn:
    """The soil groups as horizontal layers (collective construction).

    Args:
        md: mesh and tags.
        materials: cell-group name -> material; the :class:`SoilMaterial` groups are the layers.
    """

    def __init__(self, md: MeshData, materials: Mapping[str, SoilMaterial | ElasticSolid]
                 ) -> None:
        comm = md.mesh.comm
        gx = md.mesh.geometry.x
        cdm = md.mesh.geometry.dofmaps[0]
        self.layers: list[GeostaticLayer] = []
        self.by_name: dict[str, GeostaticLayer] = {}
        for name, mat in materials.items():
            if not isinstance(mat, SoilMaterial):
                continue
            cells = md.cell_tags.find(md.cell_tag(name))
            z = gx[cdm[cells].reshape(-1), 2] if cells.size else None
            zmin = comm.allreduce(float(z.min()) if z is not None else np.inf, op=MPI.MIN)
            zmax = comm.allreduce(float(z.max()) if z is not None else -np.inf, op=MPI.MAX)
            layer = GeostaticLayer(zmin, zmax, mat.gamma_sat - GAMMA_W, mat.k0,
                                   mat.excess_ratio, mat.excess_kPa)
            self.layers.append(layer)
            self.by_name[name] = layer
        self.z_top = max(lay.z_max for lay in self.layers) if self.layers else 0.0
        self._levels: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def has_excess(self) -> bool:
        """Whether any layer starts with an excess pore pressure."""
        return any(lay.excess_ratio > 0.0 or lay.excess_kPa > 0.0 for lay in self.layers)

    def excess_at_nodes(self, z: np.ndarray) -> np.ndarray:
        """Initial excess pore pressure (kPa, >= 0) of the layers at elevations ``z`` (m).

        At an elevation shared by two layers the lower layer's rule applies.
        """
        out = np.zeros_like(z)
        sv = -self.sigma_v(z)
        for lay in self.layers:
            inside = (z >= lay.z_min) & (z <= lay.z_max)
            out[inside] = lay.excess_ratio * sv[inside] + lay.excess_kPa
        return out

    def set_excess_levels(self, z_nodes: np.ndarray, comm: MPI.Comm) -> None:
        """Make ``u0`` the interpolant through the pressure nodes' elevations (all ranks)."""
        levels = np.unique(np.concatenate(comm.allgather(np.round(z_nodes, 9))))
        self._levels = (levels, self.excess_at_nodes(levels))

    def excess(self, z: np.ndarray) -> np.ndarray:
        """Initial excess pore pressure (kPa) at elevations ``z``: the nodal interpolant."""
        if not self.has_excess:
            return np.zeros_like(z)
        if self._levels is None:
            raise RuntimeError("SoilColumn.set_excess_levels was not called")
        return np.interp(z, *self._levels)

    def sigma_v(self, z: np.ndarray) -> np.ndarray:
        """Vertical geostatic effective stress (kPa, negative) at elevations ``z`` (m)."""
        s = np.zeros_like(z)
        for lay in self.layers:
            s -= lay.gamma_b * np.clip(np.minimum(lay.z_max, self.z_top)
                                       - np.maximum(lay.z_min, z), 0.0, None)
        return s

    def buoyant_weight(self, z: np.ndarray) -> np.ndarray:
        """Buoyant unit weight (kN/m^3) of the layer at each elevation (0 outside every layer)."""
        return self._value(z, "gamma_b")

    def k0(self, z: np.ndarray) -> np.ndarray:
        """K0 of the layer at each elevation (0 outside every layer)."""
        return self._value(z, "k0")

    def _value(self, z: np.ndarray, key: str) -> np.ndarray:
        out = np.zeros_like(z)
        for lay in self.layers:
            out[(z >= lay.z_min) & (z <= lay.z_max)] = getattr(lay, key)
        return out

    def stress(self, states: Sequence[QuadratureState]) -> dict[str, np.ndarray]:
        """K0 effective stress at the quadrature points of each group (Mandel, kPa)."""
        out = {}
        for g in (g for qp in states for g in qp.groups):
            z = g.x[:, 2]
            sv, u0 = self.sigma_v(z), self.excess(z)
            s = np.zeros((g.n, 6))
            if isinstance(g.material, SoilMaterial):  # effective stress
                s[:, 0] = s[:, 1] = g.material.k0 * (sv + u0)
                s[:, 2] = sv + u0
            else:  # a solid takes the total stress of the soil it replaces
                s[:, 0] = s[:, 1] = self.k0(z) * (sv + u0) - u0
                s[:, 2] = sv
            out[g.name] = s
        return out

    def interface_traction(self, z: np.ndarray, soil_group: str | None) -> np.ndarray:
        """In-situ local interface traction ``[sigma_n, 0, 0]`` (kPa) at heights ``z``.

        The interface law carries the effective traction (the excess pore pressure acts on the
        pile besides it, ``solver/forms.py::interface``): shafts (``soil_group`` the adjacent
        soil layer) ``K0 (sigma'_v + u0)``, bases (``soil_group = None``) ``sigma'_v + u0``.
        """
        sv, u0 = self.sigma_v(z), self.excess(z)
        t = np.zeros((z.size, 3))
        if soil_group is None:
            t[:, 0] = sv + u0
        else:
            layer = self.by_name.get(soil_group)
            t[:, 0] = (layer.k0 if layer is not None else self.k0(z)) * (sv + u0)
        return t
