"""What the laws and the initial state a run builds from a scenario need of it.

A run turns every layer into a soil law and, where the piles are joined to the soil, an
interface law, and starts from the in-situ state; each refuses input it cannot work with. The
rules here make the same refusals when the scenario is built, so that ``pilegroup scenario
validate`` makes them and a run makes them before meshing, with the scenario's key:

* the strength keys a model uses are given (``phi_deg``, ``c_kPa``: the plastic soil models
  and the interface law; :func:`check_strength_keys`), and give a strength (a Mohr-Coulomb or
  Drucker-Prager soil with ``c_kPa = 0`` and ``phi_deg = 0`` has none) and an interface friction
  (Eq. 17 gives ``delta = 0`` for ``phi_deg = 0``; :func:`check_laws`);
* the interface evaluated at Gauss points needs trilinear displacements
  (:func:`check_quadrature`);
* the installation pore pressures leave the horizontal effective stress compressive
  everywhere below the water table, and a Mohr-Coulomb or Drucker-Prager soil within its
  strength (:func:`strength_room`), with the in-situ state of :mod:`pilegroup.model.insitu`
  (:func:`check_installation`; the solver checks it again at the mesh's pressure nodes,
  ``pilegroup.solver.geostatic.SoilColumn.check_installation``).
"""

from __future__ import annotations

import math
from dataclasses import fields
from typing import NamedTuple, Protocol

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.model.analysis import INTERFACE_LAWS, PLASTIC_SOILS, InterfaceOptions, Numerics, Soil
from pilegroup.model.insitu import seepage, seepage_at, vertical_effective_stress
from pilegroup.model.piles import Piles
from pilegroup.model.site import Layer, Site
from pilegroup.model.soil_models import check_layer_model

#: Points per pile shaft at which the installation pore pressure is evaluated: the field of a
#: group is largest on a shaft (each pile's term is subharmonic in plan), and 360 points place
#: the largest within 0.01 % of a shaft's circumference of the true one.
SHAFT_POINTS = 360


class RuledScenario(Protocol):
    """What the rules read of a scenario (:class:`~pilegroup.model.scenario.Scenario`)."""

    site: Site
    layers: tuple[Layer, ...]
    piles: Piles
    soil: Soil
    interface: InterfaceOptions
    numerics: Numerics

    def layer_depths(self) -> tuple[float, ...]:
        """Depths of the layer boundaries, m."""


def _soil_model(sc: RuledScenario, layer: Layer) -> str:
    """The soil model of ``layer``: its own where it names one, else ``soil.model``."""
    return getattr(layer, "model", None) or sc.soil.model


def _has_interface_law(sc: RuledScenario, layer: Layer) -> bool:
    """Whether a run builds an interface law for ``layer`` (it has parameters, not tied)."""
    return sc.interface.mode in INTERFACE_LAWS and layer.interface is not None


def check_strength_keys(sc: RuledScenario) -> None:
    """Every layer gives the keys its soil law and interface law use.

    A field of a layer or of its ``interface`` table marks who uses it in its metadata
    (``soil_models``, ``interface_modes``); a key left out that the scenario's soil model or
    the layer's interface law uses is missing.
    """
    for i, layer in enumerate(sc.layers):
        law = _has_interface_law(sc, layer)
        tables = [(f"layers[{i}]", layer)] + ([(f"layers[{i}].interface", layer.interface)]
                                              if law else [])
        for key, table in tables:
            for f in fields(table):  # type: ignore[arg-type]
                if getattr(table, f.name) is not None or f.metadata.get("optional"):
                    continue  # an optional key: the model's own rule (check_laws)
                users = []
                model = _soil_model(sc, layer)
                if model in f.metadata.get("soil_models", ()):
                    users.append(f"the soil model {model!r}")
                if law and sc.interface.mode in f.metadata.get("interface_modes", ()):
                    users.append(f"the layer's interface law (interface.mode ="
                                 f" {sc.interface.mode!r})")
                if users:
                    raise ScenarioError(f"{key}.{f.name}", None, "missing key; expected a"
                                        f" number ({' and '.join(users)} uses it)")


def check_laws(sc: RuledScenario) -> None:
    """A plastic soil has a strength; an interface law has a friction angle."""
    for i, layer in enumerate(sc.layers):
        model = _soil_model(sc, layer)
        if model in PLASTIC_SOILS and layer.c_kPa == 0.0 and layer.phi_deg == 0.0:
            raise ScenarioError(f"layers[{i}].c_kPa", 0.0, "with phi_deg = 0 the layer has no"
                                f" strength in the soil model {model!r}: give c_kPa > 0 or"
                                " phi_deg > 0", "kPa")
        check_layer_model(layer, model, f"layers[{i}]")  # a critical-state model's needs
        if (_has_interface_law(sc, layer) and layer.interface.delta_deg is None  # type: ignore[union-attr]
                and layer.phi_deg == 0.0):
            raise ScenarioError(f"layers[{i}].interface.delta_deg", None, "missing: Eq. 17"
                                " gives delta = 0 from phi_deg = 0, an interface without"
                                " friction; give delta_deg in (0, 60)", "degree")


def check_quadrature(sc: RuledScenario) -> None:
    """The interface at Gauss points (``interface.quadrature = "gauss"``) needs Q1Q1."""
    num = sc.numerics
    if (sc.interface.mode not in INTERFACE_LAWS or sc.interface.quadrature != "gauss"
            or num.element == "Q1Q1"):
        return
    chose = (f"numerics.element = 'auto' chose {num.element!r} ({num.element_reason})"
             if num.element_reason.startswith("auto") else f"numerics.element = {num.element!r}")
    raise ScenarioError("interface.quadrature", "gauss", "needs numerics.element = 'Q1Q1' (its"
                        f" Gauss points lie on trilinear facets), but {chose}: set"
                        " numerics.element = 'Q1Q1', or interface.quadrature = 'nodal'")


def _largest_field(xy: np.ndarray, r0: np.ndarray, ratio: float) -> tuple[float, int, float]:
    """``(S, pile, angle)``: the largest sum of the piles' shape functions on their shafts.

    Each pile's term is ``ln(R/r) / ln(R/r0)`` (``R = ratio r0``, ``r`` clipped to
    ``[r0, R]``), as the solver evaluates it (``InstallationExcess.shape``).
    """
    t = np.linspace(0.0, 2.0 * math.pi, SHAFT_POINTS, endpoint=False)
    pts = (xy[:, None, :] + r0[:, None, None] * np.stack([np.cos(t), np.sin(t)], -1))
    pts = pts.reshape(-1, 2)
    r = np.hypot(pts[:, None, 0] - xy[None, :, 0], pts[:, None, 1] - xy[None, :, 1])
    r = np.clip(r, r0[None, :], ratio * r0[None, :])
    s = (np.log(ratio * r0[None, :] / r) / math.log(ratio)).sum(axis=1)
    k = int(np.argmax(s))
    return float(s[k]), k // SHAFT_POINTS, float(t[k % SHAFT_POINTS])


class InstallationPeak(NamedTuple):
    """Where the installation pore pressure comes closest to the horizontal effective stress.

    ``ratio``: ``u_i / (K0 (sigma'_v - u0))`` there (``inf``: no effective stress left at rest
    for it); ``pile`` (0-based) and ``angle`` (rad) the shaft point, ``depth`` (m) and
    ``layer`` (0-based) where it is.
    """

    ratio: float
    pile: int
    angle: float
    depth: float
    layer: int


def _cuts(sc: RuledScenario, seep: tuple[tuple[float, float], ...]) -> list[float]:
    """Depths (m) down to the deepest toe where the ratio's formula changes.

    The layer boundaries, the toes, the water table and the seepage's breakpoints: between two
    of them ``sigma'_v``, ``u0`` and the active piles are linear or fixed.
    """
    toe = max(sc.piles.lengths)
    depths = sorted({*sc.layer_depths(), *sc.piles.lengths, sc.site.water_table_depth_m,
                     *(d for d, _ in seep)})
    out: list[float] = []
    for d in depths:
        if d <= toe + 1e-9 and (not out or d > out[-1] + 1e-9):
            out.append(d)
    return out


class _Ratio:
    """``u_i / (K0 (sigma'_v - u0))`` on the shafts at a depth, from the in-situ state.

    ``sigma'_v`` with the water table (:func:`~pilegroup.model.insitu.vertical_effective_stress`),
    ``u0`` the layer's initial excess pore pressure plus the seepage at rest
    (:func:`~pilegroup.model.insitu.seepage_at`), as the solver's ``SoilColumn`` builds them.
    """

    def __init__(self, sc: RuledScenario) -> None:
        self.sc = sc
        self.seep = seepage(sc.site, sc.layers)
        self.xy = np.asarray(sc.piles.xy, dtype=float)
        self.r0 = np.asarray(sc.piles.diameters, dtype=float) / 2.0
        self.lengths = np.asarray(sc.piles.lengths, dtype=float)
        self._fields: dict[tuple[int, ...], tuple[float, int, float]] = {}

    def field(self, depth: float) -> tuple[float, int, float]:
        """``(S, pile, angle)`` of the piles whose toes are at or below ``depth``."""
        active = tuple(int(k) for k in np.flatnonzero(self.lengths >= depth - 1e-9))
        if active not in self._fields:
            ins = self.sc.piles.installation
            s, k, angle = _largest_field(self.xy[list(active)], self.r0[list(active)],
                                         ins.radius_ratio)  # type: ignore[union-attr]
            self._fields[active] = (s, active[k], angle)
        return self._fields[active]

    def at(self, depth: float, j: int, field_depth: float,
           shown: float | None = None) -> InstallationPeak:
        """The ratio at ``depth`` in layer ``j``, the piles active at ``field_depth``.

        ``shown``: the depth the peak names (a limit's end), else ``depth``.
        """
        sc, lay = self.sc, self.sc.layers[j]
        shown = depth if shown is None else shown
        sv = vertical_effective_stress(sc.site, sc.layers, depth)
        s, pile, angle = self.field(field_depth)
        if sv <= 0.0:  # the ground surface: no installation pore pressure
            return InstallationPeak(0.0, pile, angle, shown, j)
        u0 = lay.excess_pore_pressure_ratio * sv + lay.excess_pore_pressure_kPa
        u0 += seepage_at(self.seep, depth)
        room = lay.k0 * (sv - u0)
        if _soil_model(sc, lay) in PLASTIC_SOILS:
            room = min(room, strength_room(sv - u0, lay.k0, lay.phi_deg or 0.0, lay.c_kPa or 0.0))
        ratio = sc.piles.installation.excess_pore_pressure_ratio  # type: ignore[union-attr]
        q = math.inf if room <= 0.0 else ratio * sv * s / room
        return InstallationPeak(q, pile, angle, shown, j)


def strength_room(s: float, k0: float, phi_deg: float, c_kPa: float) -> float:
    """The largest pore pressure (kPa) the state at rest can take within Mohr-Coulomb.

    ``s`` the vertical effective stress at rest (kPa, compression positive), ``k0 s`` the
    horizontal one. A pore pressure ``u`` lowers both by ``u``; the state stays within
    ``sigma_1 - sigma_3 <= (sigma_1 + sigma_3) sin(phi) + 2 c cos(phi)`` for
    ``u <= ((1 + K0) s sin(phi) + 2 c cos(phi) - |1 - K0| s) / (2 sin(phi))`` (any ``u`` with
    ``phi = 0``). The Drucker-Prager outer cone coincides with it on the triaxial-compression
    meridian (``K0 <= 1``) and is wider elsewhere. A state at rest already beyond the strength
    (a ``K0`` the layer's ``c``, ``phi`` cannot hold) sets no bound here: that is the state the
    scenario gives, not one the installation makes.
    """
    sin, cos = math.sin(math.radians(phi_deg)), math.cos(math.radians(phi_deg))
    spare = (1.0 + k0) * s * sin + 2.0 * c_kPa * cos - abs(1.0 - k0) * s
    if sin <= 0.0 or spare < 0.0:
        return math.inf
    return spare / (2.0 * sin)


def installation_ratio(sc: RuledScenario) -> InstallationPeak | None:
    """The largest ratio of the installation pore pressure to the horizontal effective stress.

    The solver's check (``SoilColumn.check_installation``) at every depth the mesh can have
    a node: ``u_i = ratio sigma'_v S`` (``S`` the largest sum of the active piles' terms, on a
    shaft) against ``K0 (sigma'_v - u0)``, in the soil below the water table only (the dry soil
    above it takes no pore pressure; with the water table at the ground surface all of it).
    Between two depths of :func:`_cuts` the ratio is a quotient of two linear functions of
    depth, largest at an end: each end is taken as the limit from inside (the layer's own
    ``K0`` and ``u0``, the piles that reach below), and each depth itself with the lower
    layer's and the piles whose toes are there, as the solver takes a node on a boundary.
    None without installation pore pressures.
    """
    if sc.piles.installation is None:
        return None
    wt, rate = sc.site.water_table_depth_m, _Ratio(sc)
    cuts = _cuts(sc, rate.seep)
    bounds = sc.layer_depths()

    def layer(d: float) -> int:
        return max(k for k in range(len(sc.layers)) if bounds[k] <= d + 1e-9)

    worst = InstallationPeak(0.0, 0, 0.0, 0.0, 0)
    for top, bottom in zip(cuts[:-1], cuts[1:], strict=True):
        if wt > 0.0 and bottom <= wt + 1e-9:
            continue  # dry soil
        j, inside = layer(top), 1e-9 * (bottom - top)
        peaks = [rate.at(top + inside, j, bottom, top), rate.at(bottom - inside, j, bottom, bottom),
                 rate.at(bottom, layer(bottom), bottom)]
        if top > wt + 1e-9 or wt == 0.0:
            peaks.append(rate.at(top, j, top))
        worst = max([worst, *peaks], key=lambda p: p.ratio)
    return worst


def check_installation(sc: RuledScenario) -> None:
    """The installation pore pressure stays below the horizontal effective stress.

    Everywhere below the water table, with the in-situ state the run starts from
    (:func:`installation_ratio`): the solver checks the same at the mesh's pressure nodes.
    """
    peak = installation_ratio(sc)
    if peak is None or peak.ratio < 1.0:
        return
    ins = sc.piles.installation
    n, r0 = peak.pile, sc.piles.diameters[peak.pile] / 2.0
    x = sc.piles.xy[n][0] + r0 * math.cos(peak.angle)
    y = sc.piles.xy[n][1] + r0 * math.sin(peak.angle)
    where = (f"on the shaft of pile {n + 1} (x = {x:.3g}, y = {y:.3g} m, {peak.depth:g} m deep,"
             f" layer {peak.layer + 1}")
    reach = (f"reaches {peak.ratio:.3g} times what the soil can take there (the horizontal"
             " effective stress K0 (sigma'_v - u0), or less where the layer's Mohr-Coulomb"
             " strength c, phi would be exceeded first)"
             if math.isfinite(peak.ratio) else "meets no horizontal effective stress:"
             " the pore pressure at rest u0 (the layer's initial excess pore pressure and the"
             " seepage) already reaches sigma'_v")
    raise ScenarioError(
        "piles.installation.excess_pore_pressure_ratio",
        ins.excess_pore_pressure_ratio,  # type: ignore[union-attr]
        f"the installation pore pressure {reach} {where}; the fields of neighbouring piles add"
        " up): it must stay below it everywhere below the water table, or the soil would start"
        " with tensile effective stress or beyond its strength (lower the ratio or the"
        " radius_ratio)", "-")


def check_all(sc: RuledScenario) -> None:
    """Every rule of this module, in the order of the module text."""
    check_strength_keys(sc)
    check_laws(sc)
    check_quadrature(sc)
    check_installation(sc)


__all__ = ["SHAFT_POINTS", "InstallationPeak", "RuledScenario", "check_all",
           "check_installation", "check_laws", "check_quadrature", "check_strength_keys",
           "installation_ratio", "strength_room"]
