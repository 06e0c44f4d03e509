"""The source paper's closed-form relations (Eqs. 13 and 17) and its Table 1 (Pier 667).

The formulas are pure math on scalars: the interface and soil laws use them (the laws with an
Eq. 13 cone get ``alpha`` and ``k`` from :class:`DruckerPragerCone`), and so does the scenario
model (``pilegroup.model`` derives a layer's interface friction angle from Eq. 17).

Table 1 is reference data: the scenario in ``pilegroup.model`` is the source of truth for runs;
this copy only feeds the constitutive tests and benchmarks. Units as in the paper's table: E in
MPa, c in kPa, angles in degrees, eta in "MPa·d" (read as MPa·d/m, see docs/model.md), gamma in
kN/m3.
"""

from __future__ import annotations

import math
from functools import cached_property


def delta_eq17(phi_deg: float) -> float:
    """Interface friction angle of Eq. 17, degrees: ``atan(sin phi cos phi / (1 + sin^2 phi))``."""
    ph = math.radians(phi_deg)
    return math.degrees(math.atan(math.sin(ph) * math.cos(ph) / (1.0 + math.sin(ph) ** 2)))


def dp_outer_cone(c: float, phi_deg: float) -> tuple[float, float]:
    """Drucker–Prager ``(alpha, k)`` of Eq. 13 (outer cone, compression meridian), k in kPa.

    ``alpha = 2 sin phi / (sqrt3 (3 - sin phi))``, ``k = 6 c cos phi / (sqrt3 (3 - sin phi))``
    for ``F = sqrt(J2) + alpha I1 - k`` with tension-positive ``I1``.
    """
    ph = math.radians(phi_deg)
    den = math.sqrt(3.0) * (3.0 - math.sin(ph))
    return 2.0 * math.sin(ph) / den, 6.0 * c * math.cos(ph) / den


class DruckerPragerCone:
    """Mixin of the laws that use the Eq. 13 cone of their strength ``c`` (kPa), ``phi_deg``."""

    c: float
    phi_deg: float

    @cached_property
    def alpha(self) -> float:
        """Drucker–Prager alpha of Eq. 13, -."""
        return dp_outer_cone(self.c, self.phi_deg)[0]

    @cached_property
    def k(self) -> float:
        """Drucker–Prager k of Eq. 13, kPa."""
        return dp_outer_cone(self.c, self.phi_deg)[1]


# layer: (H m, gamma kN/m3, E MPa, nu, phi deg, c kPa, e0, delta deg, K, n, R_f, eta MPa·d/m)
TABLE1: dict[int, dict[str, float | str | None]] = {}

_ROWS = [
    (1, "Clay", 0.4, 17.8, 6.8, 0.35, 6.6, 14.8, 0.9, 6.4, 515, 0.42, 0.11, 7.42),
    (2, "Mud", 19.3, 16.9, 3.0, 0.42, 2.6, 5.6, 1.2, 2.6, 296, 0.29, 0.27, 6.23),
    (3, "Mucky clay", 12.4, 17.4, 3.7, 0.40, 4.0, 10.2, 1.1, 4.0, 408, 0.28, 0.28, 6.40),
    (4, "Silty clay", 5.0, 18.5, 7.7, 0.35, 6.6, 18.4, 0.8, 6.4, 527, 0.41, 0.13, 12.31),
    (5, "Silt", 4.8, 19.0, 21.5, 0.30, 25.0, 7.4, 0.7, 18.0, 771, 0.40, 0.08, 27.00),
    (6, "Silty clay", 2.7, 18.5, 7.8, 0.35, 6.6, 18.4, 0.8, 6.4, 559, 0.43, 0.10, 10.61),
    (7, "Silty clay", 7.2, 18.5, 8.3, 0.35, 6.5, 18.7, 0.8, 6.3, 623, 0.45, 0.10, 11.99),
    (8, "Gravel soil", 8.2, 19.0, 30.0, 0.23, 35.0, 0.0, 0.4, 19.5, 820, 0.52, 0.09, 53.27),
    (9, "Silty clay", 4.3, 19.0, 14.5, 0.28, 15.0, 39.9, 0.8, 13.2, 787, 0.45, 0.10, 17.65),
    (10, "Silty clay", math.nan, 19.0, 29.3, 0.28, 12.6, 45.0, 0.8, None, None, None, None, None),
]
_KEYS = ("name", "H", "gamma", "E_MPa", "nu", "phi_deg", "c", "e0", "delta_deg", "K", "n",
         "R_f", "eta_MPa_day_per_m")
for _row in _ROWS:
    TABLE1[_row[0]] = dict(zip(_KEYS, _row[1:], strict=True))


def soil_kwargs(layer: int) -> dict[str, float]:
    """Soil-law keyword arguments (E kPa, nu, c kPa, phi_deg) of a Table 1 layer."""
    r = TABLE1[layer]
    return {"E": 1000.0 * float(r["E_MPa"]), "nu": float(r["nu"]), "c": float(r["c"]),
            "phi_deg": float(r["phi_deg"])}


def interface_kwargs(layer: int, k_normal: float = 1.0e5) -> dict[str, float]:
    """Interface-law keyword arguments of a Table 1 layer (eta converted to kPa·d/m)."""
    r = TABLE1[layer]
    if r["K"] is None:
        raise KeyError(f"layer {layer} has no interface parameters in Table 1")
    return {"K": float(r["K"]), "n": float(r["n"]), "R_f": float(r["R_f"]),
            "delta_deg": float(r["delta_deg"]), "c": float(r["c"]),
            "phi_deg": float(r["phi_deg"]), "eta": 1000.0 * float(r["eta_MPa_day_per_m"]),
            "k_normal": k_normal}
