"""Interface parameters fitted to laboratory curves with scipy's bounded least squares.

* **Direct shear** (:func:`fit_shear`): ``K``, ``n``, ``R_f``, ``delta_deg`` from shear curves
  at several constant normal stresses. The model is the law's elastic hyperbola (Eqs. 5-7,
  ``PileSoilInterface.hyperbola``): ``tau = w / (a + b w)``, ``a = 1/(K r_w (p/P_a)^n)``,
  ``b = R_f / (p tan(delta))``. The curve alone fixes ``a`` and ``b``, i.e. ``K``, ``n`` and the
  ratio ``R_f / tan(delta)``; the strength separates them, as in Clough and Duncan's procedure:
  each curve's last point is its failure (the test is run to failure, as ``pilegroup lab``
  writes it; a measured curve with a peak and softening is cut at its peak), where the shear is
  the strength ``p tan(delta)``. The residuals are relative, ``model / measured - 1``, of every
  point's shear (slip > 0) and of every curve's strength: a measuring error that grows with the
  shear (a load cell's percentage) weighs every point alike, and the points near the origin
  fix the initial stiffness.
  Start: the classical straight lines (``w/tau`` against ``w`` per curve, ``log(1/a)``
  against ``log(p)``), then the joint fit.
* **Creep** (:func:`fit_creep`): ``eta_MPa_day`` (and with ``fit_N`` the Perzyna exponent
  ``N``) from creep curves at held shear and normal stress. At held stresses the law's slip
  grows at the constant rate ``PileSoilInterface.creep_rate`` (docs/model.md), so each curve is
  ``w(t) = w0 + rate t`` with its own ``w0`` (the instantaneous slip; fitted, not reported).
  The rate needs the yield surface: the soil's ``c_kPa``, ``phi_deg`` and the Eq. 15 reading.
  The residuals are relative too (``model / measured - 1`` of every slip).

Rows of one curve follow each other in the file; a curve is the rows of one ``curve`` number
(when the column is there) and one normal stress, and a new one starts where the time (creep)
or the slip (shear) goes down. With a ``variant`` column the rows of one reading are used.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy.optimize import least_squares

from pilegroup.constitutive.interface_law import PileSoilInterface
from pilegroup.errors import FitError, ScenarioError
from pilegroup.studies.lab.fit_stats import FitResult, check_converged, rms, statistics
from pilegroup.studies.lab.lab_params import VARIANTS, LabMaterial
from pilegroup.studies.lab.lab_tables import read_lab_table

SHEAR_KEYS = ("K", "n", "R_f", "delta_deg")
#: Bounds of the shear fit (docs/model.md's ranges of K and n; R_f < 1; delta in degrees).
SHEAR_BOUNDS = ((1.0, 0.0, 0.0, 0.01), (1.0e5, 2.0, 0.999, 89.0))
SHEAR_COLUMNS = ("normal_stress_kPa", "shear_stress_kPa", "slip_m")
CREEP_COLUMNS = ("time_day", "normal_stress_kPa", "shear_stress_kPa", "slip_m")
#: Bounds of eta (kPa·day/m: docs/model.md's 0.001-1e6 MPa·day/m) and N.
CREEP_BOUNDS = ((1.0, 0.05), (1.0e9, 20.0))


@dataclass(frozen=True)
class Curve:
    """One curve of a data file: its normal stress (kPa, compression positive) and points."""

    normal_kPa: float
    time: np.ndarray
    shear: np.ndarray
    slip: np.ndarray


@dataclass(frozen=True)
class CurveFit:
    """What a fit's figure needs: the curves, the fitted model per curve and the residuals."""

    curves: tuple[Curve, ...]
    model: Callable[[int, np.ndarray], np.ndarray]
    """``model(curve index, x)``: the fitted shear (against slip) or slip (against time)."""
    residual: np.ndarray
    result: FitResult


def read_curves(path: Path, columns: tuple[str, ...], along: str, variant: str | None
                ) -> tuple[tuple[Curve, ...], str | None]:
    """The curves of a lab-layout file (rows of the reading ``variant`` if it has several)."""
    t = read_lab_table(path, columns, ("variant", "curve"))
    chosen = None
    if "variant" in t:
        present = list(dict.fromkeys(t["variant"]))
        chosen = variant or ("default" if "default" in present else present[0])
        if chosen not in present:
            raise ScenarioError(f"{path} column 'variant'", chosen,
                                "no rows of that reading; the file has " + ", ".join(present))
        t = {k: v[t["variant"] == chosen] for k, v in t.items() if k != "variant"}
    n = len(t["slip_m"])
    key = t.get("curve", np.zeros(n))
    x = t[along]
    cut = np.nonzero((np.diff(key) != 0) | (np.diff(t["normal_stress_kPa"]) != 0)
                     | (np.diff(x) < 0))[0] + 1
    if np.any(t["normal_stress_kPa"] <= 0.0):
        row = int(np.argmax(t["normal_stress_kPa"] <= 0.0)) + 2
        raise ScenarioError(f"{path} row {row}", float(t["normal_stress_kPa"][row - 2]),
                            "column 'normal_stress_kPa' must be > 0 (compression positive)")
    curves = tuple(Curve(float(t["normal_stress_kPa"][s[0]]), t.get("time_day", x)[s],
                         t["shear_stress_kPa"][s], t["slip_m"][s])
                   for s in np.split(np.arange(n), cut) if s.size)
    return curves, chosen


def _too_few(path: Path, points: int, names: tuple[str, ...], extra: str = "") -> ScenarioError:
    return ScenarioError(str(path), f"{points} data points", f"fewer than the {len(names)} "
                         f"parameters fitted ({', '.join(names)}{extra}); give more points")


def _hyperbola(x: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``(a, b)`` of the law at compressive normal stresses ``p`` for ``x = (K, n, R_f, d)``."""
    law = PileSoilInterface(K=x[0], n=x[1], R_f=x[2], c=0.0, phi_deg=0.0, eta=1.0,
                            k_normal=1.0, delta_deg=x[3])
    return law.hyperbola(-p)


def _shear_start(curves: tuple[Curve, ...]) -> np.ndarray:
    """Clough and Duncan's straight lines: a start inside the bounds."""
    p = np.array([c.normal_kPa for c in curves])
    a, b = [], []
    for c in curves:
        m = c.slip > 0
        slope, icpt = np.polyfit(c.slip[m], c.slip[m] / c.shear[m], 1)
        a.append(icpt if icpt > 0 else float(np.min(c.slip[m] / c.shear[m])))
        b.append(max(slope, 0.0))
    law = PileSoilInterface(K=1.0, n=0.0, R_f=0.0, c=0.0, phi_deg=0.0, eta=1.0, k_normal=1.0,
                            delta_deg=1.0)
    n, lnk = np.polyfit(np.log(p / law.P_a), np.log(1.0 / (np.array(a) * law.r_w)), 1)
    tan_d = float(np.mean([c.shear[-1] / c.normal_kPa for c in curves]))
    r_f = float(np.mean(np.array(b) * p * tan_d))
    x0 = np.array([np.exp(lnk), n, r_f, np.degrees(np.arctan(tan_d))])
    lo, hi = (np.array(v) for v in SHEAR_BOUNDS)
    return np.clip(x0, lo + 1e-3 * (hi - lo), hi - 1e-3 * (hi - lo))


def fit_shear(path: Path, variant: str | None = None) -> CurveFit:
    """``K``, ``n``, ``R_f``, ``delta_deg`` from the direct-shear curves of ``path``."""
    curves, chosen = read_curves(path, SHEAR_COLUMNS, "slip_m", variant)
    curves = tuple(replace(c, time=c.time[c.slip > 0], shear=c.shear[c.slip > 0],
                           slip=c.slip[c.slip > 0]) for c in curves)
    points = sum(c.slip.size for c in curves)
    if points < len(SHEAR_KEYS):
        raise _too_few(path, points, SHEAR_KEYS)
    if len({c.normal_kPa for c in curves}) < 2 or min(c.slip.size for c in curves) < 2:
        raise ScenarioError(str(path), f"{len(curves)} curves", "needs curves at two normal "
                            "stresses or more, with two points of slip > 0 each (n is the "
                            "change of stiffness with normal stress)")
    if any(np.any(c.shear <= 0) for c in curves):
        raise ScenarioError(f"{path} column 'shear_stress_kPa'", "<= 0",
                            "must be > 0 where the slip is > 0 (one direction of shear)")
    p = np.array([c.normal_kPa for c in curves])
    peak = np.array([c.shear[-1] for c in curves])

    def residual(x: np.ndarray) -> np.ndarray:
        a, b = _hyperbola(x, p)
        parts = [c.slip / ((a[i] + b[i] * c.slip) * c.shear) - 1.0
                 for i, c in enumerate(curves)]
        parts.append(p * np.tan(np.radians(x[3])) / peak - 1.0)
        return np.concatenate(parts)

    res = least_squares(residual, _shear_start(curves), bounds=SHEAR_BOUNDS, x_scale="jac",
                        method="trf", max_nfev=2000)
    check_converged(res, SHEAR_KEYS, *SHEAR_BOUNDS, str(path))
    se, corr = statistics(res.jac, res.fun, SHEAR_KEYS, len(SHEAR_KEYS))
    result = FitResult("interface-shear", str(path), SHEAR_KEYS, tuple(map(float, res.x)), se,
                       corr, rms(res.fun), "(relative)", res.fun.size, int(res.nfev),
                       (("variant", chosen), ("curves", len(curves))))
    a, b = _hyperbola(res.x, p)
    return CurveFit(curves, lambda i, w: w / (a[i] + b[i] * w), res.fun, result)


def _creep_law(material: LabMaterial, variant: str) -> PileSoilInterface:
    """The law whose yield surface the creep fit uses (c, phi, reading; N when not fitted)."""
    if variant not in VARIANTS:
        raise ScenarioError("--variant", variant, "must be one of " + ", ".join(VARIANTS))
    missing = {k: 1.0 for k in ("K", "n", "eta_MPa_day") if material.get(k) is None}
    missing.update({"R_f": 0.0} if material.get("R_f") is None else {})
    full = LabMaterial(material.values + tuple(missing.items()), material.source)
    return full.interface_law(variant, "fit interface-creep")


def fit_creep(path: Path, material: LabMaterial, variant: str | None = None,
              fit_N: bool = False) -> CurveFit:
    """``eta_MPa_day`` (and ``N``) from the creep curves of ``path``."""
    curves, chosen = read_curves(path, CREEP_COLUMNS, "time_day", variant)
    law = _creep_law(material, variant or chosen or "default")
    names = ("eta_MPa_day", "N") if fit_N else ("eta_MPa_day",)
    np_ = len(names)
    points = sum(c.slip.size for c in curves)
    if points < np_ + len(curves) or min(c.slip.size for c in curves) < 2:
        raise _too_few(path, points, names, f" and one instantaneous slip per curve, "
                       f"{len(curves)} curves; two points per curve at least")
    if any(np.any(c.slip <= 0) for c in curves):
        raise ScenarioError(f"{path} column 'slip_m'", "<= 0", "must be > 0 under a held "
                            "shear (one direction of shear)")
    tr = np.array([[-c.normal_kPa, float(np.mean(c.shear)), 0.0] for c in curves])
    t0 = [c.time - c.time[0] for c in curves]

    def rates(x: np.ndarray) -> np.ndarray:
        return replace(law, eta=x[0], N=x[1] if fit_N else law.N).creep_rate(tr)

    if not np.any(rates(np.array([law.eta, law.N])) > 0.0):
        raise FitError(f"the data of {path} do not determine eta_MPa_day: the law "
                       f"(c = {law.c:g} kPa, phi = {law.phi_deg:g} deg, {law.variant} "
                       "reading) does not creep at any of its held stresses (F <= 0)")

    def residual(x: np.ndarray) -> np.ndarray:
        r = rates(x)
        return np.concatenate([(x[np_ + i] + r[i] * t0[i]) / c.slip - 1.0
                               for i, c in enumerate(curves)])

    slopes = np.array([np.polyfit(t, c.slip, 1)[0] for t, c in zip(t0, curves, strict=True)])
    unit = rates(np.array([1.0, law.N]))
    ok = (unit > 0) & (slopes > 0)
    eta0 = float(np.median(unit[ok] / slopes[ok])) if np.any(ok) else law.eta
    lo = [CREEP_BOUNDS[0][0]] + ([CREEP_BOUNDS[0][1]] if fit_N else []) + [-np.inf] * len(curves)
    hi = [CREEP_BOUNDS[1][0]] + ([CREEP_BOUNDS[1][1]] if fit_N else []) + [np.inf] * len(curves)
    x0 = np.array([np.clip(eta0, 2.0, 5e8)] + ([law.N] if fit_N else [])
                  + [c.slip[0] for c in curves])
    res = least_squares(residual, x0, bounds=(lo, hi), x_scale="jac", method="trf",
                        max_nfev=2000)
    check_converged(res, names, lo, hi, str(path))
    all_names = names + tuple(f"w0[{i}]" for i in range(len(curves)))
    se, corr = statistics(res.jac, res.fun, all_names, np_, [1e-3, 1.0][:np_])
    values = (res.x[0] * 1e-3,) + ((float(res.x[1]),) if fit_N else ())
    details = (("variant", law.variant), ("curves", len(curves)), ("c_kPa", law.c),
               ("phi_deg", law.phi_deg), ("N_held", law.N) if not fit_N else ("fit_N", True),
               ("parameters from", material.source))
    result = FitResult("interface-creep", str(path), names, tuple(map(float, values)), se, corr,
                       rms(res.fun), "(relative)", res.fun.size, int(res.nfev), details)
    r = rates(res.x)
    return CurveFit(curves, lambda i, t: res.x[np_ + i] + r[i] * (t - curves[i].time[0]),
                    res.fun, result)


__all__ = ["CREEP_BOUNDS", "CREEP_COLUMNS", "Curve", "CurveFit", "SHEAR_BOUNDS",
           "SHEAR_COLUMNS", "SHEAR_KEYS", "fit_creep", "fit_shear", "read_curves"]
