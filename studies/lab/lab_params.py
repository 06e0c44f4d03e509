"""The parameters of a laboratory test: a scenario's layer, given values, or both.

Keys are the scenario's (``K``, ``n``, ``R_f``, ``delta_deg``, ``eta_MPa_day`` of
``layers[i].interface``, ``N`` of ``[interface]``; ``E_MPa``, ``nu``, ``c_kPa``, ``phi_deg``,
``psi_deg``, ``e0`` of ``layers[i]``; ``soil_model`` = the layer's ``model``, else ``soil.model``;
the critical-state keys of :mod:`.soft_soil_params`). A layer of a scenario
gives every key it has; a value given on the command line replaces the layer's. The laws are
built here from those values and checked on the way (an invalid or missing value is a
:class:`~pilegroup.errors.ScenarioError` naming the key: exit code 2).

The normal stress of every interface test is held constant, so the interface's normal penalty
stiffness does not enter the results; :data:`LAB_K_NORMAL` is only a valid value for it.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

from pilegroup.constitutive.interface_law import PileSoilInterface
from pilegroup.constitutive.soil import (
    DruckerPrager,
    LinearElastic,
    MohrCoulomb,
    require_elastic_constants,
)
from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.model import load_scenario
from pilegroup.model.site import InterfaceParams
from pilegroup.model.soil_models import layer_model
from pilegroup.studies.lab.soft_soil_params import (
    CRITICAL_KEYS,
    CRITICAL_STATE_LAWS,
    CRITICAL_STATE_MODELS,
    CriticalStateLaw,
    critical_state_law,
)
from pilegroup.validate import require_in_range, require_non_negative, require_positive

#: Normal penalty stiffness of the lab's interface, kPa/m (held normal stress: no effect).
LAB_K_NORMAL = 1.0e6
INTERFACE_KEYS = ("K", "n", "R_f", "delta_deg", "eta_MPa_day", "N")
SOIL_KEYS = ("E_MPa", "nu", "c_kPa", "phi_deg", "psi_deg", "e0", "soil_model") + CRITICAL_KEYS
#: The two readings of Eq. 15 (docs/model.md, item 4).
VARIANTS = ("default", "seed")
SOIL_MODELS = {"mohr_coulomb": MohrCoulomb, "drucker_prager": DruckerPrager,
               "linear_elastic": LinearElastic, **CRITICAL_STATE_LAWS}
SoilLaw = LinearElastic | MohrCoulomb | DruckerPrager | CriticalStateLaw


@dataclass(frozen=True)
class LabMaterial:
    """The values of one material point (scenario key -> value) and where they came from."""

    values: tuple[tuple[str, Any], ...]
    source: str

    def get(self, key: str) -> Any:
        """The value of ``key``, or ``None``."""
        return dict(self.values).get(key)

    def need(self, key: str, test: str) -> Any:
        """The value of ``key``; missing: invalid input naming the key and the test."""
        v = self.get(key)
        if v is None:
            raise ScenarioError(f"--{key}", None, f"missing: {test} needs it; give --scenario S "
                                f"--layer NAME or --{key} VALUE")
        return v

    def interface_law(self, variant: str = "default", test: str = "the interface test"
                      ) -> PileSoilInterface:
        """The interface law of these values, with the Eq. 15 reading ``variant``."""
        ip = _checked(lambda: InterfaceParams(
            K=self.need("K", test), n=self.need("n", test), R_f=self.need("R_f", test),
            eta_MPa_day=self.need("eta_MPa_day", test), delta_deg=self.get("delta_deg")))
        c, phi = self.need("c_kPa", test), self.need("phi_deg", test)
        N = self.get("N") or 1.0
        require_non_negative("c_kPa", c, "kPa", error=ScenarioError)
        require_in_range("phi_deg", phi, 0.0, 90.0, "deg", hi_open=True, error=ScenarioError)
        require_positive("N", N, "-", error=ScenarioError)
        return _checked(lambda: PileSoilInterface(
            K=ip.K, n=ip.n, R_f=ip.R_f, c=c, phi_deg=phi, eta=ip.eta, k_normal=LAB_K_NORMAL,
            delta_deg=ip.delta_deg, N=N, variant=variant))

    def interface_laws(self, test: str = "the interface test") -> dict[str, PileSoilInterface]:
        """Both readings of Eq. 15: ``{"default": law, "seed": law}``."""
        law = self.interface_law("default", test)
        return {v: replace(law, variant=v) for v in VARIANTS}

    def soil_law(self, test: str = "the soil test") -> SoilLaw:
        """The soil law (``soil_model``, default Mohr-Coulomb) of these values, E in kPa."""
        model = self.get("soil_model") or "mohr_coulomb"
        if model not in SOIL_MODELS:
            raise ScenarioError("--soil_model", model, "must be one of " + ", ".join(SOIL_MODELS))
        if model in CRITICAL_STATE_MODELS:
            return critical_state_law(self, model, test)
        E = 1000.0 * float(self.need("E_MPa", test))
        nu = self.need("nu", test)
        require_elastic_constants(E, nu, error=ScenarioError)
        if model == "linear_elastic":
            return _checked(lambda: LinearElastic(E, nu))
        return _checked(lambda: SOIL_MODELS[model](
            E, nu, self.need("c_kPa", test), self.need("phi_deg", test),
            self.get("psi_deg") or 0.0))


def _checked(build: Any) -> Any:
    """``build()``, a law's invalid parameter turned into invalid input (exit code 2)."""
    try:
        return build()
    except ConstitutiveError as exc:
        raise ScenarioError("law parameters", "given", str(exc)) from None


def layer_values(scenario: str, layer: str, sets: Mapping[str, Any] | None = None
                 ) -> tuple[dict[str, Any], str]:
    """The values of layer ``layer`` (its name, or its index in ``layers``) of a scenario."""
    sc = load_scenario(scenario, sets)
    names = [lay.name for lay in sc.layers]
    if layer in names:
        j = names.index(layer)
    elif layer.isdigit() and int(layer) < len(names):
        j = int(layer)
    else:
        raise ScenarioError("--layer", layer, f"no such layer in {sc.name!r}; its layers: "
                            + ", ".join(names) + " (or an index from 0)")
    lay = sc.layers[j]
    vals: dict[str, Any] = {"E_MPa": lay.E_MPa, "nu": lay.nu, "c_kPa": lay.c_kPa,
                            "phi_deg": lay.phi_deg, "psi_deg": lay.psi_deg, "e0": lay.e0,
                            "soil_model": layer_model(lay, sc.soil), "N": sc.interface.N}
    vals.update({k: getattr(lay, k) for k in CRITICAL_KEYS})
    if lay.interface is not None:
        ip = lay.interface
        vals.update(K=ip.K, n=ip.n, R_f=ip.R_f, delta_deg=ip.delta_deg,
                    eta_MPa_day=ip.eta_MPa_day)
    return vals, f"{sc.name} layers[{j}] ({lay.name})"


def lab_material(given: Mapping[str, Any], scenario: str | None = None,
                 layer: str | None = None, sets: Mapping[str, Any] | None = None
                 ) -> LabMaterial:
    """The values of a scenario's layer (if any), replaced by the ``given`` ones (not None)."""
    if (scenario is None) != (layer is None):
        raise ScenarioError("--layer" if scenario else "--scenario", layer or scenario,
                            "--scenario and --layer go together")
    vals: dict[str, Any] = {}
    source = "given values"
    if scenario is not None and layer is not None:
        vals, source = layer_values(scenario, layer, sets)
    given = {k: v for k, v in given.items() if v is not None}
    for k, v in given.items():
        if k != "soil_model" and not (isinstance(v, int | float) and math.isfinite(v)):
            raise ScenarioError(f"--{k}", v, "must be a finite number")
    if given and scenario is not None:
        source += " with " + ", ".join(f"{k} = {v}" for k, v in given.items())
    return LabMaterial(tuple({**vals, **given}.items()), source)


__all__ = ["INTERFACE_KEYS", "LAB_K_NORMAL", "LabMaterial", "SOIL_KEYS", "SOIL_MODELS",
           "SoilLaw", "VARIANTS", "lab_material", "layer_values"]
