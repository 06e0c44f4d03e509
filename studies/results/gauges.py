"""The field method of the paper's strain gauges (Eqs. 1-3) as pure functions of the readings.

No mesh, no MPI: numbers in, numbers out (numpy). :mod:`pilegroup.studies.run.gauge_probe` samples
the model's pile and feeds these functions; the tests check them against hand-computed values.

Conventions (docs/model.md, "Virtual strain gauges"): depths in m below the ground surface,
positive down, sections numbered 1..n from the top; strain compression positive; axial force kN,
compression positive; friction kPa, positive when the soil supports the pile; displacements m,
down positive.

* Eq. 1: ``N_i = E eps_i A``.
* Eq. 2: ``f_i = (N_i - N_{i+1}) / (U l_i)``, ``l_i = z_{i+1} - z_i``: the mean friction of the
  interval from section ``i`` down to section ``i + 1``. The last section has no interval
  below it: its ``f`` is NaN.
* Eq. 3: ``w_i = w_0 - sum_{j=0}^{i-1} l_j / 2 (eps_j + eps_{j+1})`` with a section 0 at the
  pile top (depth 0) whose strain is that of section 1 (no gauge there) and ``l_0 = z_1``: the
  pile-top settlement minus the shortening of the pile between the top and section ``i`` by the
  trapezoid rule. (The printed sum over ``j = 1..i`` with ``l_j`` between sections ``j`` and
  ``j + 1`` would count the shortening down to section ``i + 1``: read with the sections
  numbered from 0 at the pile top it is the rule above.)
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np


def _increasing(depths: np.ndarray) -> np.ndarray:
    z = np.asarray(depths, dtype=float)
    if z.ndim != 1 or z.size == 0 or z[0] < 0.0 or np.any(np.diff(z) <= 0.0):
        raise ValueError(f"gauge depths {z.tolist()}: need a non-empty, strictly increasing "
                         "list of depths >= 0 m")
    return z


def field_reduction(depths: Sequence[float] | np.ndarray, strains: Sequence[float] | np.ndarray,
                    E: float, A: float, U: float, w0: float
                    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Axial force, friction and relative displacement from section strains (Eqs. 1-3).

    Args:
        depths: section depths (m), strictly increasing, >= 0.
        strains: section-mean axial strains (-), compression positive, one per section.
        E: Young's modulus of the pile (kPa).
        A: cross-section area (m^2).
        U: circumference (m).
        w0: pile-top displacement (m, down positive).

    Returns:
        ``(N, f, w)``: axial force (kN), friction of the interval below each section (kPa; NaN
        for the last section) and relative displacement (m) at each section.
    """
    z = _increasing(np.asarray(depths, dtype=float))
    eps = np.asarray(strains, dtype=float)
    if eps.shape != z.shape:
        raise ValueError(f"{eps.size} strains for {z.size} gauge depths")
    N = E * eps * A
    f = np.full(z.size, np.nan)
    f[:-1] = (N[:-1] - N[1:]) / (U * np.diff(z))
    lengths = np.diff(np.concatenate([[0.0], z]))
    eps_above = np.concatenate([eps[:1], eps[:-1]])
    w = w0 - np.cumsum(0.5 * lengths * (eps_above + eps))
    return N, f, w


def interval_means(z: np.ndarray, v: np.ndarray, depths: Sequence[float] | np.ndarray
                   ) -> np.ndarray:
    """Mean of the piecewise-linear profile ``v(z)`` over each interval between ``depths``.

    ``z`` increasing; the profile is constant beyond its ends. Exact (the trapezoid rule on the
    profile's own stations inside each interval). Returns one value per interval and NaN for the
    last depth, in the layout of :func:`field_reduction`'s ``f``.
    """
    d = _increasing(np.asarray(depths, dtype=float))
    out = np.full(d.size, np.nan)
    for k in range(d.size - 1):
        a, b = d[k], d[k + 1]
        s = np.concatenate([[a], z[(z > a) & (z < b)], [b]])
        out[k] = np.trapezoid(np.interp(s, z, v), s) / (b - a)
    return out


def nearest_times(times: Sequence[float] | np.ndarray, targets: Sequence[float]) -> list[float]:
    """The output times > 0 nearest to each target time, without repeats, in order.

    Time 0 is left out: it is the reference state of the gauges (every reading zero).
    """
    t = np.unique(np.asarray(times, dtype=float))
    t = t[t > 0.0]
    if t.size == 0:
        return []
    return sorted({float(t[np.argmin(np.abs(t - x))]) for x in targets})
