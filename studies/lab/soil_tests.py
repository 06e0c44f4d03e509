"""Element tests of the soil laws at one material point (no mesh): triaxial and oedometer.

Strains and stresses of the tables are the laboratory's: compression positive, effective
stresses (the laws work tension positive in Mandel notation, :mod:`pilegroup.constitutive.base`).
The soil laws are rate independent, so "drained" and "undrained" are kinematic conditions:

* **drained triaxial compression**: the cell pressure ``p0`` is held on the sides (the two
  lateral strains are found per step by Newton on the law's tangent), the axial strain grows;
* **undrained triaxial compression**: no volume change (lateral strains minus half the axial
  one); the excess pore pressure is what keeps the total lateral stress at ``p0``:
  ``u = p0 - sigma'_lateral`` (compression positive);
* **oedometer**: no lateral strain; the vertical effective stress is taken up by doubling
  from ``start`` to ``max`` and down again by halving (each value reached by Newton on the
  vertical strain), from a start at ``K0 = 1 - sin(phi)`` (Jaky; ``nu/(1 - nu)`` for a law
  without friction angle). The void ratio is ``e0 - (1 + e0) * vertical strain``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.studies.lab.lab_params import SoilLaw
from pilegroup.studies.lab.lab_tables import COLUMNS
from pilegroup.studies.results.tables import Table

#: Relative tolerance on a held stress.
STRESS_TOL = 1.0e-9


@dataclass(frozen=True)
class SoilProtocol:
    """What the soil tests do (stresses kPa, strains -)."""

    confining_stresses_kPa: tuple[float, ...] = (50.0, 100.0, 200.0)
    max_axial_strain: float = 0.15
    steps: int = 60
    oedometer_start_kPa: float = 12.5
    oedometer_max_kPa: float = 800.0

    def __post_init__(self) -> None:
        vals = self.confining_stresses_kPa
        if not vals or any(not (v > 0.0 and math.isfinite(v)) for v in vals):
            raise ScenarioError("--confining-stresses-kPa", list(vals),
                                "must be one or more numbers > 0")
        if not 0.0 < self.max_axial_strain <= 0.5:
            raise ScenarioError("--max-axial-strain", self.max_axial_strain, "must be in (0, 0.5]")
        if not 2 <= self.steps <= 100_000:
            raise ScenarioError("--steps", self.steps, "must be an integer in [2, 100000]")
        if not 0.0 < self.oedometer_start_kPa < self.oedometer_max_kPa:
            raise ScenarioError("--oedometer-max-kPa", self.oedometer_max_kPa,
                                f"must be > the start, {self.oedometer_start_kPa:g} kPa")


def _solve(law: SoilLaw, state: dict, d_eps: np.ndarray, free: list[int], target: np.ndarray
           ) -> tuple[dict, np.ndarray]:
    """The strain increment whose ``free`` components give stresses ``target`` there."""
    d = d_eps.copy()
    scale = max(float(np.abs(target).max()), 1.0)
    for _ in range(50):
        sig, st, tan = law.update(d[None, :], state, 0.0)
        r = sig[0, free] - target
        if np.abs(r).max() <= STRESS_TOL * scale:
            return st, d
        d[free] -= np.linalg.lstsq(tan[0][np.ix_(free, free)], r, rcond=None)[0]
    raise ConstitutiveError("a soil test step did not reach its held stresses in 50 Newton "
                            "iterations")


def _triaxial_curve(law: SoilLaw, p0: float, drainage: str, protocol: SoilProtocol,
                    curve: int, cols: dict[str, list]) -> None:
    st = law.initial_state(1, -p0 * np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0]))
    eps = np.zeros(6)
    de = protocol.max_axial_strain / protocol.steps
    for i in range(protocol.steps + 1):
        if i:
            d = np.array([0.5 * de, 0.5 * de, -de, 0.0, 0.0, 0.0])
            if drainage == "drained":
                st, d = _solve(law, st, d, [0, 1], np.array([-p0, -p0]))
            else:
                _, st, _ = law.update(d[None, :], st, 0.0)
            eps += d
        s = st["stress"][0]
        lateral = 0.5 * (s[0] + s[1])
        row = (drainage, curve, p0, -eps[2], -eps[:3].sum(), -s[:3].sum() / 3.0,
               lateral - s[2], 0.0 if drainage == "drained" else p0 + lateral)
        for c, v in zip(COLUMNS["triaxial"], row, strict=True):
            cols[c].append(v)


def triaxial_test(law: SoilLaw, protocol: SoilProtocol) -> Table:
    """Drained and undrained triaxial compression from each isotropic cell pressure."""
    cols: dict[str, list] = {c: [] for c in COLUMNS["triaxial"]}
    curve = 0
    for drainage in ("drained", "undrained"):
        for p0 in protocol.confining_stresses_kPa:
            curve += 1
            _triaxial_curve(law, p0, drainage, protocol, curve, cols)
    return {c: np.array(v, dtype=str if c == "drainage" else float) for c, v in cols.items()}


def oedometer_stresses(protocol: SoilProtocol) -> np.ndarray:
    """Vertical effective stresses of the oedometer steps: doubling up, halving down."""
    up = [protocol.oedometer_start_kPa]
    while up[-1] * 2.0 < protocol.oedometer_max_kPa * (1.0 + 1e-12):
        up.append(up[-1] * 2.0)
    if up[-1] < protocol.oedometer_max_kPa:
        up.append(protocol.oedometer_max_kPa)
    return np.array(up + up[-2::-1])


def oedometer_test(law: SoilLaw, e0: float, protocol: SoilProtocol) -> Table:
    """One-dimensional compression and unloading; ``e0`` the initial void ratio."""
    if not 0.0 < e0 < 10.0:
        raise ScenarioError("--e0", e0, "must be a void ratio in (0, 10)")
    phi = getattr(law, "phi_deg", None)
    k0 = 1.0 - math.sin(math.radians(phi)) if phi else law.nu / (1.0 - law.nu)
    levels = oedometer_stresses(protocol)
    sv0 = levels[0]
    st = law.initial_state(1, -np.array([k0 * sv0, k0 * sv0, sv0, 0.0, 0.0, 0.0]))
    cols: dict[str, list] = {c: [] for c in COLUMNS["oedometer"]}
    ez = 0.0
    for step, sv in enumerate(levels):
        if step:
            prev = -st["stress"][0, 2]
            for sub in range(1, 11):  # ten sub-steps per load step: the path, not just its end
                target = prev + (sv - prev) * sub / 10.0
                st, d = _solve(law, st, np.zeros(6), [2], np.array([-target]))
                ez += d[2]
        s = st["stress"][0]
        for c, v in zip(COLUMNS["oedometer"], (step, -ez, -s[2], -0.5 * (s[0] + s[1]),
                                                e0 + (1.0 + e0) * ez), strict=True):
            cols[c].append(v)
    return {c: np.array(v, dtype=float) for c, v in cols.items()}


__all__ = ["SoilProtocol", "oedometer_stresses", "oedometer_test", "triaxial_test"]
