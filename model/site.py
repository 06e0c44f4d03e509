"""The ground and what stands in it: soil block, layers, piles, cap, structural material.

Field names are the TOML keys, so they carry their unit (``E_MPa``, ``k_m_per_day``); properties
without a unit suffix return internal units (kN, m, day; stresses in kPa). Validation happens
when a dataclass is built (:mod:`pilegroup.validate`); errors are
:class:`~pilegroup.errors.ScenarioError` naming the key, value, unit and what is allowed.
Geometry: plan centred at x = y = 0, ground surface z = 0, z up; the cap sits on the ground
surface, centred on the plan origin.

A layer's interface friction angle defaults to the paper's Eq. 17, which lives with the laws in
:mod:`pilegroup.constitutive.paper`: the model's one import from ``constitutive``, a pure
formula on floats (no numpy, no law), so that the formula is written once.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

from pilegroup.constitutive.paper import delta_eq17
from pilegroup.errors import ScenarioError
from pilegroup.model.bounds import check_bound
from pilegroup.model.units import KPA_PER_MPA, unit_weight_from_density
from pilegroup.validate import (
    require_finite,
    require_in_range,
    require_non_negative,
    require_positive,
)

#: At most this many piles: the mesh names its pile groups ``pile_1`` .. ``pile_99``
#: (``pilegroup.geometry.groups``), and the overlap check is quadratic in the count.
MAX_PILES = 99


def _require_friction_angle(key: str, value: float) -> None:
    require_in_range(key, value, 0.0, 60.0, "degree", hi_open=True)


class _ElasticMPa:
    """Elastic constants given as ``E_MPa`` and ``nu``: their checks and ``E`` in kPa."""

    E_MPa: float
    nu: float

    def _check_elastic(self, table: str) -> None:
        require_positive("E_MPa", self.E_MPa, "MPa")
        check_bound(f"{table}.E_MPa", self.E_MPa)
        require_in_range("nu", self.nu, 0.0, 0.5, "-", lo_open=True, hi_open=True)

    @property
    def E(self) -> float:
        """Young's modulus in kPa."""
        return self.E_MPa * KPA_PER_MPA


@dataclass(frozen=True)
class InterfaceParams:
    """Pile-soil interface parameters of one soil layer (paper Table 1, Eqs. 5-17).

    ``eta_MPa_day`` is read as MPa·day per metre of slip (docs/model.md, item 3), so that
    the slip rate of the zero-thickness interface is in m/day. ``base_bearing_kPa``: the
    ultimate base resistance of a pile whose toe stands in this layer (the largest compressive
    normal stress of its base interface, kPa; docs/model.md, "Capacity"); absent: the soil below
    the toe alone limits it.
    """

    K: float
    n: float
    R_f: float
    eta_MPa_day: float
    delta_deg: float | None = None
    base_bearing_kPa: float | None = None

    def __post_init__(self) -> None:
        require_positive("K", self.K, "-")
        check_bound("layers.interface.K", self.K)
        require_non_negative("n", self.n, "-")
        check_bound("layers.interface.n", self.n)
        require_in_range("R_f", self.R_f, 0.0, 1.0, "-", hi_open=True)
        require_positive("eta_MPa_day", self.eta_MPa_day, "MPa·day/m")
        check_bound("layers.interface.eta_MPa_day", self.eta_MPa_day)
        if self.delta_deg is not None:
            _require_friction_angle("delta_deg", self.delta_deg)
        if self.base_bearing_kPa is not None:
            require_positive("base_bearing_kPa", self.base_bearing_kPa, "kPa")
            check_bound("layers.interface.base_bearing_kPa", self.base_bearing_kPa)

    @property
    def eta(self) -> float:
        """Viscosity in kPa·day/m."""
        return self.eta_MPa_day * KPA_PER_MPA


@dataclass(frozen=True)
class Layer(_ElasticMPa):
    """One horizontal soil layer (paper Table 1). The last layer may omit ``thickness_m``."""

    name: str
    """Free text, e.g. ``"Mud"``."""
    gamma_kN_per_m3: float
    """Saturated soil unit weight, kN/m^3 (Table 1's "water unit weight", docs/model.md, item 6)."""
    E_MPa: float
    """Young's modulus of the soil skeleton, MPa."""
    nu: float
    """Poisson's ratio, in (0, 0.5)."""
    phi_deg: float
    """Friction angle, degrees, in [0, 60)."""
    c_kPa: float
    """Cohesion, kPa."""
    k_m_per_day: float
    """Hydraulic conductivity, m/day (the vertical one when ``k_h_m_per_day`` is given).

    Table 1's permeability column is read as 10^-6 cm/s (docs/model.md, item 5).
    """
    e0: float
    """Initial void ratio."""
    thickness_m: float | None = None
    """Thickness, m; the last layer may omit it and then reaches the block bottom."""
    psi_deg: float = 0.0
    """Dilatancy angle, degrees, in [0, phi_deg]."""
    k_h_m_per_day: float | None = None
    """Horizontal hydraulic conductivity, m/day; None: equal to ``k_m_per_day``."""
    interface: InterfaceParams | None = None
    """Pile-soil interface parameters; needed where the piles cross the layer (not tied)."""
    excess_pore_pressure_ratio: float = 0.0
    """Excess pore pressure at the start, as a fraction of the vertical effective stress it will
    carry once dissipated, in [0, 1): a layer still consolidating (under-consolidated)."""
    excess_pore_pressure_kPa: float = 0.0
    """Excess pore pressure at the start, kPa, uniform over the layer (e.g. from an earlier
    fill); at most the vertical effective stress at the layer's top. Not with the ratio."""
    drained: bool = False
    """An aquifer: its pore water drains to far away (a sand or gravel layer open to the
    region), so its excess pore pressure stays the water table's (0, or that of a lowered
    water table): the layers around it consolidate towards it."""

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise ScenarioError("name", self.name, "must be a non-empty string")
        if self.thickness_m is not None:
            require_positive("thickness_m", self.thickness_m, "m")
            check_bound("layers.thickness_m", self.thickness_m)
        require_positive("gamma_kN_per_m3", self.gamma_kN_per_m3, "kN/m^3")
        check_bound("layers.gamma_kN_per_m3", self.gamma_kN_per_m3)
        self._check_elastic("layers")
        _require_friction_angle("phi_deg", self.phi_deg)
        require_non_negative("c_kPa", self.c_kPa, "kPa")
        check_bound("layers.c_kPa", self.c_kPa)
        if not 0.0 <= self.psi_deg <= self.phi_deg:
            raise ScenarioError("psi_deg", self.psi_deg,
                                f"must be in [0, phi_deg = {self.phi_deg}]", "degree")
        for key in ("k_m_per_day", "k_h_m_per_day", "e0"):
            if getattr(self, key) is not None:
                require_positive(key, getattr(self, key), "-" if key == "e0" else "m/day")
                check_bound(f"layers.{key}", getattr(self, key))
        require_non_negative("excess_pore_pressure_kPa", self.excess_pore_pressure_kPa, "kPa")
        check_bound("layers.excess_pore_pressure_kPa", self.excess_pore_pressure_kPa)
        require_non_negative("excess_pore_pressure_ratio", self.excess_pore_pressure_ratio, "-")
        check_bound("layers.excess_pore_pressure_ratio", self.excess_pore_pressure_ratio)
        if self.excess_pore_pressure_ratio > 0.0 and self.excess_pore_pressure_kPa > 0.0:
            raise ScenarioError("excess_pore_pressure_kPa", self.excess_pore_pressure_kPa,
                                "give either excess_pore_pressure_ratio or"
                                " excess_pore_pressure_kPa, not both", "kPa")

    @property
    def porosity(self) -> float:
        """Porosity n = e0 / (1 + e0)."""
        return self.e0 / (1.0 + self.e0)

    @property
    def K0(self) -> float:
        """Earth pressure coefficient at rest, Jaky: 1 - sin(phi)."""
        return 1.0 - math.sin(math.radians(self.phi_deg))

    @property
    def k_h(self) -> float:
        """Horizontal permeability in m/day (isotropic unless ``k_h_m_per_day`` is given)."""
        return self.k_m_per_day if self.k_h_m_per_day is None else self.k_h_m_per_day

    @property
    def delta_deg(self) -> float:
        """Interface friction angle: Table 1 value if given, else Eq. 17 from phi."""
        if self.interface is not None and self.interface.delta_deg is not None:
            return self.interface.delta_deg
        return delta_eq17(self.phi_deg)


@dataclass(frozen=True)
class _PlanRectangle:
    """A rectangle in plan centred on the origin, ``size_x_m`` x ``size_y_m`` (m)."""

    size_x_m: float
    size_y_m: float

    def _check_plan_size(self, table: str) -> None:
        for key in ("size_x_m", "size_y_m"):
            require_positive(key, getattr(self, key), "m")
            check_bound(f"{table}.{key}", getattr(self, key))


@dataclass(frozen=True)
class Site(_PlanRectangle):
    """The soil block: plan size, depth, water table (depth below ground, m)."""

    depth_m: float
    water_table_depth_m: float = 0.0

    def __post_init__(self) -> None:
        self._check_plan_size("site")
        require_positive("depth_m", self.depth_m, "m")
        check_bound("site.depth_m", self.depth_m)
        require_non_negative("water_table_depth_m", self.water_table_depth_m, "m")
        if self.water_table_depth_m > self.depth_m:
            raise ScenarioError("water_table_depth_m", self.water_table_depth_m,
                                f"must be <= depth_m = {self.depth_m}", "m")
        if self.water_table_depth_m != 0.0:
            raise ScenarioError("water_table_depth_m", self.water_table_depth_m,
                                "only 0 (the water table at the ground surface) is modelled; a "
                                "water table lowered after the start is a groundwater stage "
                                "(docs/model.md, 'Ground that moves')", "m")


@dataclass(frozen=True)
class Installation:
    """Excess pore pressure the piles' installation leaves in the soil around each shaft.

    Cylindrical cavity expansion (docs/model.md, "Installation pore pressures"): at a distance
    ``r`` from a pile's axis, ``u = u_s ln(R/r) / ln(R/r0)`` for ``r0 <= r <= R`` (``r0`` the
    pile radius, ``R = radius_ratio r0``), 0 beyond and below the toe; the fields of the piles
    add up. At the shaft ``u_s = excess_pore_pressure_ratio x sigma'_v``: the undrained
    strength of a normally consolidated clay, and with it the cavity pressure, grows with the
    vertical effective stress.
    """

    excess_pore_pressure_ratio: float
    """``u_s / sigma'_v`` at the shaft, in (0, 1)."""
    radius_ratio: float
    """``R / r0``: the radius of the disturbed zone over the pile radius (> 1)."""

    def __post_init__(self) -> None:
        require_positive("excess_pore_pressure_ratio", self.excess_pore_pressure_ratio, "-")
        check_bound("piles.installation.excess_pore_pressure_ratio",
                    self.excess_pore_pressure_ratio)
        require_finite("radius_ratio", self.radius_ratio, "-")
        check_bound("piles.installation.radius_ratio", self.radius_ratio)


#: Words that mark a key of a layout entry as a rake (batter) of the pile: rejected with their
#: own message, since every pile of the model is vertical.
RAKE_WORDS = ("rake", "batter", "inclin", "tilt", "angle", "azimuth")


def _check_pile_size(table: str, diameter: float | None, length: float | None) -> None:
    """A pile's ``diameter_m`` and ``length_in_soil_m``, where given: positive, in bounds."""
    for key, value in (("diameter_m", diameter), ("length_in_soil_m", length)):
        if value is not None:
            require_positive(key, value, "m")
            check_bound(f"{table}.{key}", value)


@dataclass(frozen=True)
class LayoutPile:
    """One entry of ``piles.layout``: a vertical pile at ``(x_m, y_m)`` (m, plan coordinates).

    ``diameter_m`` and ``length_in_soil_m`` (m) are the pile's own; an omitted one is the
    ``[piles]``-level value of the same name. Raked (battered) piles are not modelled: a key
    giving a rake is rejected (:meth:`unknown_key_message`).
    """

    x_m: float
    y_m: float
    diameter_m: float | None = None
    length_in_soil_m: float | None = None

    def __post_init__(self) -> None:
        require_finite("x_m", self.x_m, "m")
        require_finite("y_m", self.y_m, "m")
        _check_pile_size("piles.layout", self.diameter_m, self.length_in_soil_m)

    @classmethod
    def unknown_key_message(cls, key: str) -> str:
        """What the loader says of an unknown key ``key`` in a layout entry.

        A key naming a rake or batter (:data:`RAKE_WORDS`, e.g. ``rake_deg``, ``batter``,
        ``inclination_deg``) says that raked piles are not supported; any other says so too,
        after the allowed keys, so that nobody reads a silently dropped key as a raked pile.
        """
        allowed = "allowed keys: " + ", ".join(f.name for f in dataclasses.fields(cls))
        if any(w in key.lower() for w in RAKE_WORDS):
            return (f"raked piles are not supported: every pile is vertical (no rake or batter"
                    f" can be given); {allowed}")
        return f"unknown key; {allowed} (vertical piles only: raked piles are not supported)"


@dataclass(frozen=True)
class Piles:
    """The piles: a regular grid centred on the cap, explicit positions, or an explicit layout.

    Exactly one of: ``grid`` [nx, ny] with ``spacing_m`` [sx, sy]; ``positions_m`` [[x, y],
    ...] (m, plan coordinates); ``layout``, a list of :class:`LayoutPile` tables, each pile
    with its own position and, optionally, its own diameter and length in soil. With ``grid``
    or ``positions_m`` every pile has ``diameter_m`` and ``length_in_soil_m``; with ``layout``
    these are the defaults of the entries that omit them (and may be left out when every entry
    gives its own). The embedment in the cap is one for all piles.

    Piles are numbered from 1 in the order :attr:`xy` lists them; :attr:`diameters` and
    :attr:`lengths` are aligned with it. Two piles must not overlap: the distance between their
    centres is at least the mean of their two diameters (their cross-sections may touch).
    """

    diameter_m: float | None = None
    length_in_soil_m: float | None = None
    embedment_m: float = 0.0
    grid: tuple[int, int] | None = None
    spacing_m: tuple[float, float] | None = None
    positions_m: tuple[tuple[float, float], ...] | None = None
    layout: tuple[LayoutPile, ...] | None = None
    installation: Installation | None = None
    """Installation pore pressures present at the start (None: wished in place, no excess)."""

    def __post_init__(self) -> None:
        _check_pile_size("piles", self.diameter_m, self.length_in_soil_m)
        require_non_negative("embedment_m", self.embedment_m, "m")
        self._check_layout()
        self._check_sizes()
        self._check_overlap()

    def _layout_key(self) -> str:
        """The key that places the piles: ``layout``, ``positions_m`` or ``grid``."""
        if self.layout is not None:
            return "layout"
        return "positions_m" if self.positions_m is not None else "grid"

    def _check_layout(self) -> None:
        """Exactly one of grid, positions_m and layout; finite positions; at most MAX_PILES."""
        given = [k for k, v in (("grid", self.grid), ("positions_m", self.positions_m),
                                ("layout", self.layout)) if v is not None]
        if len(given) > 1:
            later = given[-1]
            n = len(getattr(self, later))
            raise ScenarioError(later, f"{n} entries", "give exactly one of grid (with"
                                " spacing_m), positions_m or layout; here also "
                                + " and ".join(given[:-1]))
        if self.spacing_m is not None and self.grid is None and given:
            raise ScenarioError("spacing_m", list(self.spacing_m),
                                f"goes with grid only: leave it out with {given[0]}", "m")
        if self.layout is not None:
            if len(self.layout) == 0:
                raise ScenarioError("layout", [], "must list at least one pile")
        elif self.positions_m is not None:
            if len(self.positions_m) == 0:
                raise ScenarioError("positions_m", [], "must list at least one pile", "m")
            for i, xy in enumerate(self.positions_m):
                for j, v in enumerate(xy):
                    require_finite(f"positions_m[{i}][{j}]", v, "m")
        else:
            if self.grid is None:
                raise ScenarioError("grid", None, "missing: give grid = [nx, ny] with spacing_m,"
                                    " positions_m or layout")
            for i, v in enumerate(self.grid):
                if v < 1:
                    raise ScenarioError(f"grid[{i}]", v, "must be an integer >= 1")
            if self.spacing_m is None:
                if any(v > 1 for v in self.grid):
                    raise ScenarioError("spacing_m", None, "missing: required when grid > 1x1",
                                        "m")
            else:
                for i, v in enumerate(self.spacing_m):
                    require_positive(f"spacing_m[{i}]", v, "m")
        n = self.count
        if n > MAX_PILES:
            raise ScenarioError(self._layout_key(), n,
                                f"at most {MAX_PILES} piles (the mesh names pile_1 .. "
                                f"pile_{MAX_PILES})", "-")

    def _check_sizes(self) -> None:
        """Every pile has a diameter and a length: its own (layout) or the ``[piles]`` one."""
        for key in ("diameter_m", "length_in_soil_m"):
            if getattr(self, key) is not None:
                continue
            if self.layout is None:
                raise ScenarioError(key, None, f"missing key; expected a number (with"
                                    f" {self._layout_key()} every pile has this {key}; a layout"
                                    " may give each pile its own)", "m")
            for i, entry in enumerate(self.layout):
                if getattr(entry, key) is None:
                    raise ScenarioError(f"layout[{i}].{key}", None,
                                        f"missing: give {key} in this entry, or piles.{key} as"
                                        " the value of every entry that omits it", "m")

    def _check_overlap(self) -> None:
        """No two pile cross-sections overlap: centre distance >= the mean of the diameters."""
        xy, d = self.xy, self.diameters
        for i in range(len(xy)):
            for j in range(i):
                dist = math.dist(xy[i], xy[j])
                least = 0.5 * (d[i] + d[j])
                if dist < least:
                    key = {"layout": f"layout[{i}]", "positions_m": "positions_m",
                           "grid": "spacing_m"}[self._layout_key()]
                    raise ScenarioError(
                        key, [list(xy[j]), list(xy[i])],
                        f"piles {j + 1} and {i + 1} overlap: centre distance {dist:g} m must be"
                        f" >= the mean of their diameters ({d[j]:g} + {d[i]:g}) / 2 ="
                        f" {least:g} m", "m")

    @property
    def xy(self) -> tuple[tuple[float, float], ...]:
        """Plan positions (m) of every pile, numbered from 1.

        In the order of ``layout`` or ``positions_m``; a grid row by row (x fastest).
        """
        if self.layout is not None:
            return tuple((float(e.x_m), float(e.y_m)) for e in self.layout)
        if self.positions_m is not None:
            return tuple((float(x), float(y)) for x, y in self.positions_m)
        nx, ny = self.grid  # type: ignore[misc]
        sx, sy = self.spacing_m if self.spacing_m is not None else (0.0, 0.0)
        return tuple(((i - (nx - 1) / 2) * sx, (j - (ny - 1) / 2) * sy)
                     for j in range(ny) for i in range(nx))

    def _per_pile(self, key: str) -> tuple[float, ...]:
        default = getattr(self, key)
        if self.layout is None:
            return (float(default),) * self.count
        return tuple(float(default if getattr(e, key) is None else getattr(e, key))
                     for e in self.layout)

    @property
    def diameters(self) -> tuple[float, ...]:
        """Diameter (m) of every pile, aligned with :attr:`xy` (pile ``i`` at index ``i - 1``)."""
        return self._per_pile("diameter_m")

    @property
    def lengths(self) -> tuple[float, ...]:
        """Length in soil (m) of every pile, aligned with :attr:`xy`."""
        return self._per_pile("length_in_soil_m")

    def key_of(self, i: int, key: str) -> str:
        """The scenario key that sets ``key`` of pile ``i`` (1-based), for messages.

        ``key`` is ``diameter_m`` or ``length_in_soil_m``; the answer is
        ``piles.layout[i - 1].<key>`` when that entry gives it, else ``piles.<key>``.
        """
        if self.layout is not None and getattr(self.layout[i - 1], key) is not None:
            return f"piles.layout[{i - 1}].{key}"
        return f"piles.{key}"

    @property
    def count(self) -> int:
        """Number of piles."""
        if self.layout is not None:
            return len(self.layout)
        if self.positions_m is not None:
            return len(self.positions_m)
        return math.prod(self.grid)  # type: ignore[arg-type]


@dataclass(frozen=True)
class Cap(_PlanRectangle):
    """Rectangular pile cap centred on the plan origin, bottom on the ground surface.

    ``in_contact_with_soil``: whether the cap bottom is bonded to the ground. It follows the
    interface model and is checked against it (``Scenario``): tied piles share the soil's
    displacement field and bond the cap (``true``); piles on their own field joined by the
    interface law leave the cap free of the soil (``false``, the paper's arrangement); ``None``
    (absent): whatever the interface model implies.
    """

    thickness_m: float
    in_contact_with_soil: bool | None = None

    def __post_init__(self) -> None:
        self._check_plan_size("cap")
        require_positive("thickness_m", self.thickness_m, "m")
        check_bound("cap.thickness_m", self.thickness_m)


@dataclass(frozen=True)
class Structure(_ElasticMPa):
    """Linear elastic material of piles and cap."""

    E_MPa: float
    nu: float
    density_kg_per_m3: float

    def __post_init__(self) -> None:
        self._check_elastic("structure")
        require_positive("density_kg_per_m3", self.density_kg_per_m3, "kg/m^3")
        check_bound("structure.density_kg_per_m3", self.density_kg_per_m3)

    @property
    def gamma(self) -> float:
        """Unit weight in kN/m^3."""
        return unit_weight_from_density(self.density_kg_per_m3)
