"""The settlement a model reports when its soil is loaded by its own weight: a closed form.

A finite-element model whose geostatic step does not start in equilibrium (the soil begins
stress-free and gravity is switched on) settles under the soil's own buoyant weight before any
foundation load; if that displacement is not reset, it is part of the reported settlement. On a
laterally confined column (a wide site) each layer is in one-dimensional (oedometric)
compression, so the settlement of the ground surface is the sum over the layers of

    s_j = H_j (sigma'_top,j + gamma'_j H_j / 2) / E_oed,j,
    E_oed = E (1 - nu) / ((1 + nu)(1 - 2 nu)),   gamma' = gamma - gamma_w,

with the water table at the ground surface (linear elasticity with the layer's E and nu; plastic
yield would add to it). docs/results.md compares it with the paper's 30 cm.
"""

from __future__ import annotations

from dataclasses import dataclass

from pilegroup.model import Scenario
from pilegroup.model.units import GAMMA_WATER


@dataclass(frozen=True)
class LayerSettlement:
    """One layer's share: name, top and bottom depth (m), settlement (m)."""

    name: str
    top_m: float
    bottom_m: float
    settlement_m: float


def oedometric_modulus(E: float, nu: float) -> float:
    """Constrained (oedometric) modulus, same unit as ``E``."""
    return E * (1.0 - nu) / ((1.0 + nu) * (1.0 - 2.0 * nu))


def self_weight_settlement(sc: Scenario, gamma_w: float = GAMMA_WATER) -> list[LayerSettlement]:
    """Each layer's 1D elastic compression under the buoyant weight of the soil (m), top down."""
    out: list[LayerSettlement] = []
    sigma = 0.0  # effective vertical stress at the layer top, kPa
    for i, lay in enumerate(sc.layers):
        top, bottom = sc.layer_top(i), sc.layer_bottom(i)
        h = bottom - top
        g = lay.gamma_kN_per_m3 - gamma_w
        s = h * (sigma + 0.5 * g * h) / oedometric_modulus(lay.E, lay.nu)
        out.append(LayerSettlement(lay.name, top, bottom, s))
        sigma += g * h
    return out
