"""Which soil law a layer uses, and the rules of the critical-state keys.

A layer names its law with ``model``; without it the scenario's ``soil.model`` holds
(:func:`layer_model`). Modified Cam Clay (Roscoe & Burland 1968) and Soft Soil Creep (Vermeer &
Neher 1999) take their parameters from keys of the layer (docs/model.md, "Soil models per
layer"): Cam Clay ``lam``, ``kappa``, ``M`` or ``phi_cs_deg``, the layer's ``nu`` and ``e0``;
Soft Soil Creep ``lambda_star``, ``kappa_star``, ``mu_star``, ``nu_ur``, ``tau_ref_day`` and the
layer's ``phi_deg`` and ``c_kPa``; both the layer's ``OCR`` or ``POP_kPa``.

Two sets of rules, each refused with one line naming the key:

* :func:`check_critical_state_keys`, when a layer is built, whatever its model: every given key
  in its range (:data:`~pilegroup.model.bounds.BOUNDS`), ``kappa < lam``,
  ``kappa_star < lambda_star``, not both ``M`` and ``phi_cs_deg``, not both ``OCR`` and
  ``POP_kPa``;
* :func:`check_layer_model`, when the scenario is built (:mod:`pilegroup.model.law_rules`):
  what the layer's model needs beyond the keys its fields mark as used (``soil_models``): Cam
  Clay one of ``M`` and ``phi_cs_deg``; Soft Soil Creep ``phi_deg > 0`` and an ellipse for its
  ``K0nc = 1 - sin phi`` (:func:`pilegroup.constitutive.critical_state.m_from_k0nc`, the one
  formula the law uses, so that the law never refuses what validation let through).
"""

from __future__ import annotations

import math
from typing import Any, Protocol

from pilegroup.constitutive.critical_state import m_from_k0nc
from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.model.analysis import Soil
from pilegroup.model.bounds import check_bound

__all__ = ["CriticalStateLayer", "check_critical_state_keys", "check_layer_model",
           "friction_for_k0", "k0nc", "layer_model"]

#: The critical-state keys of a layer checked against their range when given.
BOUNDED = ("lam", "kappa", "M", "phi_cs_deg", "POP_kPa", "lambda_star", "kappa_star",
           "mu_star", "nu_ur", "tau_ref_day")


class CriticalStateLayer(Protocol):
    """What the rules read of a layer (:class:`~pilegroup.model.site.Layer`)."""

    model: str | None
    nu: float
    phi_deg: float | None
    OCR: float | None
    lam: float | None
    kappa: float | None
    M: float | None
    phi_cs_deg: float | None
    POP_kPa: float | None
    lambda_star: float | None
    kappa_star: float | None
    mu_star: float | None
    nu_ur: float
    tau_ref_day: float


def layer_model(layer: CriticalStateLayer, soil: Soil) -> str:
    """The soil law of ``layer``: its own ``model``, else the scenario's ``soil.model``."""
    return layer.model if layer.model is not None else soil.model


def friction_for_k0(layer: CriticalStateLayer) -> float | None:
    """The friction angle (degree) of the layer's K0 at rest: ``phi_cs``, else ``phi_deg``.

    The critical-state angle of Modified Cam Clay's keys first (``phi_cs_deg``, or ``M`` with
    ``sin phi_cs = 3M/(6 + M)``, triaxial compression), so that the K0 at rest and the law's
    ``K0nc`` agree; else ``phi_deg``; None when the layer gives none of the three.
    """
    if layer.phi_cs_deg is not None:
        return layer.phi_cs_deg
    if layer.M is not None:
        return math.degrees(math.asin(3.0 * layer.M / (6.0 + layer.M)))
    return layer.phi_deg


def k0nc(layer: CriticalStateLayer) -> float | None:
    """Jaky's ``1 - sin phi`` of :func:`friction_for_k0` (the K0 of normal consolidation)."""
    phi = friction_for_k0(layer)
    return None if phi is None else 1.0 - math.sin(math.radians(phi))


def check_critical_state_keys(layer: CriticalStateLayer) -> None:
    """The critical-state keys given are in range and agree (the module doc's first rules)."""
    for key in BOUNDED:
        value: Any = getattr(layer, key)
        if value is not None:
            check_bound(f"layers.{key}", value)
    if layer.lam is not None and layer.kappa is not None and not layer.kappa < layer.lam:
        raise ScenarioError("kappa", layer.kappa, f"must be < lam = {layer.lam:g} (the"
                            " unloading-reloading line is flatter than the normal compression"
                            " line)", "-")
    if (layer.lambda_star is not None and layer.kappa_star is not None
            and not layer.kappa_star < layer.lambda_star):
        raise ScenarioError("kappa_star", layer.kappa_star, "must be < lambda_star ="
                            f" {layer.lambda_star:g} (the swelling line is flatter than the"
                            " compression line)", "-")
    if layer.M is not None and layer.phi_cs_deg is not None:
        raise ScenarioError("phi_cs_deg", layer.phi_cs_deg, "give either M or phi_cs_deg, not"
                            " both", "degree")
    if layer.POP_kPa is not None and layer.OCR is not None:
        raise ScenarioError("POP_kPa", layer.POP_kPa, "give either OCR or POP_kPa, not both",
                            "kPa")


def check_layer_model(layer: CriticalStateLayer, model: str, where: str) -> None:
    """What the layer's critical-state ``model`` needs beyond its required keys.

    ``where``: the layer's dotted path (``layers[2]``), which the messages name.
    """
    if model == "modified_cam_clay" and layer.M is None and layer.phi_cs_deg is None:
        raise ScenarioError(f"{where}.M", None, "missing key; expected a number (soil model"
                            " 'modified_cam_clay' uses M, or phi_cs_deg instead)", "-")
    if model != "soft_soil_creep" or layer.phi_deg is None:
        return  # phi_deg missing: the required-key rule names it
    if not layer.phi_deg > 0.0:
        raise ScenarioError(f"{where}.phi_deg", layer.phi_deg, "must be > 0 with soil model"
                            " 'soft_soil_creep' (K0nc = 1 - sin phi < 1 gives its ellipse)",
                            "degree")
    k0 = 1.0 - math.sin(math.radians(layer.phi_deg))
    try:
        m_from_k0nc(k0, float(layer.lambda_star or 1.0), float(layer.kappa_star or 0.5),
                    layer.nu_ur)
    except ConstitutiveError:
        raise ScenarioError(f"{where}.phi_deg", layer.phi_deg, f"gives K0nc = 1 - sin phi ="
                            f" {k0:.4g}, too small for lambda_star/kappa_star ="
                            f" {layer.lambda_star:g}/{layer.kappa_star:g} and nu_ur ="
                            f" {layer.nu_ur:g}: no ellipse of Soft Soil Creep gives it"
                            " (docs/model.md): a smaller phi_deg or nu_ur, or a larger"
                            " lambda_star/kappa_star",
                            "degree") from None
