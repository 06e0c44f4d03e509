"""The ground and what stands on it: soil block, layers, cap, structural material.

Field names are the TOML keys, so they carry their unit (``E_MPa``, ``k_m_per_day``); properties
without a unit suffix return internal units (kN, m, day; stresses in kPa). Validation happens
when a dataclass is built (:mod:`pilegroup.validate`); errors are
:class:`~pilegroup.errors.ScenarioError` naming the key, value, unit and what is allowed.
Geometry: plan centred at x = y = 0, ground surface z = 0, z up; the cap sits on the ground
surface, centred on the plan origin. The piles are in :mod:`pilegroup.model.piles`.

A layer's interface friction angle defaults to the paper's Eq. 17, which lives with the laws in
:mod:`pilegroup.constitutive.paper`, a pure formula on floats (no numpy, no law), so that
the formula is written once (:mod:`pilegroup.model.soil_models` takes the Soft Soil Creep
ellipse's formula from the laws likewise).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from pilegroup.constitutive.paper import delta_eq17
from pilegroup.errors import ScenarioError
from pilegroup.model.analysis import INTERFACE_LAWS, PLASTIC_SOILS, SoilModel
from pilegroup.model.bounds import BOUNDS, check_bound
from pilegroup.model.soil_models import check_critical_state_keys, friction_for_k0
from pilegroup.model.units import KPA_PER_MPA, unit_weight_from_density
from pilegroup.validate import (
    require_in_range,
    require_non_negative,
    require_positive,
)

#: A layer's strength keys: the plastic soil models use them, and so does the layer's
#: interface law (its yield cone; Eq. 17's delta_deg).
_STRENGTH = {"soil_models": PLASTIC_SOILS, "interface_modes": INTERFACE_LAWS}
#: Keys of one critical-state model (required where it is used); ``optional``: used, not required.
_MCC, _SSC = {"soil_models": ("modified_cam_clay",)}, {"soil_models": ("soft_soil_creep",)}
_CRITICAL_OPTIONAL = {"soil_models": ("modified_cam_clay", "soft_soil_creep"), "optional": True}


class _ElasticMPa:
    """Elastic constants given as ``E_MPa`` and ``nu``: their checks and ``E`` in kPa."""

    E_MPa: float
    nu: float

    def _check_elastic(self, table: str) -> None:
        require_positive("E_MPa", self.E_MPa, "MPa")
        check_bound(f"{table}.E_MPa", self.E_MPa)
        check_bound(f"{table}.nu", self.nu)

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
    """Modulus number of the hyperbolic shear stiffness (Clough & Duncan, Eq. 6)."""
    n: float
    """Exponent of the shear stiffness on the normal stress (Eq. 6)."""
    R_f: float
    """Failure ratio of the hyperbola (Eq. 7); 0: linear shear springs."""
    eta_MPa_day: float | None = field(default=None,
                                      metadata={"interface_modes": ("viscoplastic",)})
    """Viscosity of the viscoplastic slip, MPa·day per m of slip (docs/model.md, item 3);
    required where the interface is viscoplastic."""
    delta_deg: float | None = None
    """Interface friction angle, degrees; not set: Eq. 17 from the layer's ``phi_deg``."""
    base_bearing_kPa: float | None = field(default=None, metadata={
        "allowed": "> the in-situ vertical effective stress at the toes in the layer"})
    """Ultimate base resistance of a pile whose toe stands in this layer, kPa; not set: the
    soil below the toe alone limits it."""

    def __post_init__(self) -> None:
        require_positive("K", self.K, "-")
        check_bound("layers.interface.K", self.K)
        require_non_negative("n", self.n, "-")
        check_bound("layers.interface.n", self.n)
        check_bound("layers.interface.R_f", self.R_f)
        if self.eta_MPa_day is not None:
            require_positive("eta_MPa_day", self.eta_MPa_day, "MPa·day/m")
            check_bound("layers.interface.eta_MPa_day", self.eta_MPa_day)
        if self.delta_deg is not None:
            check_bound("layers.interface.delta_deg", self.delta_deg)
        if self.base_bearing_kPa is not None:
            require_positive("base_bearing_kPa", self.base_bearing_kPa, "kPa")
            check_bound("layers.interface.base_bearing_kPa", self.base_bearing_kPa)

    @property
    def eta(self) -> float | None:
        """Viscosity in kPa·day/m (None: not given, an elastic interface has none)."""
        return None if self.eta_MPa_day is None else self.eta_MPa_day * KPA_PER_MPA


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
    k_m_per_day: float
    """Hydraulic conductivity, m/day (the vertical one when ``k_h_m_per_day`` is given).

    Table 1's permeability column is read as 10^-6 cm/s (docs/model.md, item 5).
    """
    e0: float
    """Initial void ratio."""
    phi_deg: float | None = field(default=None, metadata=_STRENGTH | {
        "soil_models": (*PLASTIC_SOILS, "soft_soil_creep")})
    """Friction angle, degrees: with ``c_kPa`` the soil's strength, which the plastic soil
    models and the layer's interface law use (required where they are)."""
    c_kPa: float | None = field(default=None, metadata=_STRENGTH)
    """Cohesion, kPa (required where ``phi_deg`` is)."""
    thickness_m: float | None = None
    """Thickness, m; the last layer may omit it and then reaches the block bottom."""
    psi_deg: float = field(default=0.0, metadata={"soil_models": PLASTIC_SOILS,
                                                  "allowed": "in [0, phi_deg]"})
    """Dilatancy angle, degrees."""
    k_h_m_per_day: float | None = None
    """Horizontal hydraulic conductivity, m/day; None: equal to ``k_m_per_day``."""
    interface: InterfaceParams | None = field(default=None,
                                              metadata={"interface_modes": INTERFACE_LAWS})
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
    gamma_unsat_kN_per_m3: float | None = field(default=None,
                                                metadata={"allowed": "<= gamma_kN_per_m3"})
    """Unit weight above the water table, kN/m^3 (total: dry or moist soil); None: equal to
    ``gamma_kN_per_m3``. At most ``gamma_kN_per_m3``."""
    K0: float | None = field(default=None, metadata={"allowed": "not with OCR"})
    """Coefficient of earth pressure at rest, in (0, 3]: the in-situ horizontal effective stress
    over the vertical one; None: from ``OCR`` (Mayne & Kulhawy 1982), else ``1 - sin(phi)``
    (``nu / (1 - nu)`` for a layer without ``phi_deg``)."""
    OCR: float | None = None
    """Over-consolidation ratio, >= 1: ``K0 = (1 - sin phi) OCR^sin(phi)`` (Mayne & Kulhawy
    1982) and, in the critical-state models, the pre-consolidation stress ``OCR sigma'_v0``.
    Not with ``K0``."""
    piezometric_depth_m: float | None = field(default=None, metadata={
        "allowed": "a layer below the water table with one the water seeps through between it"
                   " and the water table (or another held layer); not with drained or an"
                   " initial excess pore pressure"})
    """Depth of the piezometric level of the layer's pore water below the ground surface, m
    (negative: above it, an artesian head): an aquifer whose head the region holds, under-drained
    or artesian; the layers between it and the water table seep steadily. None: the water
    table's hydrostatic pressure, or that seepage (docs/model.md, "The ground at rest")."""
    model: SoilModel | None = None
    """The layer's soil law; not set: ``soil.model`` (docs/model.md, "Soil models per layer")."""
    lam: float | None = field(default=None, metadata=_MCC | {"allowed": "> kappa"})
    """Modified Cam Clay: slope lambda of the normal compression line, void ratio against ln p'."""
    kappa: float | None = field(default=None, metadata=_MCC | {"allowed": "< lam"})
    """Modified Cam Clay: slope kappa of the unloading-reloading line, void ratio against ln p'."""
    M: float | None = field(default=None, metadata=_MCC | {
        "optional": True, "allowed": "one of M and phi_cs_deg"})
    """Modified Cam Clay: critical-state stress ratio q/p' (or ``phi_cs_deg``)."""
    phi_cs_deg: float | None = field(default=None, metadata=_MCC | {
        "optional": True, "allowed": "one of M and phi_cs_deg"})
    """Modified Cam Clay: critical-state friction angle, degrees, ``M = 6 sin phi/(3 - sin
    phi)`` (or ``M``)."""
    POP_kPa: float | None = field(default=None, metadata=_CRITICAL_OPTIONAL | {
        "allowed": "not with OCR"})
    """Pre-overburden pressure of the critical-state models, kPa: the vertical pre-consolidation
    stress is ``sigma'_v0 + POP_kPa`` (with ``OCR`` instead ``OCR sigma'_v0``; neither:
    ``sigma'_v0``, normally consolidated)."""
    lambda_star: float | None = field(default=None, metadata=_SSC | {"allowed": "> kappa_star"})
    """Soft Soil Creep: modified compression index lambda*, volumetric strain against ln p'."""
    kappa_star: float | None = field(default=None, metadata=_SSC | {"allowed": "< lambda_star"})
    """Soft Soil Creep: modified swelling index kappa*, volumetric strain against ln p'."""
    mu_star: float | None = field(default=None, metadata=_SSC)
    """Soft Soil Creep: modified creep index mu*, the creep strain per unit of ln(time)."""
    nu_ur: float = field(default=0.15, metadata=_SSC)
    """Soft Soil Creep: Poisson's ratio of unloading and reloading (PLAXIS's default 0.15)."""
    tau_ref_day: float = field(default=1.0, metadata=_SSC)
    """Soft Soil Creep: reference time, day: the load steps of the oedometer test that gave
    lambda* and mu* (1 day: the standard 24 h steps)."""

    def __post_init__(self) -> None:
        if not self.name.strip():
            raise ScenarioError("name", self.name, "must be a non-empty string")
        if self.thickness_m is not None:
            require_positive("thickness_m", self.thickness_m, "m")
            check_bound("layers.thickness_m", self.thickness_m)
        require_positive("gamma_kN_per_m3", self.gamma_kN_per_m3, "kN/m^3")
        check_bound("layers.gamma_kN_per_m3", self.gamma_kN_per_m3)
        self._check_elastic("layers")
        self._check_strength()
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
        self._check_at_rest()
        check_critical_state_keys(self)

    def _check_at_rest(self) -> None:
        """The keys of the ground at rest: unit weight above water, K0 or OCR, head.

        The piezometric level is not with ``drained`` or an initial excess pore pressure.
        """
        if self.piezometric_depth_m is not None:
            check_bound("layers.piezometric_depth_m", self.piezometric_depth_m)
            for key in ("drained", "excess_pore_pressure_ratio", "excess_pore_pressure_kPa"):
                if getattr(self, key):
                    raise ScenarioError("piezometric_depth_m", self.piezometric_depth_m,
                                        f"not with {key}: a layer with a piezometric level of"
                                        " its own holds its pore pressure there", "m")
        if self.gamma_unsat_kN_per_m3 is not None:
            check_bound("layers.gamma_unsat_kN_per_m3", self.gamma_unsat_kN_per_m3)
            if self.gamma_unsat_kN_per_m3 > self.gamma_kN_per_m3:
                raise ScenarioError("gamma_unsat_kN_per_m3", self.gamma_unsat_kN_per_m3,
                                    f"must be <= gamma_kN_per_m3 = {self.gamma_kN_per_m3:g} (a"
                                    " soil weighs most when saturated)", "kN/m^3")
        if self.K0 is not None:
            check_bound("layers.K0", self.K0)
        if self.OCR is not None:
            check_bound("layers.OCR", self.OCR)
            if self.K0 is not None:
                raise ScenarioError("OCR", self.OCR, "give either K0 or OCR, not both", "-")
            top = BOUNDS["layers.K0"].hi
            if self.k0 > top:
                raise ScenarioError("OCR", self.OCR, f"gives K0 = (1 - sin phi) OCR^sin(phi) ="
                                    f" {self.k0:.4g}, must give K0 <= {top:g} (layers.K0's"
                                    " range): a smaller OCR, or K0", "-")

    def _check_strength(self) -> None:
        """``phi_deg``, ``c_kPa`` where given and ``psi_deg`` in range.

        Whether a scenario needs them is its rule
        (:func:`pilegroup.model.law_rules.check_strength_keys`).
        """
        if self.phi_deg is not None:
            check_bound("layers.phi_deg", self.phi_deg)
        if self.c_kPa is not None:
            require_non_negative("c_kPa", self.c_kPa, "kPa")
            check_bound("layers.c_kPa", self.c_kPa)
        phi = 0.0 if self.phi_deg is None else self.phi_deg
        if not 0.0 <= self.psi_deg <= phi:
            raise ScenarioError("psi_deg", self.psi_deg, f"must be in [0, phi_deg = {phi:g}]",
                                "degree")
        if self.OCR is not None and friction_for_k0(self) is None:
            raise ScenarioError("OCR", self.OCR, "needs phi_deg (K0 = (1 - sin phi) OCR^sin(phi))"
                                ": give phi_deg (or phi_cs_deg or M), or K0 instead", "-")

    @property
    def porosity(self) -> float:
        """Porosity n = e0 / (1 + e0)."""
        return self.e0 / (1.0 + self.e0)

    @property
    def k0(self) -> float:
        """Coefficient of earth pressure at rest, the one the ground starts at.

        ``K0`` if given, else Mayne & Kulhawy (1982) ``(1 - sin phi) OCR^sin(phi)`` (``OCR`` 1
        when absent: Jaky's ``1 - sin phi``); phi is Modified Cam Clay's critical-state angle
        (``phi_cs_deg`` or ``M``), else ``phi_deg`` (:func:`~.soil_models.friction_for_k0`).
        """
        if self.K0 is not None:
            return self.K0
        phi = friction_for_k0(self)
        if phi is None:  # no strength keys (linear elastic): the elastic ratio
            return self.nu / (1.0 - self.nu)
        s = math.sin(math.radians(phi))
        return (1.0 - s) * (self.OCR or 1.0) ** s

    @property
    def gamma_unsat(self) -> float:
        """Unit weight above the water table, kN/m^3 (``gamma_kN_per_m3`` unless given)."""
        if self.gamma_unsat_kN_per_m3 is None:
            return self.gamma_kN_per_m3
        return self.gamma_unsat_kN_per_m3

    @property
    def k_h(self) -> float:
        """Horizontal permeability in m/day (isotropic unless ``k_h_m_per_day`` is given)."""
        return self.k_m_per_day if self.k_h_m_per_day is None else self.k_h_m_per_day

    @property
    def delta_deg(self) -> float:
        """Interface friction angle: Table 1 value if given, else Eq. 17 from phi."""
        if self.interface is not None and self.interface.delta_deg is not None:
            return self.interface.delta_deg
        return delta_eq17(self.phi_deg or 0.0)


@dataclass(frozen=True)
class _PlanRectangle:
    """A rectangle in plan centred on the origin, ``size_x_m`` x ``size_y_m`` (m)."""

    size_x_m: float
    """Size in plan along x, m, centred on the plan origin."""
    size_y_m: float
    """Size in plan along y, m, centred on the plan origin."""

    def _check_plan_size(self, table: str) -> None:
        for key in ("size_x_m", "size_y_m"):
            require_positive(key, getattr(self, key), "m")
            check_bound(f"{table}.{key}", getattr(self, key))


@dataclass(frozen=True)
class Site(_PlanRectangle):
    """The soil block: plan size, depth, water table (depth below ground, m)."""

    depth_m: float
    """Depth of the soil block below the ground surface, m."""
    water_table_depth_m: float = field(default=0.0, metadata={"allowed": "[0, depth_m)"})
    """Depth of the water table below the ground surface, m, in [0, depth_m): the soil above
    it is dry and below it saturated, the pore pressure hydrostatic from it (docs/model.md,
    "The ground at rest")."""

    def __post_init__(self) -> None:
        self._check_plan_size("site")
        require_positive("depth_m", self.depth_m, "m")
        check_bound("site.depth_m", self.depth_m)
        require_in_range("water_table_depth_m", self.water_table_depth_m, 0.0, self.depth_m,
                         "m", hi_open=True, why="in the soil block, above site.depth_m")


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
    """Thickness of the cap above the ground surface, m."""
    in_contact_with_soil: bool | None = field(default=None, metadata={
        "allowed": "true with interface.mode = \"tied\", else false"})
    """Whether the cap's bottom is bonded to the ground; not set: what the interface mode
    implies (bonded with tied piles, free of the soil with an interface law)."""

    def __post_init__(self) -> None:
        self._check_plan_size("cap")
        require_positive("thickness_m", self.thickness_m, "m")
        check_bound("cap.thickness_m", self.thickness_m)


@dataclass(frozen=True)
class Structure(_ElasticMPa):
    """Linear elastic material of piles and cap."""

    E_MPa: float
    """Young's modulus of the piles and the cap, MPa."""
    nu: float
    """Poisson's ratio of the piles and the cap."""
    density_kg_per_m3: float
    """Density of the piles and the cap, kg/m^3 (their self-weight)."""

    def __post_init__(self) -> None:
        self._check_elastic("structure")
        require_positive("density_kg_per_m3", self.density_kg_per_m3, "kg/m^3")
        check_bound("structure.density_kg_per_m3", self.density_kg_per_m3)

    @property
    def gamma(self) -> float:
        """Unit weight in kN/m^3."""
        return unit_weight_from_density(self.density_kg_per_m3)
