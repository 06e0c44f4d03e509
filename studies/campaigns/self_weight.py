"""The settlement a model reports when its soil is loaded by its own weight: a closed form.

A finite-element model whose geostatic step does not start in equilibrium (the soil begins
stress-free and gravity is switched on) settles under the soil's own weight before any
foundation load; if that displacement is not reset, it is part of the reported settlement. On a
laterally confined column (a wide site) each layer is in one-dimensional (oedometric)
compression, so the settlement of the ground surface is the sum over the layers of

    s_j = int_j sigma'(z) dz / E_oed,j,   E_oed = E (1 - nu) / ((1 + nu)(1 - 2 nu)),

with ``sigma'`` the vertical effective stress at rest the skeleton carries once the soil has
drained (docs/model.md, "The ground at rest"; :mod:`pilegroup.model.insitu`): the soil's
total weight above the water table, its buoyant weight ``gamma - gamma_w`` below it, less the
seepage towards layers held at a piezometric level of their own (steady, it stays). The layers'
initial excess pore pressures are left out: they dissipate. ``sigma'`` is linear between the
layer boundaries, the water table and the seepage's breakpoints, so the trapezoidal rule
between them is exact; with the water table at the ground surface and no seepage
``s_j = H_j (sigma'_top,j + gamma'_j H_j / 2) / E_oed,j``. Linear elasticity with the layer's
E and nu; plastic yield would add to it. docs/results.md compares it with the paper's 30 cm.
"""

from __future__ import annotations

from dataclasses import dataclass

from pilegroup.model import Scenario
from pilegroup.model.insitu import seepage, seepage_at, vertical_effective_stress


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


def self_weight_settlement(sc: Scenario) -> list[LayerSettlement]:
    """Each layer's 1D elastic compression under the effective stress at rest (m), top down."""
    seep = seepage(sc.site, sc.layers)

    def stress(depth: float) -> float:
        """Vertical effective stress at rest (kPa) at ``depth`` (m)."""
        return vertical_effective_stress(sc.site, sc.layers, depth) - seepage_at(seep, depth)

    breaks = {sc.site.water_table_depth_m, *(d for d, _ in seep)}
    out: list[LayerSettlement] = []
    for i, lay in enumerate(sc.layers):
        top, bottom = sc.layer_top(i), sc.layer_bottom(i)
        cuts = sorted({top, bottom, *(d for d in breaks if top < d < bottom)})
        area = sum(0.5 * (b - t) * (stress(t) + stress(b))
                   for t, b in zip(cuts[:-1], cuts[1:], strict=True))
        out.append(LayerSettlement(lay.name, top, bottom,
                                   area / oedometric_modulus(lay.E, lay.nu)))
    return out
