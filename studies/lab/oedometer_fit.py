"""Soft Soil Creep's ``lambda_star``, ``kappa_star``, ``mu_star`` (and ``OCR``) from an oedometer.

The data (:func:`read_oedometer`): an oedometer CSV in the layout of ``pilegroup lab`` or a
user's with the columns ``step``, ``time_day``, ``vertical_stress_kPa`` (effective, compression
positive) and ``vertical_strain`` (compression positive), readings in time order. The rows of
one ``step`` number (consecutive) are the readings of one load step at its held stress; the
first step is the start (the sample's stress before the first load); a step's load is applied
at the time of the previous step's last reading (at once). Strains count from the first
reading.

The model: the law itself (:class:`~pilegroup.constitutive.soft_soil_creep.SoftSoilCreep`) run
through the file's steps and reading times by the lab's oedometer
(:func:`~.oedometer_programme.run_programme`: K0nc start, instantaneous loads, backward-Euler
holds), so loading, creep and unloading steps all count. The held keys ``phi_deg`` (needed: it
gives K0nc and the ellipse), ``nu_ur`` and ``tau_ref_day`` (the layer's defaults) come from
``--scenario S --layer NAME`` and/or are given; they are checked by the scenario's rules
(:func:`~.soft_soil_params.checked_values`).

The fit: :func:`scipy.optimize.least_squares` (bounded, ``trf``) on ``(lambda*,
kappa*/lambda*, mu*[, OCR])`` within the scenario's ranges (model/bounds.py; the ratio below
what leaves an ellipse for K0nc, :func:`~pilegroup.constitutive.critical_state.m_from_k0nc`),
residuals relative (``model/measured - 1`` of every reading with strain > 0). The standard
errors and correlations of ``lambda_star``, ``kappa_star``, ``mu_star`` (``OCR``) are those of
:mod:`.fit_stats` with the Jacobian carried over to them by the chain rule. Start: the
classical constructions (secant slopes of the end-of-step strains against ``ln sigma'_v``
while loading and unloading; the slope against ``ln t`` late in the longest hold).

``OCR`` is fitted when the curve starts over-consolidated (the first loading step's secant
slope below 0.8 of the steepest; else the sample is normally consolidated at its first
stress, ``OCR`` held at 1) unless ``--OCR`` holds it; an ``OCR`` that ends on 1 is refitted
held there.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from scipy.optimize import least_squares

from pilegroup.constitutive.critical_state import m_from_k0nc
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
from pilegroup.errors import ConstitutiveError, ScenarioError
from pilegroup.model.bounds import BOUNDS
from pilegroup.studies.lab.fit_stats import FitResult, check_converged, rms, statistics
from pilegroup.studies.lab.lab_params import LabMaterial
from pilegroup.studies.lab.lab_tables import read_lab_table
from pilegroup.studies.lab.oedometer_programme import LoadStep, run_programme
from pilegroup.studies.lab.soft_soil_params import checked_values

FIT = "fit oedometer"
OEDOMETER_COLUMNS = ("step", "time_day", "vertical_stress_kPa", "vertical_strain")
KEYS = ("lambda_star", "kappa_star", "mu_star")
#: Relative change of a held stress within one step that is still one step.
STRESS_SPREAD = 0.01
#: Relative step of the finite-difference Jacobian.
DIFF_STEP = 1e-4


@dataclass(frozen=True)
class OedometerData:
    """The readings of an oedometer file and its load steps."""

    path: Path
    steps: tuple[LoadStep, ...]
    number: np.ndarray
    time: np.ndarray
    stress: np.ndarray
    strain: np.ndarray
    """Vertical strain counted from the first reading."""

    def ends(self) -> np.ndarray:
        """Index of each step's last reading."""
        return np.append(np.nonzero(np.diff(self.number) != 0)[0], self.number.size - 1)


@dataclass(frozen=True)
class OedometerFit:
    """What the fit's figure needs: the data, the fitted law's strains, the residuals."""

    data: OedometerData
    model: np.ndarray
    residual: np.ndarray
    used: np.ndarray
    result: FitResult


def _row_error(path: Path, i: int, value: object, allowed: str) -> ScenarioError:
    return ScenarioError(f"{path} row {i + 2}", value, allowed)


def read_oedometer(path: Path) -> OedometerData:
    """The readings and load steps of ``path`` (module doc)."""
    t = read_lab_table(path, OEDOMETER_COLUMNS)
    sv, time, number = t["vertical_stress_kPa"], t["time_day"], t["step"]
    if np.any(sv <= 0.0):
        i = int(np.argmax(sv <= 0.0))
        raise _row_error(path, i, float(sv[i]), "column 'vertical_stress_kPa' must be > 0 "
                         "(effective, compression positive)")
    if np.any(np.diff(time) < 0.0):
        i = int(np.argmax(np.diff(time) < 0.0)) + 1
        raise _row_error(path, i, float(time[i]), "column 'time_day' must not decrease (the "
                         "readings in time order)")
    groups = np.split(np.arange(sv.size), np.nonzero(np.diff(number) != 0)[0] + 1)
    steps: list[LoadStep] = []
    for g in groups:
        s = float(sv[g[0]])
        bad = np.nonzero(np.abs(sv[g] - s) > STRESS_SPREAD * s)[0]
        if bad.size:
            raise _row_error(path, int(g[bad[0]]), float(sv[g[bad[0]]]), "column "
                             f"'vertical_stress_kPa' changes within step {number[g[0]]:g}: "
                             "one held stress per step (a new load is a new step)")
        start = float(time[g[0]] if not steps else time[g[0] - 1])
        steps.append(LoadStep(s, start, tuple(float(x) for x in time[g])))
    if len(steps) < 2:
        raise ScenarioError(str(path), f"{len(steps)} step", "needs the start and load steps "
                            "(two step numbers or more)")
    return OedometerData(path, tuple(steps), number, time, sv,
                         t["vertical_strain"] - t["vertical_strain"][0])


def _slopes(d: OedometerData) -> tuple[list[float], list[float]]:
    """Secant slopes ``d eps/d ln sigma'`` of the end-of-step readings: loading, unloading."""
    e = d.ends()
    load, unload = [], []
    for a, b in zip(e[:-1], e[1:], strict=True):
        r = math.log(d.stress[b] / d.stress[a])
        if abs(r) > 1e-3:
            (load if r > 0 else unload).append(float((d.strain[b] - d.strain[a]) / r))
    return load, unload


def _creep_slope(d: OedometerData) -> float | None:
    """``d eps/d ln t`` late in the longest hold (its readings after a tenth of it)."""
    k = max(range(1, len(d.steps)), key=lambda j: d.steps[j].times[-1] - d.steps[j].start_day)
    m = np.nonzero(d.number == d.number[d.ends()[k]])[0]
    u = d.time[m] - d.steps[k].start_day
    late = u >= 0.1 * u[-1]
    if u[-1] <= 0.0 or np.count_nonzero(late) < 3:
        return None
    return float(np.polyfit(np.log(u[late]), d.strain[m][late], 1)[0])


def _start(d: OedometerData, fit_ocr: bool) -> list[float]:
    """``(lambda*, kappa*/lambda*, mu*[, OCR])`` from the classical constructions."""
    load, unload = _slopes(d)
    if not load or max(load) <= 0.0:
        raise ScenarioError(str(d.path), "no loading", "needs load steps that compress the "
                            "sample (a stress above the start's)")
    lam = max(load)
    kap = float(np.median(unload)) if unload and np.median(unload) > 0.0 else lam / 5.0
    mu = _creep_slope(d) or lam / 20.0
    x = [lam, min(max(kap / lam, 0.1), 0.5), min(max(mu, lam / 200.0), lam / 3.0)]
    if fit_ocr:
        e = d.ends()
        i = e[int(np.argmax(d.stress[e]))]
        lnp = (lam * math.log(d.stress[i]) - d.strain[i] - kap * math.log(d.stress[0])) / (
            lam - min(kap, 0.5 * lam))
        x.append(min(max(math.exp(lnp) / d.stress[0], 1.2), 20.0))
    return x


def _over_consolidated(d: OedometerData) -> bool:
    load, _ = _slopes(d)
    return len(load) >= 2 and load[0] < 0.8 * max(load)


def _ratio_max(phi_deg: float, nu_ur: float) -> float:
    """The largest ``kappa*/lambda*`` (at most 0.9) whose ellipse gives ``K0nc = 1 - sin phi``."""
    k0, r = 1.0 - math.sin(math.radians(phi_deg)), 0.9
    while r > 1e-3:
        try:
            m_from_k0nc(k0, 1.0, r, nu_ur)
            return r
        except ConstitutiveError:
            r *= 0.9
    raise ScenarioError("--phi_deg", phi_deg, f"gives K0nc = {k0:.4g}, which no ellipse of "
                        f"Soft Soil Creep gives with nu_ur = {nu_ur:g}", "degree")


@dataclass(frozen=True)
class _Problem:
    """The residuals of one fit: the data, the held keys and the law they make."""

    data: OedometerData
    held: dict[str, Any]
    per_decade: int
    used: np.ndarray
    calls: list[int]

    def law(self, x: np.ndarray) -> SoftSoilCreep:
        ocr = float(x[3]) if x.size > 3 else float(self.held["OCR"])
        return SoftSoilCreep(float(x[0]), float(x[0] * x[1]), float(x[2]),
                             self.held["phi_deg"], nu_ur=self.held["nu_ur"], OCR=ocr,
                             tau=self.held["tau_ref_day"])

    def strain(self, x: np.ndarray) -> np.ndarray:
        self.calls[0] += 1
        rows = run_programme(self.law(x), self.data.steps, self.per_decade)
        return rows[:, 0] - rows[0, 0]

    def residual(self, x: np.ndarray) -> np.ndarray:
        return self.strain(x)[self.used] / self.data.strain[self.used] - 1.0


def _solve(pb: _Problem, x0: list[float], ratio_hi: float) -> Any:
    b = {k: BOUNDS[f"layers.{k}"] for k in ("lambda_star", "mu_star", "OCR")}
    lo = [1e-4, 1e-3, 1e-6] + [b["OCR"].lo] * (len(x0) - 3)
    hi = [b["lambda_star"].hi, ratio_hi, b["mu_star"].hi] + [b["OCR"].hi] * (len(x0) - 3)
    x0 = list(np.clip(x0, np.array(lo) * 1.01, np.array(hi) * 0.99))
    return least_squares(pb.residual, x0, bounds=(lo, hi), x_scale="jac", method="trf",
                         diff_step=DIFF_STEP, ftol=1e-4, xtol=1e-4, max_nfev=200), lo, hi


def _held(material: LabMaterial, ocr: float | None) -> dict[str, Any]:
    """The held keys, checked; ``OCR`` the given one (checked too) or 1."""
    fitted = KEYS + ("POP_kPa",) + (("OCR",) if ocr is None else ())
    vals = checked_values(material, "soft_soil_creep", FIT, fitted)
    vals["OCR"] = 1.0 if ocr is None else float(ocr)
    return vals


def fit_oedometer(path: Path, material: LabMaterial, ocr: float | None = None,
                  per_decade: int = 20) -> OedometerFit:
    """``lambda_star``, ``kappa_star``, ``mu_star`` (and ``OCR``) from the readings of ``path``.

    ``ocr``: held at this value (else fitted where the curve starts over-consolidated).
    """
    if not 2 <= per_decade <= 1000:
        raise ScenarioError("--substeps-per-decade", per_decade, "must be an integer in "
                            "[2, 1000]")
    data = read_oedometer(path)
    held = _held(material, ocr)
    fit_ocr = ocr is None and _over_consolidated(data)
    used = data.strain > 0.0
    names = KEYS + (("OCR",) if fit_ocr else ())
    if np.count_nonzero(used) <= len(names):
        raise ScenarioError(str(path), f"{np.count_nonzero(used)} data points", "fewer than "
                            f"the {len(names)} parameters fitted ({', '.join(names)}) and one;"
                            " give more readings with strain > 0")
    pb = _Problem(data, held, per_decade, used, [0])
    ratio_hi = _ratio_max(held["phi_deg"], held["nu_ur"])
    res, lo, hi = _solve(pb, _start(data, fit_ocr), ratio_hi)
    if fit_ocr and res.active_mask[3] < 0:  # OCR on 1: normally consolidated after all
        names, fit_ocr = KEYS, False
        res, lo, hi = _solve(pb, list(res.x[:3]), ratio_hi)
    check_converged(res, ("lambda_star", "kappa_star/lambda_star", "mu_star", "OCR")[:len(lo)],
                    lo, hi, str(path))
    return _result(pb, res, names, material.source)


def _result(pb: _Problem, res: Any, names: tuple[str, ...], source: str) -> OedometerFit:
    x = res.x
    values = [float(x[0]), float(x[0] * x[1]), float(x[2])] + [float(v) for v in x[3:]]
    chain = np.eye(x.size)  # d (lambda*, ratio, mu*, OCR) / d (lambda*, kappa*, mu*, OCR)
    chain[1, :2] = [-x[1] / x[0], 1.0 / x[0]]
    se, corr = statistics(res.jac @ chain, res.fun, names, len(names))
    model = pb.strain(x)
    calls = pb.calls[0] - 1
    held = pb.held
    details: tuple[tuple[str, Any], ...] = (
        ("phi_deg", held["phi_deg"]), ("nu_ur", held["nu_ur"]),
        ("tau_ref_day", held["tau_ref_day"]), ("steps", len(pb.data.steps) - 1),
        ("substeps_per_decade", pb.per_decade), ("parameters from", source))
    if "OCR" not in names:
        details = (("OCR_held", held["OCR"]), *details)
    result = FitResult("oedometer", str(pb.data.path), names, tuple(values), se, corr,
                       rms(res.fun), "(relative)", int(res.fun.size), calls, details)
    return OedometerFit(pb.data, model, res.fun, pb.used, result)

__all__ = ["KEYS", "OEDOMETER_COLUMNS", "OedometerData", "OedometerFit", "fit_oedometer",
           "read_oedometer"]
