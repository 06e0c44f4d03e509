"""Frozen inputs of the coupled solver (the scenario model maps onto these).

Units: kN, m, day (stress kPa, permeability m/day, unit weight kN/m^3). Tension positive;
``p`` is the excess pore pressure, compression of the water positive (docs/model.md).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from pilegroup.constitutive.base import ConstitutiveLaw
from pilegroup.constitutive.soil import LinearElastic, require_elastic_constants
from pilegroup.errors import SolverInputError
from pilegroup.model.units import GAMMA_WATER, K_WATER
from pilegroup.validate import require_in_range, require_non_negative, require_positive

#: Unit weight of water, kN/m^3 (model.units). Darcy's law is written ``q = -(k / GAMMA_W) grad p``
#: with the hydraulic conductivity ``k`` in m/day, so ``k / GAMMA_W`` is in m^2/(kPa day).
GAMMA_W = GAMMA_WATER


@dataclass(frozen=True)
class SoilMaterial:
    """Soil of one cell group, saturated below the water table.

    Attributes:
        law: a constitutive law of ``pilegroup.constitutive`` (Mandel notation, kPa, tension +).
        k_m_per_day: hydraulic conductivity k, m/day (Darcy: ``q = -(k/GAMMA_W) grad p``).
        porosity: n = e0/(1+e0), -; the storage is ``S = n / K_w`` (1/kPa).
        gamma_sat: saturated unit weight, kN/m^3; the buoyant weight ``gamma_sat - GAMMA_W``
            loads the skeleton; above the water table ``gamma_unsat`` (None: ``gamma_sat``).
        K0: coefficient of earth pressure at rest; ``None`` gives ``1 - sin(phi)`` when the law
            has ``phi_deg``, else ``nu/(1-nu)``.
        K_w: bulk modulus of the pore water, kPa.
        excess_ratio: excess pore pressure at the start as a fraction of the vertical
            effective stress it will carry once dissipated, in [0, 1) (under-consolidated).
        excess_kPa: excess pore pressure at the start, kPa, uniform over the group.
        k_h_m_per_day: horizontal conductivity, m/day (``None``: isotropic; else ``k_m_per_day``
            is the vertical one).
    """

    law: ConstitutiveLaw
    k_m_per_day: float
    porosity: float
    gamma_sat: float = GAMMA_W
    K0: float | None = None
    K_w: float = K_WATER
    excess_ratio: float = 0.0
    excess_kPa: float = 0.0
    k_h_m_per_day: float | None = None
    gamma_unsat: float | None = None

    def __post_init__(self) -> None:
        err = SolverInputError
        require_non_negative("k_m_per_day", self.k_m_per_day, "m/day", error=err)
        for key, unit in (("k_h_m_per_day", "m/day"), ("gamma_unsat", "kN/m^3")):
            if getattr(self, key) is not None:
                require_non_negative(key, getattr(self, key), unit, error=err)
        require_in_range("porosity", self.porosity, 0.0, 1.0, "-", hi_open=True, error=err)
        require_non_negative("gamma_sat", self.gamma_sat, "kN/m^3", error=err)
        require_positive("K_w", self.K_w, "kPa", error=err)
        if self.K0 is not None:
            require_positive("K0", self.K0, "-", error=err)
        require_in_range("excess_ratio", self.excess_ratio, 0.0, 1.0, "-", hi_open=True,
                         error=err)
        require_non_negative("excess_kPa", self.excess_kPa, "kPa", error=err)
        if not hasattr(self.law, "update") or not hasattr(self.law, "initial_state"):
            raise SolverInputError(f"law = {self.law!r} does not follow the constitutive protocol")

    @property
    def storage(self) -> float:
        """Storage coefficient S = n / K_w, 1/kPa."""
        return self.porosity / self.K_w

    @property
    def mobility(self) -> float:
        """Mobility k / GAMMA_W, m^2/(kPa day) (the vertical one when anisotropic)."""
        return self.k_m_per_day / GAMMA_W

    @property
    def mobility_h(self) -> float:
        """Horizontal mobility k_h / GAMMA_W, m^2/(kPa day)."""
        k = self.k_m_per_day if self.k_h_m_per_day is None else self.k_h_m_per_day
        return k / GAMMA_W

    @property
    def k0(self) -> float:
        """Coefficient of earth pressure at rest used by the geostatic stage, -."""
        if self.K0 is not None:
            return float(self.K0)
        phi = getattr(self.law, "phi_deg", None)
        if phi is not None:
            return 1.0 - math.sin(math.radians(float(phi)))
        nu = float(getattr(self.law, "nu", 0.0))
        return nu / (1.0 - nu)

    def elastic_moduli(self) -> tuple[float, float]:
        """(bulk K, shear G) of the law's elastic part, kPa (used by preconditioners)."""
        E = float(self.law.E)
        nu = float(self.law.nu)
        return E / (3.0 * (1.0 - 2.0 * nu)), E / (2.0 * (1.0 + nu))


@dataclass(frozen=True)
class ElasticSolid:
    """Linear elastic, impermeable body (piles, cap): no pressure field in its cells.

    Attributes:
        E: Young's modulus, kPa.
        nu: Poisson's ratio, -.

    The solid is "wished in place": zero initial stress and no self weight in the geostatic
    stage (its weight can be applied as part of the loads).
    """

    E: float
    nu: float

    def __post_init__(self) -> None:
        require_elastic_constants(self.E, self.nu, error=SolverInputError)

    @property
    def law(self) -> LinearElastic:
        """The constitutive law (LinearElastic)."""
        return LinearElastic(self.E, self.nu)

    def elastic_moduli(self) -> tuple[float, float]:
        """(bulk K, shear G), kPa."""
        return self.E / (3.0 * (1.0 - 2.0 * self.nu)), self.E / (2.0 * (1.0 + self.nu))


@dataclass(frozen=True)
class InstallationExcess:
    """Excess pore pressure left by the piles' installation (cylindrical cavity expansion).

    At distance ``r`` from a pile's axis and depth above its toe, ``u = ratio |sigma'_v(z)|
    ln(R/r) / ln(R/r0)`` for ``r0 <= r <= R = radius_ratio r0`` (1 at ``r <= r0``, 0 beyond
    ``R``); the piles' fields add up (docs/model.md, "Installation pore pressures").

    Attributes:
        piles: ``(x, y, r0, z_toe)`` of every pile of the whole foundation (m; the mirror
            images a reduced model leaves out included).
        ratio: ``u / |sigma'_v|`` at the shaft, in (0, 1).
        radius_ratio: ``R / r0`` (> 1).
    """

    piles: tuple[tuple[float, float, float, float], ...]
    ratio: float
    radius_ratio: float

    def __post_init__(self) -> None:
        err = SolverInputError
        require_in_range("ratio", self.ratio, 0.0, 1.0, "-", lo_open=True, hi_open=True,
                         error=err)
        require_in_range("radius_ratio", self.radius_ratio, 1.0, math.inf, "-", lo_open=True,
                         error=err)
        for i, (_, _, r0, _) in enumerate(self.piles):
            require_positive(f"piles[{i}] radius", r0, "m", error=err)

    def shape(self, x: np.ndarray) -> np.ndarray:
        """``sum_i ln(R/r_i) / ln(R/r0_i)`` at points ``x`` ((n, 3), m), 0 below each toe."""
        x = np.asarray(x, dtype=float).reshape(-1, 3)
        out = np.zeros(x.shape[0])
        for px, py, r0, z_toe in self.piles:
            r = np.clip(np.hypot(x[:, 0] - px, x[:, 1] - py), r0, self.radius_ratio * r0)
            f = np.log(self.radius_ratio * r0 / r) / math.log(self.radius_ratio)
            out += np.where(x[:, 2] >= z_toe - 1e-9, f, 0.0)
        return out


@dataclass(frozen=True)
class InterfaceCoupling:
    """Piles and cap on their own displacement field, joined to the soil by an interface.

    Attributes:
        laws: one interface law per group (on the local jump ``[opening, slip1, slip2]``):
            ``laws[j]`` for the shafts in soil layer ``j`` (0-based), ``laws[L + j]`` for the
            bases in it (``L`` soil layers); ``None`` where no facet exists.
        traction0: ``traction0(x, z, m) -> (n, 3)`` initial local traction ``[sigma_n, tau1,
            tau2]`` (kPa, compression negative) of group ``m`` at the law's points ``x`` ((n, 3),
            m), a stress linear in depth taken at the heights ``z`` (nodal: the nodes' weighted
            heights; Gauss: the points'); ``None``: the in-situ state (docs/model.md).
        quadrature: where the law's state lives: ``"nodal"`` (the interface nodes) or
            ``"gauss"`` (2 x 2 Gauss points per facet, Q1 only; docs/solver.md).
        shaft_factor: factor on the shafts' shear tractions: the circle's circumference over
            the meshed polygon's perimeter (``geometry.plan.perimeter_factor``), so that a
            shaft carries the circle's friction force per unit length; 1 for a true circle.
    """

    laws: tuple[ConstitutiveLaw | None, ...]
    traction0: Callable[[np.ndarray, np.ndarray, int], np.ndarray] | None = None
    quadrature: Literal["nodal", "gauss"] = "nodal"
    shaft_factor: float = 1.0

    def __post_init__(self) -> None:
        if self.quadrature not in ("nodal", "gauss"):
            raise SolverInputError(f"InterfaceCoupling.quadrature = {self.quadrature!r}; "
                                   "allowed: 'nodal', 'gauss'")
        require_in_range("InterfaceCoupling.shaft_factor", self.shaft_factor, 0.5, 1.0, "-",
                         error=SolverInputError)
        for m, law in enumerate(self.laws):
            if law is not None and not (hasattr(law, "update") and hasattr(law, "initial_state")):
                raise SolverInputError(
                    f"interface laws[{m}] = {law!r} does not follow the constitutive protocol")


@dataclass(frozen=True)
class Discretisation:
    """Finite-element pair and quadrature.

    Attributes:
        pair: ``"Q2Q1"`` (Taylor–Hood on hexahedra, inf-sup stable) or ``"Q1Q1"`` (equal order).
        stabilise: the pressure Laplacian in each cell's metric (both pairs; docs/solver.md).
        stab_factor: multiplies its ``tau`` (``forms.projection_tau``).
    """

    pair: Literal["Q2Q1", "Q1Q1"] = "Q2Q1"
    stabilise: bool = True
    stab_factor: float = 1.0

    def __post_init__(self) -> None:
        if self.pair not in ("Q2Q1", "Q1Q1"):
            raise SolverInputError(f"pair = {self.pair!r}; allowed: 'Q2Q1', 'Q1Q1'")
        require_non_negative("stab_factor", self.stab_factor, "-", error=SolverInputError)

    @property
    def u_degree(self) -> int:
        """Polynomial degree of the displacement space."""
        return 2 if self.pair == "Q2Q1" else 1

    @property
    def quadrature_degree(self) -> int:
        """Degree of the Gauss rule at whose points the soil state lives."""
        return 2 * self.u_degree


@dataclass(frozen=True)
class NewtonOptions:
    """Newton settings.

    Attributes:
        rtol: relative residual tolerance per block, against its largest first residual so far.
        atol: absolute residual tolerance (kN for u, m^3 for p).
        stol: relative increment tolerance (acceptance once the residual reached round-off).
        max_it: iteration limit; beyond it the step fails (and is cut back).
        line_search: most step halvings of the backtracking line search (0: plain Newton);
            it acts only when a full step does not decrease the scaled residual.
        krylov_forcing: inexact Newton: Krylov solves stop at this fraction of each block's
            Newton tolerance (``Preset.forcing``); 0: the preset's own tolerance.
        alt_after, alt_factor: from iteration ``alt_after`` on, a residual within ``alt_factor``
            times the tolerance is accepted (docs/solver.md, "Newton").
    """

    rtol: float = 1e-9
    atol: float = 1e-12
    stol: float = 1e-12
    max_it: int = 15
    line_search: int = 4
    krylov_forcing: float = 0.1
    alt_after: int = 4
    alt_factor: float = 100.0

    def __post_init__(self) -> None:
        require_in_range("krylov_forcing", self.krylov_forcing, 0.0, 1.0, "-", hi_open=True,
                         error=SolverInputError)


@dataclass(frozen=True)
class SolverOptions:
    """Linear solver: a named preset of PETSc options merged with overrides.

    Attributes:
        preset: a name of :data:`~pilegroup.solver.presets.PRESETS` (docs/solver.md):
            ``"direct"`` (MUMPS LU), ``"direct_reuse"`` (FGMRES on a kept single-precision
            LU), the field splits ``"fieldsplit_gamg"``, ``"fieldsplit_pier"``,
            ``"fieldsplit_kept"``, ``"fieldsplit_hypre"`` (where PETSc has hypre).
        overrides: extra PETSc options (without prefix), applied after the preset.
        band_layers: cell layers of soil around the interface that join the structure's exact
            block of a ``fieldsplit_pier`` split (``presets.Preset.band_layers``); ``None``:
            the preset's own.
        prefix: PETSc options prefix of this problem.
        newton: Newton settings.
        jit_options: DOLFINx JIT options of the forms and expressions; the default compiles the
            kernels with ``-O3 -march=native`` (measured 2x faster Q1 and 1.3x faster Q2
            tangent assembly than DOLFINx's ``-O2``); ``None`` uses DOLFINx's defaults.
    """

    preset: str = "direct"
    overrides: Mapping[str, Any] = field(default_factory=dict)
    band_layers: int | None = None
    prefix: str = "biot_"
    newton: NewtonOptions = field(default_factory=NewtonOptions)
    jit_options: Mapping[str, Any] | None = field(
        default_factory=lambda: {"cffi_extra_compile_args": ["-O3", "-march=native"]})

    def __post_init__(self) -> None:
        if self.band_layers is not None and not (
                isinstance(self.band_layers, int) and self.band_layers >= 0):
            raise SolverInputError(f"band_layers = {self.band_layers!r}; allowed: an integer "
                                   ">= 0 or None (the preset's)")


@dataclass(frozen=True)
class StepControl:
    """Adaptive backward-Euler steps, days.

    Attributes:
        dt0: first step size, day.
        dt_min: a cut-back below this raises :class:`StepFailure`, day.
        dt_max: largest step, day.
        grow: factor applied after a step that took at most ``easy_newton`` iterations.
        cut: factor applied after a failed step (< 1).
        easy_newton: Newton iterations counted as easy.
        hold: number of consecutive easy steps at one size before it grows (a linear problem
            then refactors its matrix only when the size changes).
        milestones: extra times (day) hit exactly (output times); stage ends are always hit.
    """

    dt0: float = 1.0
    dt_min: float = 1e-8
    dt_max: float = math.inf
    grow: float = 1.5
    cut: float = 0.25
    easy_newton: int = 4
    hold: int = 1
    milestones: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        require_positive("dt0", self.dt0, "day", error=SolverInputError)
        require_positive("dt_min", self.dt_min, "day", error=SolverInputError)
        if not self.dt_max >= self.dt0:
            raise SolverInputError(f"dt_max = {self.dt_max} day must be >= dt0 = {self.dt0}")
        if not self.grow >= 1.0:
            raise SolverInputError(f"grow = {self.grow}; allowed: >= 1")
        require_in_range("cut", self.cut, 0.0, 1.0, "-", lo_open=True, hi_open=True,
                         error=SolverInputError)


@dataclass(frozen=True)
class DisplacementBC:
    """Prescribed displacement of one component on a facet group.

    ``value`` (m) is multiplied by the stage load factor when ``ramp`` is true.
    """

    facet: str
    component: int
    value: float = 0.0
    ramp: bool = True


@dataclass(frozen=True)
class PressureBC:
    """Prescribed excess pore pressure (kPa) on a facet group (drained boundary: 0).

    ``facet=None`` (nor ``cells``, ``level``) fixes every pressure dof (a drained analysis).
    A drainage condition on a facet group is not applied in undrained steps (``dt = 0``): the
    instantaneous response has no flow, and at ``t = 0+`` the exact pressure equals its undrained
    value everywhere in the open domain (the drained boundary layer has zero thickness), which no
    continuous pressure space can follow with a jump at the boundary nodes (Gibbs overshoot;
    Haga, Osnes & Langtangen, IJNAMG 36, 2012). Set ``in_undrained_steps=True`` to keep it.
    """

    facet: str | None
    value: float = 0.0
    in_undrained_steps: bool = False
    action: int | None = None
    """Ground action whose amplitude multiplies ``value`` (e.g. a lowered water table)."""
    cells: str | None = None
    """Every pressure dof of this soil cell group instead (a drained layer: an aquifer)."""
    level: float | None = None
    """The pressure dofs at this elevation (m) instead (a water table below the ground)."""

    def __post_init__(self) -> None:
        if sum(v is not None for v in (self.facet, self.cells, self.level)) > 1:
            raise SolverInputError(f"{self!r}: give one of facet, cells and level")


@dataclass(frozen=True)
class SurfaceLoad:
    """Uniform normal pressure (kPa, positive = compressive, pushing into the body).

    The load is ``load_factor * pressure`` when ``ramp`` is true, else constant; with
    ``action = i`` it is ``pressure`` times the amplitude of ground action ``i`` instead (set by
    the ground stages, :class:`SolverStage`). ``area`` ``(x_min, x_max, y_min, y_max)`` (m)
    limits it to a rectangle of the facet group; a facet cut by its edge carries the part
    inside (to the accuracy of the facet quadrature).
    """

    facet: str
    pressure: float
    ramp: bool = True
    action: int | None = None
    area: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class FaceAction:
    """One unit action (1 kN or 1 kN m) on a plane horizontal face, times an action amplitude.

    ``component`` 0..5 is Fx, Fy, Fz, Mx, My, Mz about the face's ``centre`` (m) in global
    axes; ``area`` (m^2) and ``inertia`` ``(I_xx, I_yy)`` (m^4, about the centre) are those of
    the whole face (a symmetry-reduced mesh holds part of it and carries that part's share).
    The traction (kPa per unit amplitude) is statically equivalent to the unit action: ``e_k /
    area`` for a force; ``e_z (y - y_c) / I_xx`` for Mx, ``-e_z (x - x_c) / I_yy`` for My (a
    linear bearing pressure); ``(-(y - y_c), x - x_c, 0) / (I_xx + I_yy)`` for Mz (a
    torsional shear). Its amplitude is that of action ``action`` (set by the stages).
    """

    facet: str
    component: int
    action: int
    centre: tuple[float, float, float]
    area: float
    inertia: tuple[float, float]
    #: a face action never follows the load factor: its amplitude is its value (kN or kN m)
    ramp = False
    #: the amplitude multiplies the unit action
    pressure = 1.0

    def __post_init__(self) -> None:
        if self.component not in range(6):
            raise SolverInputError(f"face action on {self.facet!r}: component = "
                                   f"{self.component!r} (allowed: 0..5 = Fx, Fy, Fz, Mx, My, Mz)")
        for key in ("area", "inertia"):
            vals = np.atleast_1d(getattr(self, key))
            if not np.all(np.isfinite(vals)) or np.any(vals <= 0.0):
                raise SolverInputError(f"face action on {self.facet!r}: {key} = "
                                       f"{getattr(self, key)!r} (allowed: > 0)")


@dataclass(frozen=True)
class RigidPlate:
    """A rigid, frictionless plate on a facet group, under force control.

    The ``component`` of displacement is one unknown U on the group; the resultant of the
    reactions there is ``force`` (kN, along +``component``) times the load factor (bordering).
    """

    facet: str
    component: int
    force: float


@dataclass(frozen=True)
class SolverStage:
    """One stage of the analysis.

    Attributes:
        name: label.
        kind: ``"geostatic"`` (K0 stresses, equilibrium check, displacements reset),
            ``"load"`` (load factor ramped linearly from its previous value to ``load_factor``
            over ``duration``; ``duration = 0`` is one instantaneous, undrained step),
            ``"ground"`` (the ground actions ramped linearly to ``ground`` over ``duration``,
            the load factor held; ``duration = 0`` is instantaneous), ``"consolidation"``
            (every action held to the stage end), ``"install"`` (the structure, held still
            and free of the soil's shear until then, joins the soil: the problem's
            ``install_structure``; an instant) or ``"capacity"`` (a load stage that ends, and
            ends the run, where the stepper finds no equilibrium even at ``dt_min``, or where a
            step callback raises :class:`~pilegroup.errors.CapacityReached`: failure is its
            result, recorded in ``RunLog.capacity_end``).
        duration: day.
        load_factor: load factor at the end of a load or capacity stage (loads with ``ramp``).
        ground: a ground or load stage's amplitudes of the actions at its end (the
            ``action`` indices of :class:`SurfaceLoad`, :class:`FaceAction` and
            :class:`PressureBC`: surcharges, water table, cap actions), ramped over the stage;
            the stages before set the start (all 0 at first); empty: held.
        dt0: first step of this stage (day); ``None`` keeps the stepper's current size.
        dt_max: largest step of this stage (day; ``None``: the run's), e.g. so that a capacity
            stage's curve has enough points.
    """

    name: str
    kind: Literal["geostatic", "load", "ground", "consolidation", "install", "capacity"]
    duration: float = 0.0
    load_factor: float = 1.0
    ground: tuple[float, ...] = ()
    dt0: float | None = None
    dt_max: float | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("geostatic", "load", "ground", "consolidation", "install",
                             "capacity"):
            raise SolverInputError(f"stage {self.name!r}: kind = {self.kind!r}")
        if self.kind == "install" and self.duration != 0.0:
            raise SolverInputError(f"stage {self.name!r}: an install stage is an instant"
                                   f" (duration = {self.duration!r}; allowed: 0)")
        if self.kind == "capacity" and not self.duration > 0.0:
            raise SolverInputError(f"stage {self.name!r}: a capacity stage ramps its load over"
                                   f" a duration > 0 (duration = {self.duration!r})")
        if self.ground and self.kind not in ("ground", "load"):
            raise SolverInputError(f"stage {self.name!r}: action amplitudes need kind 'ground' "
                                   "or 'load'")
        require_non_negative(f"stage {self.name!r} duration", self.duration, "day",
                             error=SolverInputError)
