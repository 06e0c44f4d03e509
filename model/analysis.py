"""How the analysis is run: modelling options, stages, time, mesh, numerics, outputs.

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
    require_in_range,
    require_non_negative,
    require_one_of,
    require_positive,
)


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
        for key in ("N", "normal_stiffness_factor"):
            require_positive(key, getattr(self, key), "-")
            check_bound(f"interface.{key}", getattr(self, key))


#: The keys each stage kind takes (required first, then optional), beside ``name`` and ``kind``.
STAGE_KEYS: dict[str, tuple[tuple[str, ...], tuple[str, ...]]] = {
    "geostatic": ((), ()),
    "load": (("duration_day",), ("cap_load_kN", "Fz_kN", "Fx_kN", "Fy_kN", "Mx_kNm", "My_kNm",
                                 "Mz_kNm")),
    "consolidation": ((), ("until_day",)),
    "surcharge": (("surcharge_kPa", "duration_day"), ("area_m",)),
    "groundwater": (("drawdown_m", "duration_day"), ()),
    "installation": ((), ()),
    "capacity": (("max_load_kN", "duration_day"),
                 ("plunging_stiffness_ratio", "single_pile_capacity_kN")),
}
_STAGE_UNITS = {"cap_load_kN": "kN", "duration_day": "day", "until_day": "day",
                "surcharge_kPa": "kPa", "area_m": "m", "drawdown_m": "m", "max_load_kN": "kN",
                "plunging_stiffness_ratio": "-", "single_pile_capacity_kN": "kN",
                "Fx_kN": "kN", "Fy_kN": "kN", "Fz_kN": "kN", "Mx_kNm": "kN m", "My_kNm": "kN m",
                "Mz_kNm": "kN m"}
#: The six cap actions of a load stage, in the order of the components (Fx, Fy, Fz, Mx, My, Mz).
ACTION_KEYS = ("Fx_kN", "Fy_kN", "Fz_kN", "Mx_kNm", "My_kNm", "Mz_kNm")

#: Default of ``plunging_stiffness_ratio``: the foundation plunges once its tangent stiffness
#: falls below 2 % of its initial one (docs/model.md, "Capacity").
PLUNGING_STIFFNESS_RATIO = 0.02


@dataclass(frozen=True)
class Stage:
    """One analysis stage.

    ``kind``: ``geostatic`` (in-situ stresses, no time), ``load`` (ramps the cap actions to their
    values at the stage end over ``duration_day``, drained top, consolidating meanwhile: the
    vertical load ``cap_load_kN`` (down) or ``Fz_kN`` (z up), and optionally ``Fx_kN``,
    ``Fy_kN``, ``Mx_kNm``, ``My_kNm``, ``Mz_kNm`` in global axes about the scenario's action
    point, docs/model.md, "Cap actions"; a component a stage omits keeps its value),
    ``consolidation``
    (every action held until ``until_day``, or until ``time.end_day`` when omitted),
    ``surcharge`` (a pressure ``surcharge_kPa`` placed on the ground surface over
    ``duration_day``: a fill or an embankment, over the whole surface or the rectangle
    ``area_m``, never beneath the cap, and held afterwards) or ``groundwater`` (the water
    table lowered by ``drawdown_m`` over ``duration_day``, held afterwards) or ``installation``
    (the moment the piles and cap are installed, instantaneous: before it the ground moves
    without them) or ``capacity`` (the cap load raised linearly from its value so far to
    ``max_load_kN`` over ``duration_day`` until the foundation fails: the last stage; its
    result is the load–settlement curve and the ultimate capacity, docs/model.md, "Capacity").
    Every action keeps its value in the stages that follow; docs/model.md ("Ground that
    moves") gives the physics.
    """

    name: str
    kind: Literal["geostatic", "load", "consolidation", "surcharge", "groundwater",
                  "installation", "capacity"]
    cap_load_kN: float | None = None
    """Load stage: the vertical cap load at the stage end, kN, downward positive."""
    Fz_kN: float | None = None
    """Load stage: the vertical cap action at the stage end, kN, z up (``-cap_load_kN``)."""
    Fx_kN: float | None = None
    """Load stage: horizontal cap force along x at the stage end, kN."""
    Fy_kN: float | None = None
    """Load stage: horizontal cap force along y at the stage end, kN."""
    Mx_kNm: float | None = None
    """Load stage: cap moment about the x axis at the stage end (right-hand rule), kN m."""
    My_kNm: float | None = None
    """Load stage: cap moment about the y axis at the stage end, kN m."""
    Mz_kNm: float | None = None
    """Load stage: cap torque about the z axis at the stage end, kN m."""
    duration_day: float | None = None
    """Load, surcharge and groundwater stages: the time over which the action is ramped, day."""
    until_day: float | None = None
    """Consolidation stage: its end, day (default ``time.end_day``)."""
    surcharge_kPa: float | None = None
    """Surcharge stage: pressure added on the ground surface, kPa (negative: a fill removed)."""
    area_m: tuple[float, float, float, float] | None = None
    """Surcharge stage: the loaded rectangle ``[x_min, x_max, y_min, y_max]``, m, in the
    coordinates of the site (origin at the pile group's centre); default: the whole surface."""
    drawdown_m: float | None = None
    """Groundwater stage: lowering of the water table, m (negative: the water table rises)."""
    max_load_kN: float | None = None
    """Capacity stage: the largest cap load tried, kN (reached at the end of ``duration_day``
    unless the foundation fails first)."""
    plunging_stiffness_ratio: float | None = None
    """Capacity stage: plunging once the tangent stiffness of the load–settlement curve falls
    below this fraction of its initial value (default :data:`PLUNGING_STIFFNESS_RATIO`)."""
    single_pile_capacity_kN: float | None = None
    """Capacity stage: the capacity of one pile alone (e.g. from a capacity run of the single
    pile), kN; the group efficiency is reported when it is given."""

    def __post_init__(self) -> None:
        required, optional = STAGE_KEYS[self.kind]
        for key in _STAGE_UNITS:
            value = getattr(self, key)
            if key in required and value is None:
                raise ScenarioError(key, None, f"missing: required for a {self.kind} stage",
                                    _STAGE_UNITS[key])
            if value is not None and key not in required + optional:
                kinds = [k for k, (r, o) in STAGE_KEYS.items() if key in r + o]
                raise ScenarioError(key, value, f"not allowed for a {self.kind} stage (only for"
                                    f" {' and '.join(kinds)})", _STAGE_UNITS[key])
        if self.cap_load_kN is not None:
            require_non_negative("cap_load_kN", self.cap_load_kN, "kN")
            check_bound("stages.cap_load_kN", self.cap_load_kN)
        self._check_actions()
        for key in ("max_load_kN", "single_pile_capacity_kN"):
            if getattr(self, key) is not None:
                require_positive(key, getattr(self, key), "kN")
                check_bound("stages.cap_load_kN", getattr(self, key), key)
        if self.plunging_stiffness_ratio is not None:
            require_in_range("plunging_stiffness_ratio", self.plunging_stiffness_ratio, 0.0, 1.0,
                             "-", lo_open=True, hi_open=True)
        if self.duration_day is not None:
            require_positive("duration_day", self.duration_day, "day")
            check_bound("stages.duration_day", self.duration_day)
        if self.until_day is not None:  # a day on the analysis's time axis (may be < 0)
            require_finite("until_day", self.until_day, "day")
            check_bound("stages.until_day", self.until_day)
        for key in ("surcharge_kPa", "drawdown_m"):
            if getattr(self, key) is not None:
                if not is_finite_number(getattr(self, key)) or getattr(self, key) == 0.0:
                    raise ScenarioError(key, getattr(self, key), "must be a non-zero number",
                                        _STAGE_UNITS[key])
                check_bound(f"stages.{key}", getattr(self, key))
        if self.area_m is not None:
            x0, x1, y0, y1 = self.area_m
            if not (is_finite_number(x0) and is_finite_number(x1) and x0 < x1
                    and is_finite_number(y0) and is_finite_number(y1) and y0 < y1):
                raise ScenarioError("area_m", list(self.area_m),
                                    "must be [x_min, x_max, y_min, y_max] with x_min < x_max and"
                                    " y_min < y_max", "m")


    def _check_actions(self) -> None:
        """A load stage gives its vertical load once; every action is a finite number in range."""
        if self.kind == "load" and (self.cap_load_kN is None) == (self.Fz_kN is None):
            given = self.cap_load_kN if self.cap_load_kN is not None else self.Fz_kN
            raise ScenarioError("cap_load_kN", given, "give the vertical load of a load stage "
                                "once: cap_load_kN (downward) or Fz_kN (z up), not "
                                + ("both" if given is not None else "neither"), "kN")
        for key in ACTION_KEYS:
            value = getattr(self, key)
            if value is None:
                continue
            require_finite(key, value, _STAGE_UNITS[key])
            check_bound("stages.force_kN" if key.endswith("_kN") else "stages.moment_kNm",
                        value, key)
        if self.Fz_kN is not None and self.Fz_kN > 0.0:
            raise ScenarioError("Fz_kN", self.Fz_kN, "must be <= 0 (z is up: a downward load is"
                                " negative; uplift of the foundation is not modelled)", "kN")

    def given_actions(self) -> tuple[float | None, ...]:
        """Load stage: the six actions it gives, ``ACTION_KEYS`` order, ``Fz = -vertical``.

        ``None`` where it gives none (the value before is held).
        """
        v = self.vertical_kN
        return tuple((None if v is None else -v) if k == "Fz_kN" else getattr(self, k)
                     for k in ACTION_KEYS)

    @property
    def vertical_kN(self) -> float | None:
        """Load stage: the vertical load at its end, kN, downward positive (else ``None``)."""
        if self.cap_load_kN is not None:
            return self.cap_load_kN
        return None if self.Fz_kN is None else -self.Fz_kN


@dataclass(frozen=True)
class Time:
    """Start and end of the analysis and the times at which outputs are written (day).

    Day 0 is the piles' installation when a stage of kind ``installation`` says when (the
    ground may move from ``start_day < 0`` on); otherwise the analysis starts at 0.
    """

    end_day: float
    output_days: tuple[float, ...] = ()
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

    size_m: float | None = None
    """Plan size of the elements next to the piles, m: h of the paper's mesh study."""
    far_field_size_m: float | None = None
    """Plan size the elements grow to away from the piles, m."""
    growth: float | None = None
    """Plan size growth ratio per element, in (1, 2]."""
    n_circ_min: int | None = None
    """At least this many element edges around a pile (a multiple of 4, >= 8)."""
    dz_surface_m: float | None = None
    """Vertical element size at the ground surface, m."""
    dz_toe_m: float | None = None
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
                require_in_range(key, getattr(self, key), 1.0, 2.0, "-", lo_open=True)
        if self.n_circ_min is not None:
            if self.n_circ_min < 8 or self.n_circ_min % 4:
                raise ScenarioError("n_circ_min", self.n_circ_min,
                                    "must be a multiple of 4, >= 8", "-")
            check_bound("numerics.mesh.n_circ_min", self.n_circ_min)
        require_in_range("scale", self.scale, 0.2, 5.0, "-")
        if self.min_layer_divisions is not None:
            if self.min_layer_divisions < 1:
                raise ScenarioError("min_layer_divisions", self.min_layer_divisions,
                                    "must be an integer >= 1", "-")
            check_bound("numerics.mesh.min_layer_divisions", self.min_layer_divisions)


@dataclass(frozen=True)
class TimeStepping:
    """Adaptive backward-Euler stepping (day)."""

    dt_initial_day: float = 0.5
    """First step, day."""
    dt_min_day: float = 1.0e-4
    """Smallest step, day: the run stops when a cut-back would go below it."""
    dt_max_day: float = 20.0
    """Largest step, day."""
    grow_factor: float = 1.5
    """Factor on the step after an easy step (>= 1)."""
    cut_factor: float = 0.25
    """Factor on the step after a failed step, in (0, 1)."""
    max_newton: int = 15
    """Newton iterations at most; a step that needs more fails (and is cut back)."""
    easy_newton: int = 4
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
        require_in_range("cut_factor", self.cut_factor, 0.0, 1.0, "-", lo_open=True, hi_open=True)
        if self.max_newton < 1:
            raise ScenarioError("max_newton", self.max_newton, "must be an integer >= 1")
        check_bound("numerics.time.max_newton", self.max_newton)
        if not 1 <= self.easy_newton <= self.max_newton:
            raise ScenarioError("easy_newton", self.easy_newton,
                                f"must be in [1, max_newton = {self.max_newton}]")


@dataclass(frozen=True)
class LinearSolver:
    """PETSc linear solver: a named preset merged with user ``options``.

    ``options`` are PETSc option names without the problem prefix. ``auto`` takes the preset
    measured fastest for the system's model part, interface and size
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
                    "fieldsplit_kept"] = "auto"
    options: dict[str, str | int | float | bool] = field(default_factory=dict)
    krylov_forcing: float = 0.1

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

    ``element``: ``Q1Q1`` (trilinear displacement and pressure, stabilised), ``Q2Q1``
    (triquadratic displacement, Taylor–Hood) or ``auto`` (default): Q2Q1 where trilinear
    hexahedra lock (horizontal actions, a capacity stage in plastic soil) and it fits the memory
    budget, else Q1Q1 (:mod:`pilegroup.model.mesh_defaults`). A :class:`Scenario
    <pilegroup.model.scenario.Scenario>` always holds the resolved pair.
    """

    element: Literal["auto", "Q2Q1", "Q1Q1"] = "auto"
    newton_rtol: float = 1.0e-8
    newton_atol: float = 1.0e-9
    symmetry: Literal["auto", "none", "quarter", "half_x", "half_y"] = "auto"
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
    """What to write.

    ``gauge_depths_m``: depths below ground of the pile gauge sections, top down (strictly
    increasing).

    ``checkpoint_every_min``: a checkpoint every this many minutes of wall time as well, at
    the next step boundary (0: only at the output times and on SIGTERM/SIGINT/SIGUSR1).

    ``cap_stiffness``: at the end of the run, the loaded face's 6 x 6 stiffness matrix about the
    action point (``cap_stiffness.csv``; docs/model.md, "Cap actions"): the model is then the
    full one, with every action component on the face.
    """

    xdmf: bool = True
    plots: bool = True
    gauge_depths_m: tuple[float, ...] = ()
    checkpoint_every_min: float = 0.0
    cap_stiffness: bool = False

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
