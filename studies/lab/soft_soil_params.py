"""The critical-state laws of a laboratory test: Modified Cam Clay and Soft Soil Creep.

Built from a material point's values (a scenario's layer and/or the command line) under the
layer's key names (docs/model.md, "Soil models per layer"): Cam Clay ``lam``, ``kappa``, ``M``
or ``phi_cs_deg``, ``nu``, ``e0``; Soft Soil Creep ``lambda_star``, ``kappa_star``,
``mu_star``, ``phi_deg``, ``c_kPa``, ``nu_ur``, ``tau_ref_day``; both ``OCR`` or ``POP_kPa``.

The scenario's rules decide, so that the lab refuses what a scenario refuses:

* which keys a model needs and which defaults it has are read from the fields of
  :class:`~pilegroup.model.site.Layer` (their ``soil_models`` metadata, as the scenario's
  required-key rule reads them), with the layer's ``nu`` and ``e0`` for Cam Clay;
* the values are checked by :func:`~pilegroup.model.soil_models.check_critical_state_keys`
  and :func:`~pilegroup.model.soil_models.check_layer_model` and the ranges of
  :data:`~pilegroup.model.bounds.BOUNDS`.

A refusal is a :class:`~pilegroup.errors.ScenarioError` naming the key as its option
(``--kappa_star``): exit code 2. Cam Clay's ``K0nc`` is the layer's (Jaky's ``1 - sin phi_cs``,
:func:`~pilegroup.model.soil_models.k0nc`), as a run builds it (``studies/run/pipeline.py``).
"""

from __future__ import annotations

import dataclasses
from types import SimpleNamespace
from typing import Any, Protocol

from pilegroup.constitutive.cam_clay import ModifiedCamClay
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.model.bounds import BOUNDS, check_bound
from pilegroup.model.site import Layer
from pilegroup.model.soil_models import check_critical_state_keys, check_layer_model, k0nc

#: The critical-state soil models (the scenario's names) and their laws.
CRITICAL_STATE_LAWS = {"modified_cam_clay": ModifiedCamClay, "soft_soil_creep": SoftSoilCreep}
CRITICAL_STATE_MODELS = tuple(CRITICAL_STATE_LAWS)
#: The critical-state keys of a layer the lab takes (besides ``nu``, ``e0``, ``phi_deg``,
#: ``c_kPa``, which the other soil laws use too).
CRITICAL_KEYS = ("lam", "kappa", "M", "phi_cs_deg", "lambda_star", "kappa_star", "mu_star",
                 "nu_ur", "tau_ref_day", "OCR", "POP_kPa")
#: Keys checked against their range when given (the layer's own checks of them).
_RANGED = ("e0", "nu", "phi_deg", "c_kPa", "OCR")
CriticalStateLaw = ModifiedCamClay | SoftSoilCreep


class LabValues(Protocol):
    """What the laws read of a material point (:class:`~.lab_params.LabMaterial`)."""

    def get(self, key: str) -> Any:
        """The value of ``key``, or ``None``."""


def model_keys(model: str) -> tuple[tuple[str, ...], dict[str, Any]]:
    """The keys ``model`` requires and the defaults of those it may take, from ``Layer``."""
    required: list[str] = ["nu", "e0"] if model == "modified_cam_clay" else []
    defaults: dict[str, Any] = {}
    for f in dataclasses.fields(Layer):
        if model not in f.metadata.get("soil_models", ()):
            continue
        if f.default is not dataclasses.MISSING and f.default is not None:
            defaults[f.name] = f.default
        elif not f.metadata.get("optional"):
            required.append(f.name)
    return tuple(required), defaults


def _interval(key: str) -> str:
    """The range of a layer's key, e.g. ``(0, 0.1]``."""
    b = BOUNDS[f"layers.{key}"]
    return f"{'(' if b.lo_open else '['}{b.lo:g}, {b.hi:g}{')' if b.hi_open else ']'}"


def _as_option(exc: ScenarioError) -> ScenarioError:
    """The scenario rule's refusal with its key as the lab's option (``layer.M`` -> ``--M``)."""
    return ScenarioError("--" + exc.key.rsplit(".", 1)[-1], exc.value, exc.allowed, exc.unit)


def checked_values(values: LabValues, model: str, test: str, fitted: tuple[str, ...] = ()
                   ) -> dict[str, Any]:
    """The values of ``model``'s keys (defaults filled), checked by the scenario's rules.

    ``fitted``: keys a fit finds (not needed, left None; the ellipse's check then takes
    ``kappa_star/lambda_star = 1/2``, as the scenario's rule does for keys it lacks).
    """
    required, defaults = model_keys(model)
    vals = {k: values.get(k) for k in (*CRITICAL_KEYS, *_RANGED)}
    vals.update({k: v for k, v in defaults.items() if vals.get(k) is None})
    vals.update(dict.fromkeys(fitted))
    for k in required:
        if k not in fitted and vals[k] is None:
            raise ScenarioError(f"--{k}", None, f"missing: soil model {model!r} needs it "
                                f"({test}): a number in {_interval(k)}; give --scenario S "
                                f"--layer NAME or --{k} VALUE")
    layer = SimpleNamespace(**vals, model=model)
    try:
        for k in _RANGED:
            if vals[k] is not None:
                check_bound(f"layers.{k}", vals[k])
        check_critical_state_keys(layer)  # type: ignore[arg-type]
        check_layer_model(layer, model, "layer")  # type: ignore[arg-type]
    except ScenarioError as exc:
        raise _as_option(exc) from None
    return vals


def critical_state_law(values: LabValues, model: str, test: str) -> CriticalStateLaw:
    """Modified Cam Clay or Soft Soil Creep of these values (kPa, days)."""
    v = checked_values(values, model, test)
    pre = {"OCR": 1.0 if v["OCR"] is None else float(v["OCR"]),
           "POP": 0.0 if v["POP_kPa"] is None else float(v["POP_kPa"])}
    try:
        if model == "modified_cam_clay":
            return ModifiedCamClay(v["lam"], v["kappa"], v["e0"], M=v["M"],
                                   phi_cs_deg=v["phi_cs_deg"], nu=v["nu"],
                                   K0nc=k0nc(SimpleNamespace(**v)), **pre)  # type: ignore[arg-type]
        return SoftSoilCreep(v["lambda_star"], v["kappa_star"], v["mu_star"], v["phi_deg"],
                             c=v["c_kPa"] or 0.0, nu_ur=v["nu_ur"], tau=v["tau_ref_day"], **pre)
    except ConstitutiveError as exc:
        raise ScenarioError("law parameters", "given", str(exc)) from None


__all__ = ["CRITICAL_KEYS", "CRITICAL_STATE_LAWS", "CRITICAL_STATE_MODELS", "CriticalStateLaw",
           "LabValues", "checked_values", "critical_state_law", "model_keys"]
