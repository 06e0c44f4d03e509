"""The geostatic initial state: K0 effective stress of horizontal soil layers.

``sigma'_v(z) = -int_z^{z_top} w dz`` over the soil layers (their elevation ranges, all-reduced
over the ranks), ``sigma'_h = K0 sigma'_v``; ``z_top`` is the highest soil elevation. The
skeleton's weight ``w`` is the buoyant ``gamma_sat - GAMMA_W`` below the water table
(elevation ``z_w``, ``z_top`` unless given) and the total ``gamma_unsat`` above it, where the
soil is dry: the hydrostatic pore pressure ``GAMMA_W (z_w - z)`` below it and none above,
taken off the total stress, leave that effective stress (docs/model.md, "The ground at rest").
Solids ("wished in place") take the stress and the weight of the soil layer they replace (zero
above ground). Units kPa, m; tension positive, so the in-situ stresses are negative.

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

The piles' installation adds an excess pore pressure ``u_i(x)`` around each shaft
(:class:`~pilegroup.solver.inputs.InstallationExcess`: a fraction of ``|sigma'_v|`` at the
shaft, shaped by the cavity expansion's logarithm). The total stress is held: the
effective stress of the soil is less compressive by ``u_i`` in every direction, solids keep
their total stress and the interface law starts at the effective traction less ``u_i``. The
soil's share is evaluated at the quadrature points as the pressure space's interpolant of
``u_i`` (passed to :meth:`SoilColumn.stress`), so this state too is in discrete equilibrium.
Both excess pore pressures are zero at and above the water table (dry soil, its drained
boundary). Layers held at a head of their own (under-drained or artesian) make the water seep
steadily between them and the water table: that pore pressure above the hydrostatic one
(``seepage``, either sign) is part of ``u0``, so the effective stress follows it.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from mpi4py import MPI

from pilegroup.errors import SolverInputError
from pilegroup.geometry.meshdata import MeshData
from pilegroup.solver.inputs import GAMMA_W, ElasticSolid, InstallationExcess, SoilMaterial
from pilegroup.solver.qpstate import QuadratureState

#: Elevations within this distance (m) of the water table are on it.
Z_TOL = 1e-6
#: Relative size of a positive in-situ interface normal traction taken as round-off (zero).
ROUND_OFF = 1e-12


@dataclass(frozen=True)
class GeostaticLayer:
    """One soil group: elevations (m), unit weights (kN/m^3), K0, initial excess pressure.

    ``gamma_b`` is the buoyant unit weight, ``gamma_dry`` the total one above the water table.
    """

    z_min: float
    z_max: float
    gamma_b: float
    k0: float
    excess_ratio: float = 0.0
    excess_kPa: float = 0.0
    gamma_dry: float = 0.0


class SoilColumn:
    """The soil groups as horizontal layers (collective construction).

    Args:
        md: mesh and tags.
        materials: cell-group name -> material; the :class:`SoilMaterial` groups are the layers.
        installation: the piles' installation pore pressures (None: none).
        water_table: elevation (m) of the water table; None: the top of the soil.
        seepage: ``(elevation m, kPa)`` points of a pore pressure at rest above the hydrostatic
            one, linear between them (steady seepage towards layers held at a head of their
            own): part of the initial excess pore pressure ``u0``.
    """

    def __init__(self, md: MeshData, materials: Mapping[str, SoilMaterial | ElasticSolid],
                 installation: InstallationExcess | None = None,
                 water_table: float | None = None,
                 seepage: Sequence[tuple[float, float]] = ()) -> None:
        self.installation = installation
        pts = sorted(seepage)
        self.seepage = (np.array([z for z, _ in pts]), np.array([u for _, u in pts]))
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
            dry = mat.gamma_sat if mat.gamma_unsat is None else mat.gamma_unsat
            layer = GeostaticLayer(zmin, zmax, mat.gamma_sat - GAMMA_W, mat.k0,
                                   mat.excess_ratio, mat.excess_kPa, dry)
            self.layers.append(layer)
            self.by_name[name] = layer
        self.z_top = max(lay.z_max for lay in self.layers) if self.layers else 0.0
        self.z_w = self.z_top if water_table is None else min(float(water_table), self.z_top)
        self._levels: tuple[np.ndarray, np.ndarray] | None = None

    @property
    def has_dry(self) -> bool:
        """Whether the water table lies below the top of the soil (dry soil above it)."""
        return self.z_w < self.z_top - Z_TOL

    def wet(self, z: np.ndarray) -> np.ndarray:
        """Whether each elevation ``z`` (m) is below the water table.

        On it: not, unless the water table is the top of the soil (then every elevation is).
        """
        z = np.asarray(z)
        return z < self.z_w - Z_TOL if self.has_dry else np.ones(z.shape, dtype=bool)

    @property
    def has_excess(self) -> bool:
        """Whether any layer starts with an excess pore pressure (or seepage)."""
        return bool(np.any(self.seepage[1] != 0.0)) or any(
            lay.excess_ratio > 0.0 or lay.excess_kPa > 0.0 for lay in self.layers)

    def excess_at_nodes(self, z: np.ndarray) -> np.ndarray:
        """Initial excess pore pressure (kPa) at elevations ``z`` (m).

        The layers' own (>= 0; at an elevation shared by two layers the lower layer's rule
        applies) plus the seepage at rest (either sign); 0 at and above the water table.
        """
        out = np.zeros_like(z)
        sv = -self.sigma_v(z)
        for lay in self.layers:
            inside = (z >= lay.z_min) & (z <= lay.z_max)
            out[inside] = lay.excess_ratio * sv[inside] + lay.excess_kPa
        if self.seepage[0].size:
            out += np.interp(z, *self.seepage)
        return np.where(self.wet(z), out, 0.0)

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

    def installation_excess(self, x: np.ndarray) -> np.ndarray:
        """Installation excess pore pressure (kPa, >= 0) at points ``x`` ((n, 3), m)."""
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        if self.installation is None:
            return np.zeros(x.shape[0])
        u = self.installation.ratio * -self.sigma_v(x[:, 2]) * self.installation.shape(x)
        return np.where(self.wet(x[:, 2]), u, 0.0)

    def check_installation(self, x: np.ndarray, comm: MPI.Comm) -> None:
        """The installation leaves the horizontal effective stress compressive at points ``x``.

        ``u_i < K0 |sigma'_v + u0|`` at every pressure node; else :class:`SolverInputError`
        naming the largest ratio ``u_i / (K0 |sigma'_v + u0|)`` and where (collective).
        """
        if self.installation is None:
            return
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        ui = self.installation_excess(x)
        z = np.clip(x[:, 2], min(lay.z_min for lay in self.layers), self.z_top)  # round-off
        room = self.k0(z) * -(self.sigma_v(z) + self.excess(z))
        with np.errstate(divide="ignore", invalid="ignore"):
            q = np.where(ui > 0.0, ui / room, 0.0)
        q = np.where((ui > 0.0) & (room <= 0.0), np.inf, q)
        k = int(np.argmax(q)) if q.size else -1
        worst = (float(q[k]), *map(float, x[k])) if k >= 0 else (0.0, 0.0, 0.0, 0.0)
        worst = max(comm.allgather(worst))
        if worst[0] >= 1.0:
            raise SolverInputError(
                f"piles.installation.excess_pore_pressure_ratio = {self.installation.ratio:g}:"
                f" the installation pore pressure reaches {worst[0]:.3g} times the horizontal"
                f" effective stress K0 |sigma'_v| at x = {worst[1]:.3g}, y = {worst[2]:.3g},"
                f" z = {worst[3]:.3g} m (the fields of neighbouring piles add up); allowed: < 1"
                " everywhere (the soil would start with tensile effective stress)")

    def sigma_v(self, z: np.ndarray) -> np.ndarray:
        """Vertical geostatic effective stress (kPa, negative) at elevations ``z`` (m)."""
        s = np.zeros_like(z)
        for lay in self.layers:
            top, low = min(lay.z_max, self.z_top), np.maximum(lay.z_min, z)
            s -= lay.gamma_b * np.clip(np.minimum(top, self.z_w) - low, 0.0, None)
            s -= lay.gamma_dry * np.clip(top - np.maximum(low, self.z_w), 0.0, None)
        return s

    def skeleton_weight(self, z: np.ndarray) -> np.ndarray:
        """Unit weight (kN/m^3) the skeleton carries at each elevation (0 outside every layer).

        The layer's buoyant one below the water table, its total one above.
        """
        if not self.has_dry:
            return self._value(z, "gamma_b")
        return np.where(self.wet(z), self._value(z, "gamma_b"), self._value(z, "gamma_dry"))

    def k0(self, z: np.ndarray) -> np.ndarray:
        """K0 of the layer at each elevation (0 outside every layer)."""
        return self._value(z, "k0")

    def _value(self, z: np.ndarray, key: str) -> np.ndarray:
        out = np.zeros_like(z)
        for lay in self.layers:
            out[(z >= lay.z_min) & (z <= lay.z_max)] = getattr(lay, key)
        return out

    def stress(self, states: Sequence[QuadratureState],
               installation: Mapping[str, np.ndarray] | None = None) -> dict[str, np.ndarray]:
        """K0 effective stress at the quadrature points of each group (Mandel, kPa).

        ``installation[name]``: the installation excess pore pressure at the group's points
        (the pressure space's interpolant), taken off the soil's effective stress.
        """
        out = {}
        for g in (g for qp in states for g in qp.groups):
            z = g.x[:, 2]
            sv, u0 = self.sigma_v(z), self.excess(z)
            s = np.zeros((g.n, 6))
            if isinstance(g.material, SoilMaterial):  # effective stress
                s[:, 0] = s[:, 1] = g.material.k0 * (sv + u0)
                s[:, 2] = sv + u0
                if installation is not None and g.name in installation:
                    s[:, :3] += installation[g.name][:, None]
            else:  # a solid takes the total stress of the soil it replaces
                s[:, 0] = s[:, 1] = self.k0(z) * (sv + u0) - u0
                s[:, 2] = sv
            out[g.name] = s
        return out

    def interface_traction(self, x: np.ndarray, z: np.ndarray, soil_group: str | None
                           ) -> np.ndarray:
        """In-situ local interface traction ``[sigma_n, 0, 0]`` (kPa) at points ``x`` ((n, 3)).

        The interface law carries the effective traction, the soil's total traction plus the
        excess pore pressure, which acts on the pile beside it (``solver/forms.py::interface``):
        shafts (``soil_group`` the adjacent soil layer) ``K0 (sigma'_v + u0) + u_i``, bases
        (``soil_group = None``) ``sigma'_v + u0 + u_i`` (``u0`` the layers', ``u_i`` the
        installation's excess pore pressure). The total traction, linear in depth, is taken at
        the heights ``z`` (the interface's weighted heights: a consistent resultant), the excess
        pore pressure at the points ``x`` themselves, where the interface integrates the
        pressure beside the law, so that the two cancel in the discrete equilibrium too.
        """
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        z = np.asarray(z, dtype=float)
        sv, u0, u0_x = self.sigma_v(z), self.excess(z), self.excess(x[:, 2])
        t = np.zeros((z.size, 3))
        if soil_group is None:
            t[:, 0] = sv + u0_x
        else:
            layer = self.by_name.get(soil_group)
            k0 = layer.k0 if layer is not None else self.k0(z)
            t[:, 0] = k0 * (sv + u0) - u0 + u0_x
        t[:, 0] += self.installation_excess(x)
        # at the ground surface sigma'_v and u_i are both 0, their sum positive by round-off
        # (2.8e-17 kPa on the pier's Q2-Q1 mesh): no tension, which the law would refuse
        tiny = ROUND_OFF * max(float(np.max(np.abs(t[:, 0]), initial=0.0)), 1.0)
        t[(t[:, 0] > 0.0) & (t[:, 0] <= tiny), 0] = 0.0
        return t
