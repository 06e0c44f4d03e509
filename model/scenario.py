"""The scenario: a frozen, typed, validated description of one pile-group analysis.

Field names are the TOML keys, so they carry their unit (``E_MPa``, ``k_m_per_day``); properties
without a unit suffix return internal units (kN, m, day; stresses in kPa). Validation happens
when a dataclass is built; errors are :class:`~pilegroup.model.errors.ScenarioError` naming the
key, value, unit and what is allowed. Geometry: plan centred at x = y = 0, ground surface z = 0,
z up; the cap sits on the ground surface, centred on the plan origin.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal

from pilegroup.model.errors import ScenarioError, require_non_negative, require_positive
from pilegroup.model.units import KPA_PER_MPA, unit_weight_from_density

_positive = require_positive
_non_negative = require_non_negative


def _in_open(key: str, value: float, lo: float, hi: float, unit: str) -> None:
    if not lo < value < hi:
        raise ScenarioError(key, value, f"must be in ({lo:g}, {hi:g})", unit)


def _friction_angle(key: str, value: float) -> None:
    if not 0.0 <= value < 60.0:
        raise ScenarioError(key, value, "must be in [0, 60)", "degree")


def delta_eq17_deg(phi_deg: float) -> float:
    """Interface friction angle of the paper's Eq. 17, in degrees, from phi in degrees."""
    phi = math.radians(phi_deg)
    return math.degrees(math.atan(math.sin(phi) * math.cos(phi) / (1.0 + math.sin(phi) ** 2)))


@dataclass(frozen=True)
class InterfaceParams:
    """Pile-soil interface parameters of one soil layer (paper Table 1, Eqs. 5-17).

    ``eta_MPa_day`` is read as MPa·day per metre of slip (docs/model.md, choice 3), so that
    the slip rate of the zero-thickness interface is in m/day.
    """

    K: float
    n: float
    R_f: float
    eta_MPa_day: float
    delta_deg: float | None = None

    def __post_init__(self) -> None:
        _positive("K", self.K, "-")
        _non_negative("n", self.n, "-")
        if not 0.0 <= self.R_f < 1.0:
            raise ScenarioError("R_f", self.R_f, "must be in [0, 1)", "-")
        _positive("eta_MPa_day", self.eta_MPa_day, "MPa·day/m")
        if self.delta_deg is not None:
            _friction_angle("delta_deg", self.delta_deg)

    @property
    def eta(self) -> float:
        """Viscosity in kPa·day/m."""
        return self.eta_MPa_day * KPA_PER_MPA


@dataclass(frozen=True)
class Layer:
    """One horizontal soil layer (paper Table 1). The last layer may omit ``thickness_m``.

    ``gamma_kN_per_m3`` is the (saturated) soil unit weight (design.md section 5, item 6).
    """

    name: str
    gamma_kN_per_m3: float
    E_MPa: float
    nu: float
    phi_deg: float
    c_kPa: float
    k_m_per_day: float
    e0: float
    thickness_m: float | None = None
    psi_deg: float = 0.0
    k_h_m_per_day: float | None = None
    interface: InterfaceParams | None = None

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise ScenarioError("name", self.name, "must be a non-empty string")
        if self.thickness_m is not None:
            _positive("thickness_m", self.thickness_m, "m")
        _positive("gamma_kN_per_m3", self.gamma_kN_per_m3, "kN/m^3")
        _positive("E_MPa", self.E_MPa, "MPa")
        _in_open("nu", self.nu, 0.0, 0.5, "-")
        _friction_angle("phi_deg", self.phi_deg)
        _non_negative("c_kPa", self.c_kPa, "kPa")
        if not 0.0 <= self.psi_deg <= self.phi_deg:
            raise ScenarioError("psi_deg", self.psi_deg,
                                f"must be in [0, phi_deg = {self.phi_deg}]", "degree")
        _positive("k_m_per_day", self.k_m_per_day, "m/day")
        if self.k_h_m_per_day is not None:
            _positive("k_h_m_per_day", self.k_h_m_per_day, "m/day")
        _positive("e0", self.e0, "-")

    @property
    def E(self) -> float:
        """Young's modulus in kPa."""
        return self.E_MPa * KPA_PER_MPA

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
        return delta_eq17_deg(self.phi_deg)


@dataclass(frozen=True)
class Site:
    """The soil block: plan size, depth, water table (depth below ground, m)."""

    size_x_m: float
    size_y_m: float
    depth_m: float
    water_table_depth_m: float = 0.0

    def __post_init__(self) -> None:
        _positive("size_x_m", self.size_x_m, "m")
        _positive("size_y_m", self.size_y_m, "m")
        _positive("depth_m", self.depth_m, "m")
        _non_negative("water_table_depth_m", self.water_table_depth_m, "m")
        if self.water_table_depth_m > self.depth_m:
            raise ScenarioError("water_table_depth_m", self.water_table_depth_m,
                                f"must be <= depth_m = {self.depth_m}", "m")


@dataclass(frozen=True)
class Piles:
    """The piles: a regular grid centred on the cap, or explicit positions.

    Either ``grid`` [nx, ny] with ``spacing_m`` [sx, sy], or ``positions_m`` [[x, y], ...] (m,
    plan coordinates).
    """

    diameter_m: float
    length_in_soil_m: float
    embedment_m: float = 0.0
    grid: tuple[int, int] | None = None
    spacing_m: tuple[float, float] | None = None
    positions_m: tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        _positive("diameter_m", self.diameter_m, "m")
        _positive("length_in_soil_m", self.length_in_soil_m, "m")
        _non_negative("embedment_m", self.embedment_m, "m")
        if self.positions_m is not None:
            if self.grid is not None or self.spacing_m is not None:
                raise ScenarioError("positions_m", list(self.positions_m),
                                    "give either positions_m or grid + spacing_m, not both", "m")
            if len(self.positions_m) == 0:
                raise ScenarioError("positions_m", [], "must list at least one pile", "m")
        else:
            if self.grid is None:
                raise ScenarioError("grid", None, "missing: give grid = [nx, ny] with spacing_m,"
                                    " or positions_m")
            for i, v in enumerate(self.grid):
                if v < 1:
                    raise ScenarioError(f"grid[{i}]", v, "must be an integer >= 1")
            needs = any(v > 1 for v in self.grid)
            if self.spacing_m is None:
                if needs:
                    raise ScenarioError("spacing_m", None, "missing: required when grid > 1x1",
                                        "m")
            else:
                for i, v in enumerate(self.spacing_m):
                    _positive(f"spacing_m[{i}]", v, "m")
        xy = self.xy
        for i in range(len(xy)):
            for j in range(i):
                dist = math.dist(xy[i], xy[j])
                if dist < self.diameter_m:
                    raise ScenarioError(
                        "positions_m" if self.positions_m is not None else "spacing_m",
                        [list(xy[j]), list(xy[i])],
                        f"piles {j + 1} and {i + 1} overlap: centre distance {dist:g} m must be"
                        f" >= diameter_m = {self.diameter_m:g}", "m")

    @property
    def xy(self) -> tuple[tuple[float, float], ...]:
        """Plan positions (m) of every pile, numbered row by row (x fastest) from 1."""
        if self.positions_m is not None:
            return tuple((float(x), float(y)) for x, y in self.positions_m)
        nx, ny = self.grid  # type: ignore[misc]
        sx, sy = self.spacing_m if self.spacing_m is not None else (0.0, 0.0)
        return tuple(((i - (nx - 1) / 2) * sx, (j - (ny - 1) / 2) * sy)
                     for j in range(ny) for i in range(nx))

    @property
    def count(self) -> int:
        """Number of piles."""
        return len(self.xy)


@dataclass(frozen=True)
class Cap:
    """Rectangular pile cap centred on the plan origin, bottom on the ground surface."""

    size_x_m: float
    size_y_m: float
    thickness_m: float
    in_contact_with_soil: bool = False

    def __post_init__(self) -> None:
        _positive("size_x_m", self.size_x_m, "m")
        _positive("size_y_m", self.size_y_m, "m")
        _positive("thickness_m", self.thickness_m, "m")


@dataclass(frozen=True)
class Structure:
    """Linear elastic material of piles and cap."""

    E_MPa: float
    nu: float
    density_kg_per_m3: float

    def __post_init__(self) -> None:
        _positive("E_MPa", self.E_MPa, "MPa")
        _in_open("nu", self.nu, 0.0, 0.5, "-")
        _positive("density_kg_per_m3", self.density_kg_per_m3, "kg/m^3")

    @property
    def E(self) -> float:
        """Young's modulus in kPa."""
        return self.E_MPa * KPA_PER_MPA

    @property
    def gamma(self) -> float:
        """Unit weight in kN/m^3."""
        return unit_weight_from_density(self.density_kg_per_m3)


@dataclass(frozen=True)
class Soil:
    """Which constitutive law the soil layers use."""

    model: Literal["mohr_coulomb", "drucker_prager", "linear_elastic"] = "mohr_coulomb"


@dataclass(frozen=True)
class InterfaceOptions:
    """How the pile-soil interface is modelled.

    ``mode``: ``tied`` (piles share nodes with the soil, no interface law), ``elastic``
    (hyperbolic springs only) or ``viscoplastic`` (the paper's full law). ``variant``: ``default``
    (our consistent reading) or ``seed`` (the paper's literal equations), see docs/model.md.
    The normal penalty stiffness is ``normal_stiffness_factor`` x E_layer / mesh size (kPa/m).
    ``quadrature``: where the law is evaluated and its state lives, ``nodal`` (the interface
    nodes) or ``gauss`` (2 x 2 Gauss points per facet, Q1Q1 only); docs/solver.md compares them.
    """

    mode: Literal["tied", "elastic", "viscoplastic"] = "viscoplastic"
    variant: Literal["default", "seed"] = "default"
    integrator: Literal["implicit", "explicit"] = "implicit"
    N: float = 1.0
    normal_stiffness_factor: float = 100.0
    base: bool = True
    quadrature: Literal["nodal", "gauss"] = "nodal"

    def __post_init__(self) -> None:
        _positive("N", self.N, "-")
        _positive("normal_stiffness_factor", self.normal_stiffness_factor, "-")


@dataclass(frozen=True)
class Stage:
    """One analysis stage.

    ``kind``: ``geostatic`` (in-situ stresses, no time), ``load`` (ramps the cap load to
    ``cap_load_kN`` over ``duration_day``, drained top, consolidating meanwhile), ``consolidation``
    (constant load until ``until_day``, or until ``time.end_day`` when omitted).
    """

    name: str
    kind: Literal["geostatic", "load", "consolidation"]
    cap_load_kN: float | None = None
    duration_day: float | None = None
    until_day: float | None = None

    def __post_init__(self) -> None:
        if self.kind == "load":
            if self.cap_load_kN is None:
                raise ScenarioError("cap_load_kN", None, "missing: required for a load stage", "kN")
            _non_negative("cap_load_kN", self.cap_load_kN, "kN")
            if self.duration_day is None:
                raise ScenarioError("duration_day", None, "missing: required for a load stage",
                                    "day")
            _positive("duration_day", self.duration_day, "day")
        else:
            for key in ("cap_load_kN", "duration_day"):
                if getattr(self, key) is not None:
                    raise ScenarioError(key, getattr(self, key),
                                        f"not allowed for a {self.kind} stage (only for load)")
        if self.until_day is not None:
            if self.kind != "consolidation":
                raise ScenarioError("until_day", self.until_day,
                                    "only allowed for a consolidation stage", "day")
            _positive("until_day", self.until_day, "day")


@dataclass(frozen=True)
class Time:
    """End time of the analysis and the times at which outputs are written (day)."""

    end_day: float
    output_days: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        _positive("end_day", self.end_day, "day")
        for i, t in enumerate(self.output_days):
            if not 0.0 <= t <= self.end_day:
                raise ScenarioError(f"output_days[{i}]", t, f"must be in [0, end_day = "
                                    f"{self.end_day:g}]", "day")


@dataclass(frozen=True)
class MeshOptions:
    """Mesh sizing (m unless stated); ``size_m`` is h at the pile surfaces (the paper's study).

    Plan view: quads sized ``size_m`` next to the piles, at least ``n_circ_min`` edges around a
    pile, growing by ``growth`` per element to ``far_field_size_m``. Vertical (extrusion):
    ``dz_surface_m`` at the ground, ``dz_toe_m`` at the pile toes, at most ``dz_max_m`` down to the
    deepest toe and ``dz_max_deep_m`` below it, growing by ``dz_growth``; ``dz_cap_m`` in the cap;
    at least ``min_layer_divisions`` elements across every layer.
    """

    size_m: float = 1.0
    far_field_size_m: float = 8.0
    growth: float = 1.3
    n_circ_min: int = 32
    dz_surface_m: float = 0.5
    dz_toe_m: float = 0.5
    dz_max_m: float = 2.0
    dz_max_deep_m: float = 4.0
    dz_growth: float = 1.2
    dz_cap_m: float = 0.5
    min_layer_divisions: int = 2

    def __post_init__(self) -> None:
        for key in ("size_m", "far_field_size_m", "dz_surface_m", "dz_toe_m", "dz_max_m",
                    "dz_max_deep_m", "dz_cap_m"):
            _positive(key, getattr(self, key), "m")
        if self.far_field_size_m < self.size_m:
            raise ScenarioError("far_field_size_m", self.far_field_size_m,
                                f"must be >= size_m = {self.size_m:g}", "m")
        for key in ("growth", "dz_growth"):
            if not 1.0 < getattr(self, key) <= 2.0:
                raise ScenarioError(key, getattr(self, key), "must be in (1, 2]", "-")
        if self.n_circ_min < 8 or self.n_circ_min % 4:
            raise ScenarioError("n_circ_min", self.n_circ_min,
                                "must be a multiple of 4, >= 8", "-")
        if self.min_layer_divisions < 1:
            raise ScenarioError("min_layer_divisions", self.min_layer_divisions,
                                "must be an integer >= 1", "-")


@dataclass(frozen=True)
class TimeStepping:
    """Adaptive backward-Euler stepping (day).

    The step grows by ``grow_factor`` when Newton converges in at most ``easy_newton``
    iterations and is cut back by ``cut_factor`` when it fails.
    """

    dt_initial_day: float = 0.5
    dt_min_day: float = 1.0e-4
    dt_max_day: float = 20.0
    grow_factor: float = 1.5
    cut_factor: float = 0.25
    max_newton: int = 15
    easy_newton: int = 4

    def __post_init__(self) -> None:
        for key in ("dt_initial_day", "dt_min_day", "dt_max_day"):
            _positive(key, getattr(self, key), "day")
        if self.dt_min_day > self.dt_initial_day or self.dt_initial_day > self.dt_max_day:
            raise ScenarioError("dt_initial_day", self.dt_initial_day,
                                "must satisfy dt_min_day <= dt_initial_day <= dt_max_day", "day")
        if not self.grow_factor >= 1.0:
            raise ScenarioError("grow_factor", self.grow_factor, "must be >= 1", "-")
        _in_open("cut_factor", self.cut_factor, 0.0, 1.0, "-")
        if self.max_newton < 1:
            raise ScenarioError("max_newton", self.max_newton, "must be an integer >= 1")
        if not 1 <= self.easy_newton <= self.max_newton:
            raise ScenarioError("easy_newton", self.easy_newton,
                                f"must be in [1, max_newton = {self.max_newton}]")


@dataclass(frozen=True)
class LinearSolver:
    """PETSc linear solver: a named preset merged with user ``options``.

    ``options`` are PETSc option names without the problem prefix. ``auto`` picks ``direct``
    for small problems.
    """

    preset: Literal["auto", "direct", "direct_reuse", "fieldsplit_gamg"] = "auto"
    options: dict[str, str | int | float | bool] = field(default_factory=dict)


@dataclass(frozen=True)
class Numerics:
    """Discretisation and solution controls.

    Newton accepts an iterate when every block residual (soil and structure displacement, kN;
    pressure, m^3) is at most ``newton_rtol`` times that block's reference (the largest first
    residual of the run, for displacements also the norm of the internal force, which holds
    the geostatic stress) plus ``newton_atol``; ``time.max_newton`` iterations at most.
    """

    element: Literal["Q2Q1", "Q1Q1"] = "Q2Q1"
    newton_rtol: float = 1.0e-8
    newton_atol: float = 1.0e-9
    mesh: MeshOptions = field(default_factory=MeshOptions)
    time: TimeStepping = field(default_factory=TimeStepping)
    solver: LinearSolver = field(default_factory=LinearSolver)

    def __post_init__(self) -> None:
        _positive("newton_rtol", self.newton_rtol, "-")
        _positive("newton_atol", self.newton_atol, "-")


@dataclass(frozen=True)
class Outputs:
    """What to write. ``gauge_depths_m``: depths below ground of the pile gauge sections."""

    xdmf: bool = True
    plots: bool = True
    gauge_depths_m: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        for i, z in enumerate(self.gauge_depths_m):
            _non_negative(f"gauge_depths_m[{i}]", z, "m")


@dataclass(frozen=True)
class Scenario:
    """A whole analysis: site, layers, piles, cap, materials, interface, stages, time, numerics."""

    name: str
    site: Site
    layers: tuple[Layer, ...]
    piles: Piles
    structure: Structure
    stages: tuple[Stage, ...]
    time: Time
    cap: Cap | None = None
    soil: Soil = field(default_factory=Soil)
    interface: InterfaceOptions = field(default_factory=InterfaceOptions)
    numerics: Numerics = field(default_factory=Numerics)
    outputs: Outputs = field(default_factory=Outputs)
    description: str = ""

    def __post_init__(self) -> None:  # noqa: C901 - one rule after the other
        if not self.layers:
            raise ScenarioError("layers", [], "must list at least one layer")
        for i, layer in enumerate(self.layers[:-1]):
            if layer.thickness_m is None:
                raise ScenarioError(f"layers[{i}].thickness_m", None,
                                    "missing: only the last layer may omit its thickness", "m")
        depth = self.site.depth_m
        toe = self.piles.length_in_soil_m
        if toe >= depth:
            raise ScenarioError("piles.length_in_soil_m", toe,
                                f"must be < site.depth_m = {depth:g} (pile longer than the block)",
                                "m")
        given = sum(layer.thickness_m or 0.0 for layer in self.layers)
        if self.layers[-1].thickness_m is None:
            if given >= depth:
                raise ScenarioError(f"layers[{len(self.layers) - 1}].thickness_m", None,
                                    f"the layers above already reach {given:g} m >= site.depth_m"
                                    f" = {depth:g} m; nothing is left for the last layer", "m")
        else:
            if given < toe:
                raise ScenarioError("layers", f"total thickness {given:g}",
                                    f"the layer stack must reach the pile toe at {toe:g} m depth"
                                    " (or omit the last layer's thickness to extend it to the"
                                    " bottom)", "m")
            if abs(given - depth) > 1e-9 * depth:
                raise ScenarioError("layers", f"total thickness {given:g}",
                                    f"must equal site.depth_m = {depth:g} (or omit the last"
                                    " layer's thickness)", "m")
        half_x, half_y = self.site.size_x_m / 2, self.site.size_y_m / 2
        r = self.piles.diameter_m / 2
        for i, (x, y) in enumerate(self.piles.xy):
            if abs(x) + r > half_x or abs(y) + r > half_y:
                raise ScenarioError(f"piles[{i + 1}] position", [x, y],
                                    "pile lies outside the soil block", "m")
            if self.cap is not None and (abs(x) + r > self.cap.size_x_m / 2 + 1e-12
                                         or abs(y) + r > self.cap.size_y_m / 2 + 1e-12):
                raise ScenarioError(f"piles[{i + 1}] position", [x, y],
                                    f"pile (diameter {self.piles.diameter_m:g} m) lies outside the"
                                    f" cap ({self.cap.size_x_m:g} x {self.cap.size_y_m:g} m)", "m")
        if self.cap is not None:
            if self.cap.size_x_m > self.site.size_x_m or self.cap.size_y_m > self.site.size_y_m:
                raise ScenarioError("cap.size_x_m", self.cap.size_x_m,
                                    "the cap must fit inside the soil block in plan", "m")
            if self.piles.embedment_m >= self.cap.thickness_m:
                raise ScenarioError("piles.embedment_m", self.piles.embedment_m,
                                    f"must be < cap.thickness_m = {self.cap.thickness_m:g}", "m")
        elif self.piles.embedment_m > 0.0:
            raise ScenarioError("piles.embedment_m", self.piles.embedment_m,
                                "must be 0 when there is no cap", "m")
        self._check_stages()
        if self.interface.mode != "tied":
            for i, layer in enumerate(self.layers):
                if layer.interface is None and self.layer_top(i) < toe:
                    raise ScenarioError(f"layers[{i}].interface", None,
                                        f"missing: the piles cross layer {layer.name!r} and"
                                        f" interface.mode = {self.interface.mode!r}")
        for i, z in enumerate(self.outputs.gauge_depths_m):
            if z > toe:
                raise ScenarioError(f"outputs.gauge_depths_m[{i}]", z,
                                    f"must be <= the pile length in soil {toe:g}", "m")

    def _check_stages(self) -> None:
        if not self.stages:
            raise ScenarioError("stages", [], "must list at least one stage")
        if self.stages[0].kind != "geostatic":
            raise ScenarioError("stages[0].kind", self.stages[0].kind,
                                "the first stage must be 'geostatic'")
        t = 0.0
        for i, st in enumerate(self.stages):
            if i > 0 and st.kind == "geostatic":
                raise ScenarioError(f"stages[{i}].kind", st.kind,
                                    "only the first stage may be 'geostatic'")
            if st.kind == "load":
                t += st.duration_day  # type: ignore[operator]
                if t > self.time.end_day:
                    raise ScenarioError("time.end_day", self.time.end_day,
                                        f"must be >= the end of load stage {st.name!r} at"
                                        f" {t:g} day", "day")
            elif st.kind == "consolidation":
                until = self.time.end_day if st.until_day is None else st.until_day
                if until <= t or until > self.time.end_day:
                    raise ScenarioError(f"stages[{i}].until_day", until,
                                        f"must be in ({t:g}, time.end_day = "
                                        f"{self.time.end_day:g}]", "day")
                t = until

    # ---- derived quantities (internal units) ----
    def layer_top(self, i: int) -> float:
        """Depth (m, positive down) of the top of layer ``i``."""
        return sum(layer.thickness_m or 0.0 for layer in self.layers[:i])

    def layer_bottom(self, i: int) -> float:
        """Depth (m, positive down) of the bottom of layer ``i`` (the block bottom for the last)."""
        if i == len(self.layers) - 1:
            return self.site.depth_m
        return self.layer_top(i) + self.layers[i].thickness_m  # type: ignore[operator]

    def layer_depths(self) -> tuple[float, ...]:
        """Depths (m, positive down) of all layer boundaries, from 0 to the block depth."""
        return tuple([0.0] + [self.layer_bottom(i) for i in range(len(self.layers))])

    def stage_times(self) -> tuple[tuple[Stage, float, float], ...]:
        """Each stage with its start and end time (day); the geostatic stage spans (0, 0)."""
        out, t = [], 0.0
        for st in self.stages:
            if st.kind == "geostatic":
                out.append((st, 0.0, 0.0))
            elif st.kind == "load":
                out.append((st, t, t + st.duration_day))  # type: ignore[operator]
                t += st.duration_day  # type: ignore[operator]
            else:
                end = self.time.end_day if st.until_day is None else st.until_day
                out.append((st, t, end))
                t = end
        return tuple(out)

    def total_cap_load(self) -> float:
        """Cap load (kN) at the end of the last load stage."""
        loads = [st.cap_load_kN for st in self.stages if st.kind == "load"]
        return float(loads[-1]) if loads else 0.0
