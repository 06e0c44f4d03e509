"""How the analysis is run: modelling options, time, mesh, numerics, outputs.

The stages are in :mod:`pilegroup.model.stages`.

Field names are the TOML keys (with their unit where they have one, e.g. ``duration_day``).
Validation happens when a dataclass is built (:mod:`pilegroup.validate`); errors are
:class:`~pilegroup.errors.ScenarioError` naming the key, value, unit and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass, field, fields, replace
from typing import Literal

from pilegroup.errors import ScenarioError
from pilegroup.model.bounds import check_bound
from pilegroup.validate import (
    is_finite_number,
    require_finite,
    require_non_negative,
    require_one_of,
    require_positive,
)

#: A soil law (``soil.model``, ``layers.model``; docs/model.md).
SoilModel = Literal["mohr_coulomb", "drucker_prager", "linear_elastic", "modified_cam_clay",
                    "soft_soil_creep"]


@dataclass(frozen=True)
class Soil:
    """Which constitutive law the soil layers use."""

    model: SoilModel = "mohr_coulomb"
    """The soil layers' law, unless a layer names its own (``layers.model``): Mohr-Coulomb or
    Drucker-Prager (elastic-perfectly plastic, the layers' ``phi_deg``, ``c_kPa``,
    ``psi_deg``), linear elastic (no strength keys), Modified Cam Clay or Soft Soil Creep (the
    layers' critical-state keys; docs/model.md, "Soil models per layer")."""


#: The soil models whose strength the layers' ``phi_deg``, ``c_kPa`` and ``psi_deg`` give.
PLASTIC_SOILS = ("mohr_coulomb", "drucker_prager")
#: The critical-state soil models: stiffness and pre-consolidation follow the stress.
CRITICAL_STATE_SOILS = ("modified_cam_clay", "soft_soil_creep")
#: The interface modes with an interface law (the piles on their own displacement field).
INTERFACE_LAWS = ("elastic", "viscoplastic")


@dataclass(frozen=True)
class InterfaceOptions:
    """How the pile-soil interface is modelled (docs/model.md, items 1-4)."""

    mode: Literal["tied", "elastic", "viscoplastic"] = "viscoplastic"
    """``tied``: piles share nodes with the soil, no interface law; ``elastic``: hyperbolic
    springs only; ``viscoplastic``: the paper's full law."""
    variant: Literal["default", "seed"] = field(
        default="default", metadata={"interface_modes": ("viscoplastic",)})
    """The yield function: ``default``, our consistent reading, or ``seed``, the paper's
    literal Eq. 15 (docs/model.md)."""
    integrator: Literal["implicit", "explicit"] = field(
        default="implicit", metadata={"interface_modes": ("viscoplastic",)})
    """The viscoplastic slip's integration: backward Euler, or the paper's forward update."""
    N: float = field(default=1.0, metadata={"interface_modes": ("viscoplastic",)})
    """Perzyna exponent of the viscoplastic slip rate."""
    normal_stiffness_factor: float = field(default=100.0,
                                           metadata={"interface_modes": INTERFACE_LAWS})
    """The normal penalty stiffness is this factor x the layer's E / the mesh size (kPa/m)."""
    base: bool = field(default=True, metadata={"interface_modes": INTERFACE_LAWS,
                                               "allowed": "true"})
    """An interface under every pile base too (the only arrangement modelled)."""
    quadrature: Literal["nodal", "gauss"] = field(default="nodal",
                                                  metadata={"interface_modes": INTERFACE_LAWS})
    """Where the law is evaluated: the interface nodes, or 2 x 2 Gauss points per facet (with
    ``numerics.element = "Q1Q1"`` only); docs/solver.md compares them."""

    def __post_init__(self) -> None:
        for key in ("N", "normal_stiffness_factor"):
            require_positive(key, getattr(self, key), "-")
            check_bound(f"interface.{key}", getattr(self, key))
        if not self.base and self.mode != "tied":
            raise ScenarioError("base", False, "only true (an interface under every pile base)"
                                f" is modelled with mode = {self.mode!r}", "-")


@dataclass(frozen=True)
class Time:
    """Start and end of the analysis and the times at which outputs are written (day).

    Day 0 is the piles' installation when a stage of kind ``installation`` says when (the
    ground may move from ``start_day < 0`` on); otherwise the analysis starts at 0.
    """

    end_day: float
    """The last day of the analysis."""
    output_days: tuple[float, ...] = field(default=(), metadata={
        "allowed": "increasing, in [start_day, end_day]"})
    """Days at which the fields and checkpoints are written, besides each stage's end."""
    start_day: float = 0.0
    """The geostatic state's day, <= 0 (negative: the ground moves before day 0)."""

    def __post_init__(self) -> None:
        require_positive("end_day", self.end_day, "day")
        check_bound("time.end_day", self.end_day)
        require_finite("start_day", self.start_day, "day")
        check_bound("time.start_day", self.start_day)
        for i, t in enumerate(self.output_days):
            if not self.start_day <= t <= self.end_day:
                raise ScenarioError(f"output_days[{i}]", t, f"must be in [start_day = "
                                    f"{self.start_day:g}, end_day = {self.end_day:g}]", "day")
        for i in range(1, len(self.output_days)):
            if not self.output_days[i - 1] < self.output_days[i]:
                raise ScenarioError(f"output_days[{i}]", self.output_days[i], "must be > "
                                    f"{self.output_days[i - 1]:g}, the time before it: output "
                                    "times are listed in increasing order, each once", "day")


@dataclass(frozen=True)
class MeshOptions:
    """Mesh sizing: quads in plan around the piles, extruded down through the layers.

    Every key is optional: a key left out (``None``) is chosen from the scenario when the
    scenario is built (:mod:`pilegroup.model.mesh_defaults`); a :class:`Scenario
    <pilegroup.model.scenario.Scenario>` always holds numbers, and ``automatic`` names the
    keys it chose.
    """

    size_m: float | None = field(default=None, metadata={
        "allowed": "<= 5 x the thinnest pile's diameter"})
    """Plan size of the elements next to the piles, m: h of the paper's mesh study."""
    far_field_size_m: float | None = field(default=None, metadata={"allowed": ">= size_m"})
    """Plan size the elements grow to away from the piles, m."""
    growth: float | None = None
    """Plan size growth ratio per element, in (1, 2]."""
    n_circ_min: int | None = field(default=None, metadata={"allowed": "a multiple of 4"})
    """At least this many element edges around a pile (a multiple of 4, >= 8)."""
    dz_surface_m: float | None = None
    """Vertical element size at the ground surface, m."""
    dz_toe_m: float | None = field(default=None, metadata={
        "allowed": "<= site.depth_m - the longest pile's length in soil"})
    """Vertical element size at the pile toes, m."""
    dz_max_m: float | None = None
    """Largest vertical element size down to the deepest toe, m."""
    dz_max_deep_m: float | None = None
    """Largest vertical element size below the deepest toe, m (may exceed ``dz_max_m``)."""
    dz_growth: float | None = None
    """Vertical size growth ratio per element, in (1, 2]."""
    dz_cap_m: float | None = None
    """Vertical element size in the cap, m."""
    min_layer_divisions: int | None = None
    """At least this many elements across every layer."""
    scale: float = 1.0
    """Factor on every automatic length (the edges around a pile divided by it): 0.5 halves
    the default elements, 2 doubles them; keys given are not scaled."""
    automatic: tuple[str, ...] = field(default=(), metadata={"derived": True})
    """The keys chosen automatically (set by the scenario; not a scenario key)."""

    def given(self) -> dict[str, float | int]:
        """The keys that hold a value, by name."""
        return {f.name: getattr(self, f.name) for f in fields(self)
                if not f.metadata.get("derived") and getattr(self, f.name) is not None}

    def with_given(self, **sizes: float | int) -> MeshOptions:
        """These options with ``sizes`` set as a scenario's own keys (no longer automatic)."""
        return replace(self, **sizes, automatic=tuple(k for k in self.automatic
                                                      if k not in sizes))

    def __post_init__(self) -> None:
        for key in ("size_m", "far_field_size_m", "dz_surface_m", "dz_toe_m", "dz_max_m",
                    "dz_max_deep_m", "dz_cap_m"):
            if getattr(self, key) is not None:
                require_positive(key, getattr(self, key), "m")
                check_bound(f"numerics.mesh.{key}", getattr(self, key))
        if (self.far_field_size_m is not None and self.size_m is not None
                and self.far_field_size_m < self.size_m):
            raise ScenarioError("far_field_size_m", self.far_field_size_m,
                                f"must be >= size_m = {self.size_m:g}", "m")
        for key in ("growth", "dz_growth"):
            if getattr(self, key) is not None:
                check_bound(f"numerics.mesh.{key}", getattr(self, key))
        if self.n_circ_min is not None:
            if self.n_circ_min < 8 or self.n_circ_min % 4:
                raise ScenarioError("n_circ_min", self.n_circ_min,
                                    "must be a multiple of 4, >= 8", "-")
            check_bound("numerics.mesh.n_circ_min", self.n_circ_min)
        check_bound("numerics.mesh.scale", self.scale)
        if self.min_layer_divisions is not None:
            if self.min_layer_divisions < 1:
                raise ScenarioError("min_layer_divisions", self.min_layer_divisions,
                                    "must be an integer >= 1", "-")
            check_bound("numerics.mesh.min_layer_divisions", self.min_layer_divisions)


@dataclass(frozen=True)
class TimeStepping:
    """Adaptive backward-Euler stepping (day)."""

    dt_initial_day: float = field(default=0.5, metadata={
        "allowed": "in [dt_min_day, dt_max_day]"})
    """First step, day."""
    dt_min_day: float = field(default=1.0e-4, metadata={"allowed": "<= time.end_day"})
    """Smallest step, day: the run stops when a cut-back would go below it."""
    dt_max_day: float = 20.0
    """Largest step, day."""
    grow_factor: float = 1.5
    """Factor on the step after an easy step (>= 1)."""
    cut_factor: float = 0.25
    """Factor on the step after a failed step, in (0, 1)."""
    max_newton: int = 15
    """Newton iterations at most; a step that needs more fails (and is cut back)."""
    easy_newton: int = field(default=4, metadata={"allowed": "in [1, max_newton]"})
    """Newton iterations at most of an easy step, in [1, max_newton].

    After an easy step the next one grows by ``grow_factor``.
    """

    def __post_init__(self) -> None:
        for key in ("dt_initial_day", "dt_min_day", "dt_max_day"):
            require_positive(key, getattr(self, key), "day")
            check_bound(f"numerics.time.{key}", getattr(self, key))
        if self.dt_min_day > self.dt_initial_day or self.dt_initial_day > self.dt_max_day:
            raise ScenarioError("dt_initial_day", self.dt_initial_day,
                                "must satisfy dt_min_day <= dt_initial_day <= dt_max_day", "day")
        if not self.grow_factor >= 1.0:
            raise ScenarioError("grow_factor", self.grow_factor, "must be >= 1", "-")
        check_bound("numerics.time.grow_factor", self.grow_factor)
        check_bound("numerics.time.cut_factor", self.cut_factor)
        if self.max_newton < 1:
            raise ScenarioError("max_newton", self.max_newton, "must be an integer >= 1")
        check_bound("numerics.time.max_newton", self.max_newton)
        if not 1 <= self.easy_newton <= self.max_newton:
            raise ScenarioError("easy_newton", self.easy_newton,
                                f"must be in [1, max_newton = {self.max_newton}]")


@dataclass(frozen=True)
class LinearSolver:
    """PETSc linear solver: a named preset merged with user ``options``.

    ``auto`` takes the preset measured fastest for the system's model part, interface and size
    (``studies.run.auto_preset.AUTO_TABLE``, docs/solver.md); a failing ``fieldsplit_gamg``,
    ``fieldsplit_pier`` or ``fieldsplit_kept`` falls back to ``direct_reuse`` (a kept LU in
    single precision), which falls back to ``direct_reuse_double`` (the same in double);
    ``direct_reuse_ooc`` is ``direct_reuse`` with its factors out of core (files under
    ``TMPDIR``), which ``auto`` takes when the in-core one exceeds the memory a run may use,
    and falls back to ``direct_reuse_ooc_double`` (the same in double, still out of core).

    ``krylov_forcing``: inexact Newton (presets whose Krylov solve supports it, e.g.
    ``direct_reuse``): a Newton correction's Krylov solve stops once every block's linear
    residual is below this fraction of the block's Newton tolerance; 0: every solve to the
    preset's relative tolerance (docs/solver.md, "Inexact Newton").
    """

    preset: Literal["auto", "direct", "direct_reuse", "direct_reuse_double", "direct_reuse_ooc",
                    "direct_reuse_ooc_double", "fieldsplit_gamg", "fieldsplit_pier",
                    "fieldsplit_kept", "fieldsplit_hypre"] = "auto"
    """The preset of PETSc options; ``auto``: the one measured fastest (docs/solver.md)."""
    options: dict[str, str | int | float | bool] = field(default_factory=dict)
    """PETSc options (names without the problem prefix) over the preset's."""
    krylov_forcing: float = 0.1
    """Inexact Newton: a Krylov solve stops at this fraction of Newton's tolerance; 0: at the
    preset's."""

    def __post_init__(self) -> None:
        check_bound("numerics.solver.krylov_forcing", self.krylov_forcing)


#: Values of ``numerics.symmetry``.
SYMMETRY_CHOICES = ("auto", "none", "quarter", "half_x", "half_y")


@dataclass(frozen=True)
class Numerics:
    """Discretisation and solution controls.

    Newton accepts an iterate when every block residual (soil and structure displacement, kN;
    pressure, m^3) is at most ``newton_rtol`` times that block's reference (the largest first
    residual of the run, for displacements also the norm of the internal force, which holds
    the geostatic stress) plus ``newton_atol``; ``time.max_newton`` iterations at most.

    ``symmetry``: which part of the block is modelled. ``none``: all of it; ``half_x``: x >= 0
    (mirror plane x = 0); ``half_y``: y >= 0; ``quarter``: both; ``auto`` (default): the
    smallest part the scenario's mirror symmetry allows
    (:func:`pilegroup.geometry.adapter.resolve_geometry`). A plane must be one the pile layout
    and the cap are mirror-symmetric about (the block is centred by construction, the loads are
    uniform on the cap top or the pile heads).

    ``element``: ``Q1Q1`` (trilinear displacement and pressure), ``Q2Q1`` (triquadratic
    displacement, Taylor–Hood), each with its pressure stabilisation, or ``auto`` (default):
    Q2Q1 where trilinear hexahedra lock (horizontal actions, a capacity stage in plastic soil)
    and it fits the memory budget, else Q1Q1 (:mod:`pilegroup.model.mesh_defaults`). A
    :class:`Scenario <pilegroup.model.scenario.Scenario>` always holds the resolved pair.
    """

    element: Literal["auto", "Q2Q1", "Q1Q1"] = "auto"
    """The element pair: Taylor-Hood or trilinear (each with its pressure stabilisation), or
    ``auto``: the one that fits."""
    newton_rtol: float = 1.0e-8
    """Newton's tolerance relative to each block's reference residual."""
    newton_atol: float = field(default=1.0e-9, metadata={"unit": "kN, m^3"})
    """Newton's absolute tolerance, added to the relative one (kN; m^3 for the pressure)."""
    symmetry: Literal["auto", "none", "quarter", "half_x", "half_y"] = "auto"
    """The part of the block modelled: all of it, a half or a quarter cut at mirror planes
    x = 0 and y = 0; ``auto``: the smallest the scenario's symmetry allows."""
    mesh: MeshOptions = field(default_factory=MeshOptions)
    time: TimeStepping = field(default_factory=TimeStepping)
    solver: LinearSolver = field(default_factory=LinearSolver)
    element_reason: str = field(default="", metadata={"derived": True})
    """Why the scenario holds its element pair (set by the scenario; not a scenario key)."""

    def __post_init__(self) -> None:
        for key in ("newton_rtol", "newton_atol"):
            require_positive(key, getattr(self, key), "-")
            check_bound(f"numerics.{key}", getattr(self, key))
        require_one_of("symmetry", self.symmetry, SYMMETRY_CHOICES)


@dataclass(frozen=True)
class Outputs:
    """What to write."""

    xdmf: bool = True
    """The fields at every output time, as XDMF (ParaView)."""
    plots: bool = True
    """The report's figures at the end of the run (``plots/*.png``)."""
    gauge_depths_m: tuple[float, ...] = field(default=(), metadata={
        "allowed": "increasing, each >= 0 and <= the shortest pile's length in soil"})
    """Depths below ground of the virtual strain gauge sections of every pile, top down."""
    checkpoint_every_min: float = field(default=0.0, metadata={"allowed": ">= 0"})
    """A checkpoint every this many minutes of wall time as well, at the next step boundary
    (0: only at the output times and on SIGTERM/SIGINT/SIGUSR1)."""
    cap_stiffness: bool = False
    """At the end, the loaded face's 6 x 6 stiffness matrix about the action point
    (``cap_stiffness.csv``, docs/model.md, "Cap actions"); the model is then the full one."""

    def __post_init__(self) -> None:
        for i, z in enumerate(self.gauge_depths_m):
            require_non_negative(f"gauge_depths_m[{i}]", z, "m")
            if i and not z > self.gauge_depths_m[i - 1]:
                raise ScenarioError(f"gauge_depths_m[{i}]", z,
                                    f"must be greater than gauge_depths_m[{i - 1}] = "
                                    f"{self.gauge_depths_m[i - 1]:g} (sections are listed top "
                                    "down, each below the one before)", "m")
        if not (is_finite_number(self.checkpoint_every_min)
                and self.checkpoint_every_min >= 0.0):
            raise ScenarioError("checkpoint_every_min", self.checkpoint_every_min,
                                "must be > 0 (minutes of wall time between checkpoints) or 0 "
                                "(off)", "min")
