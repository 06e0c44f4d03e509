"""Element tests of the soil laws at one material point (no mesh): triaxial compression.

Strains and stresses of the tables are the laboratory's: compression positive, effective
stresses (the laws work tension positive in Mandel notation, :mod:`pilegroup.constitutive.base`).
"Drained" and "undrained" are kinematic conditions:

* **drained triaxial compression**: the cell pressure ``p0`` is held on the sides (the two
  lateral strains are found per step by Newton on the law's tangent), the axial strain grows;
* **undrained triaxial compression**: no volume change (lateral strains minus half the axial
  one); the excess pore pressure is what keeps the total lateral stress at ``p0``:
  ``u = p0 - sigma'_lateral`` (compression positive).

The sample starts isotropic at ``p0`` (:func:`isotropic_state`): a critical-state law
consolidated isotropically to it, its pre-consolidation pressure ``OCR p0`` (or ``p0 + POP``).
The axial strain grows at ``strain_rate_per_day``, so each step lasts ``d eps_a / rate``: Soft
Soil Creep creeps over it, the other laws are rate independent. The oedometer is
:mod:`.oedometer_programme`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from pilegroup.constitutive.cam_clay import ModifiedCamClay
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
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
    step_days: float = 1.0
    creep_days: float = 30.0
    substeps_per_decade: int = 20
    strain_rate_per_day: float = 0.24

    def __post_init__(self) -> None:
        vals = self.confining_stresses_kPa
        if not vals or any(not (v > 0.0 and math.isfinite(v)) for v in vals):
            raise ScenarioError("--confining-stresses-kPa", list(vals),
                                "must be one or more numbers > 0")
        if not 0.0 < self.max_axial_strain <= 0.5:
            raise ScenarioError("--max-axial-strain", self.max_axial_strain, "must be in (0, 0.5]")
        if not 2 <= self.steps <= 100_000:
            raise ScenarioError("--steps", self.steps, "must be an integer in [2, 100000]")
        if not 0.0 < self.oedometer_start_kPa < 1e5:
            raise ScenarioError("--oedometer-start-kPa", self.oedometer_start_kPa,
                                "must be a stress in (0, 1e5) kPa")
        if not self.oedometer_start_kPa < self.oedometer_max_kPa < 1e6:
            raise ScenarioError("--oedometer-max-kPa", self.oedometer_max_kPa,
                                f"must be > the start, {self.oedometer_start_kPa:g} kPa")
        for key, v in (("--step-days", self.step_days), ("--creep-days", self.creep_days)):
            if not (0.0 < v <= 1e4 or (key == "--creep-days" and v == 0.0)):
                raise ScenarioError(key, v, "must be a duration in (0, 10000] days"
                                    + (" (0: no creep stage)" if key == "--creep-days" else ""))
        if not 2 <= self.substeps_per_decade <= 1000:
            raise ScenarioError("--substeps-per-decade", self.substeps_per_decade,
                                "must be an integer in [2, 1000]")
        if not 1e-8 <= self.strain_rate_per_day <= 1e6:
            raise ScenarioError("--axial-strain-rate-per-day", self.strain_rate_per_day,
                                "must be in [1e-8, 1e6] per day")


def _solve(law: SoilLaw, state: dict, d_eps: np.ndarray, free: list[int], target: np.ndarray,
           dt: float) -> tuple[dict, np.ndarray]:
    """The strain increment whose ``free`` components give stresses ``target`` there."""
    d = d_eps.copy()
    scale = max(float(np.abs(target).max()), 1.0)
    for _ in range(50):
        sig, st, tan = law.update(d[None, :], state, dt)
        r = sig[0, free] - target
        if np.abs(r).max() <= STRESS_TOL * scale:
            return st, d
        d[free] -= np.linalg.lstsq(tan[0][np.ix_(free, free)], r, rcond=None)[0]
    raise ConstitutiveError("a soil test step did not reach its held stresses in 50 Newton "
                            "iterations")


def isotropic_state(law: SoilLaw, p0: float) -> dict:
    """The state at the isotropic effective stress ``p0`` (kPa): consolidated to it.

    A critical-state law's pre-consolidation pressure is ``OCR p0 + POP`` (isotropic: Cam
    Clay's ``p_c``, Soft Soil Creep's ``p_p^eq``); so ``OCR = 1`` is normally consolidated.
    """
    stress = -p0 * np.array([1.0, 1.0, 1.0, 0.0, 0.0, 0.0])
    if isinstance(law, ModifiedCamClay):
        return law.initial_state(1, stress, pc0=law.OCR * p0 + law.POP)
    if isinstance(law, SoftSoilCreep):
        return law.initial_state(1, stress, pp0=law.OCR * p0 + law.POP)
    return law.initial_state(1, stress)


def _triaxial_curve(law: SoilLaw, p0: float, drainage: str, protocol: SoilProtocol,
                    curve: int, cols: dict[str, list]) -> None:
    st = isotropic_state(law, p0)
    eps = np.zeros(6)
    de = protocol.max_axial_strain / protocol.steps
    dt = de / protocol.strain_rate_per_day
    for i in range(protocol.steps + 1):
        if i:
            d = np.array([0.5 * de, 0.5 * de, -de, 0.0, 0.0, 0.0])
            if drainage == "drained":
                st, d = _solve(law, st, d, [0, 1], np.array([-p0, -p0]), dt)
            else:
                _, st, _ = law.update(d[None, :], st, dt)
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


__all__ = ["SoilProtocol", "isotropic_state", "triaxial_test"]
