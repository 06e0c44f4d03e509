"""The ultimate capacity read off a load–settlement curve by named criteria (pure numpy).

A capacity stage (docs/model.md, "Capacity") raises the load under load control until the
foundation fails. Its curve is read by two criteria:

* ``plunging``: the tangent stiffness vanishing. The tangent stiffness of segment ``i`` of the
  curve is ``(Q_i - Q_{i-1}) / (w_i - w_{i-1})``; the foundation plunges at the load ``Q_{i-1}``
  where the first segment stiffer than nothing falls below ``ratio`` times the initial
  tangent stiffness (that of the first segment). Load control cannot pass the peak: when the
  stepper found no equilibrium even at its smallest step, the last equilibrium is the plunging
  load if no segment fell below the threshold before it, bracketed from above by the load of
  the step that failed.
* ``settlement_10pct_d``: the load at which the settlement reaches 10 % of the pile diameter
  (EN 1997-1, 7.6.1.1(3)), interpolated linearly between the points of the curve; the load
  step of the segment it lies on (``load_step_kN``) says how well the curve resolves it.

The ultimate capacity is the smaller of the criteria reached; ``None`` when neither is.
"""

from __future__ import annotations

from typing import Any

import numpy as np

#: Settlement per pile diameter of the settlement criterion (EN 1997-1, 7.6.1.1(3)).
SETTLEMENT_PER_DIAMETER = 0.1


def tangent_stiffness(load: np.ndarray, settlement: np.ndarray) -> np.ndarray:
    """Tangent stiffness (kN/m) of the segment ending at each point.

    NaN at the first point and where the settlement did not grow.
    """
    q, w = np.asarray(load, float), np.asarray(settlement, float)
    k = np.full(q.shape, np.nan)
    dw = np.diff(w)
    ok = dw > 0.0
    k[1:][ok] = np.diff(q)[ok] / dw[ok]
    return k


def plunging_load(load: np.ndarray, settlement: np.ndarray, ratio: float
                  ) -> tuple[float | None, int | None]:
    """``(load, index)`` where the tangent stiffness first falls below ``ratio`` x the initial.

    The load is that at the start of the soft segment (kN); ``(None, None)`` if it never does.
    """
    k = tangent_stiffness(load, settlement)
    finite = np.flatnonzero(np.isfinite(k))
    if finite.size < 2:
        return None, None
    k0 = k[finite[0]]
    for i in finite[1:]:
        if k[i] < ratio * k0:
            return float(load[i - 1]), int(i - 1)
    return None, None


def settlement_load(load: np.ndarray, settlement: np.ndarray, limit_m: float) -> float | None:
    """The load (kN) at which the settlement first reaches ``limit_m``, or None."""
    found = _settlement_segment(load, settlement, limit_m)
    return None if found is None else found[0]


def _settlement_segment(load: np.ndarray, settlement: np.ndarray, limit_m: float
                        ) -> tuple[float, float] | None:
    """``(load at limit_m, load step of the segment holding it)`` (kN), or None."""
    q, w = np.asarray(load, float), np.asarray(settlement, float)
    above = np.flatnonzero(w >= limit_m)
    if above.size == 0:
        return None
    i = int(above[0])
    if i == 0:
        return float(q[0]), 0.0
    f = (limit_m - w[i - 1]) / (w[i] - w[i - 1])
    return float(q[i - 1] + f * (q[i] - q[i - 1])), float(q[i] - q[i - 1])


def capacity_criteria(load: np.ndarray, settlement: np.ndarray, diameter_m: float,
                      ratio: float, end: dict[str, Any] | None = None,
                      load_scale_kN: float = 1.0) -> dict[str, Any]:
    """Both criteria and the ultimate capacity of one curve.

    Args:
        load: the curve's loads (kN), in the order of the steps.
        settlement: its settlements (m, down).
        diameter_m: the pile diameter (the settlement criterion's scale).
        ratio: the plunging threshold on the tangent stiffness (fraction of the initial).
        end: how the stage ended (``RunLog.capacity_end``); with ``reason = "no equilibrium"``
            the last equilibrium brackets the plunging load with ``failed_load_factor`` x
            ``load_scale_kN`` above it.
        load_scale_kN: the load of load factor 1 (for the failed step's load).
    """
    q, w = np.asarray(load, float), np.asarray(settlement, float)
    q_pl, i_pl = plunging_load(q, w, ratio)
    how = f"tangent stiffness below {ratio:g} x the initial"
    bracket = None
    if end is not None and end.get("reason") == "no equilibrium" and q.size:
        failed = end.get("failed_load_factor")
        if q_pl is None:
            q_pl, how = float(q[-1]), "no equilibrium beyond it (the stepper's cut-backs)"
        if failed is not None:
            bracket = [float(q[-1]), float(failed) * load_scale_kN]
    limit = SETTLEMENT_PER_DIAMETER * diameter_m
    seg = _settlement_segment(q, w, limit)
    q_w = None if seg is None else seg[0]
    reached = {k: v for k, v in (("plunging", q_pl), ("settlement_10pct_d", q_w))
               if v is not None}
    governing = min(reached, key=lambda k: reached[k]) if reached else None
    k = tangent_stiffness(q, w)
    k_fin = k[np.isfinite(k)]
    return {
        "plunging": {"load_kN": q_pl, "criterion": how if q_pl is not None else None,
                     "bracket_kN": bracket,
                     "settlement_m": float(w[i_pl]) if i_pl is not None else
                     (float(w[-1]) if q_pl is not None else None)},
        "settlement_10pct_d": {"load_kN": q_w, "settlement_m": limit,
                               "load_step_kN": None if seg is None else seg[1]},
        "ultimate_kN": reached[governing] if governing else None,
        "governing": governing,
        "initial_stiffness_kN_per_m": float(k_fin[0]) if k_fin.size else None,
        "final_stiffness_kN_per_m": float(k_fin[-1]) if k_fin.size else None,
        "max_load_kN": float(q.max()) if q.size else None,
        "max_settlement_m": float(w.max()) if w.size else None,
    }


def group_efficiency(group_kN: float | None, piles: int, single_kN: float | None
                     ) -> float | None:
    """``Q_group / (n Q_single)``, or None when either capacity is unknown."""
    if group_kN is None or single_kN is None or single_kN <= 0.0:
        return None
    return group_kN / (piles * single_kN)


__all__ = ["SETTLEMENT_PER_DIAMETER", "capacity_criteria", "group_efficiency", "plunging_load",
           "settlement_load", "tangent_stiffness"]
