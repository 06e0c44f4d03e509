"""The analysis's stages: what happens to the foundation and the ground, in order.

A stage's kind says which keys it takes (:data:`STAGE_KEYS`): the cap actions of a load stage
(about the scenario's action point, :mod:`pilegroup.model.actions`), a fill on the ground
surface, a lowered water table, the piles' installation, a capacity stage. Field names are the
TOML keys of ``[[stages]]`` with their unit. Validation happens when a stage is built; errors
are :class:`~pilegroup.errors.ScenarioError` naming the key, value, unit and what is allowed.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

from pilegroup.errors import ScenarioError
from pilegroup.model.bounds import check_bound
from pilegroup.validate import (
    is_finite_number,
    require_finite,
    require_non_negative,
    require_positive,
)

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

#: The range of a stage key that is another key's (:data:`pilegroup.model.bounds.BOUNDS`).
_FORCE = {"bound": "stages.force_kN"}
_MOMENT = {"bound": "stages.moment_kNm"}
_LOAD = {"bound": "stages.cap_load_kN", "allowed": "> 0"}
_NOT_ZERO = {"allowed": "not 0"}

#: Default of ``plunging_stiffness_ratio``: the foundation plunges once its tangent stiffness
#: falls below 2 % of its initial one (docs/model.md, "Capacity").
PLUNGING_STIFFNESS_RATIO = 0.02


@dataclass(frozen=True)
class Stage:
    """One analysis stage; the stages run in the order listed, the first one geostatic.

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
    """The stage's name in the outputs, e.g. ``"loading"``."""
    kind: Literal["geostatic", "load", "consolidation", "surcharge", "groundwater",
                  "installation", "capacity"]
    """What the stage does: ``geostatic``, the in-situ stresses (the first stage); ``load``
    ramps the cap actions over ``duration_day``; ``consolidation`` holds every action until
    ``until_day``; ``surcharge`` places a fill on the ground surface; ``groundwater`` lowers the
    water table by ``drawdown_m``; ``installation`` installs the piles and the cap (an
    instant); ``capacity`` raises the cap load until the foundation fails (the last stage)."""
    cap_load_kN: float | None = None
    """Load stage: the vertical cap load at the stage end, kN, downward positive."""
    Fz_kN: float | None = field(default=None, metadata=_FORCE | {"allowed": "<= 0"})
    """Load stage: the vertical cap action at the stage end, kN, z up (``-cap_load_kN``)."""
    Fx_kN: float | None = field(default=None, metadata=_FORCE)
    """Load stage: horizontal cap force along x at the stage end, kN."""
    Fy_kN: float | None = field(default=None, metadata=_FORCE)
    """Load stage: horizontal cap force along y at the stage end, kN."""
    Mx_kNm: float | None = field(default=None, metadata=_MOMENT)
    """Load stage: cap moment about the x axis at the stage end (right-hand rule), kN m."""
    My_kNm: float | None = field(default=None, metadata=_MOMENT)
    """Load stage: cap moment about the y axis at the stage end, kN m."""
    Mz_kNm: float | None = field(default=None, metadata=_MOMENT)
    """Load stage: cap torque about the z axis at the stage end, kN m."""
    duration_day: float | None = None
    """Load, surcharge and groundwater stages: the time over which the action is ramped, day."""
    until_day: float | None = field(default=None, metadata={
        "allowed": "after the stage's start, <= time.end_day"})
    """Consolidation stage: its end, day (default ``time.end_day``)."""
    surcharge_kPa: float | None = field(default=None, metadata=_NOT_ZERO)
    """Surcharge stage: pressure added on the ground surface, kPa (negative: a fill removed)."""
    area_m: tuple[float, float, float, float] | None = field(default=None, metadata={
        "allowed": "x_min < x_max, y_min < y_max, on the ground surface"})
    """Surcharge stage: the loaded rectangle ``[x_min, x_max, y_min, y_max]``, m, in the
    coordinates of the site (origin at the pile group's centre); default: the whole surface."""
    drawdown_m: float | None = field(default=None, metadata=_NOT_ZERO)
    """Groundwater stage: lowering of the water table, m (negative: the water table rises)."""
    max_load_kN: float | None = field(default=None, metadata=_LOAD)
    """Capacity stage: the largest cap load tried, kN (reached at the end of ``duration_day``
    unless the foundation fails first)."""
    plunging_stiffness_ratio: float | None = None
    """Capacity stage: plunging once the tangent stiffness of the load–settlement curve falls
    below this fraction of its initial value (default :data:`PLUNGING_STIFFNESS_RATIO`)."""
    single_pile_capacity_kN: float | None = field(default=None, metadata=_LOAD)
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
            check_bound("stages.plunging_stiffness_ratio", self.plunging_stiffness_ratio)
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
