"""Numerical experiments on the interface law quoted in docs/model.md (pure numpy).

* :func:`seed_zero_shear` — what the literal Eq. 15 (``variant="seed"``) does to a soft-clay
  interface (Table 1, layer 2) under the in-situ normal stress alone;
* :func:`explicit_stability_scan` — relaxation at fixed slip integrated with the explicit
  (paper, Section 4) and the implicit (backward Euler) schemes over a range of steps.

Both return plain lists of dicts (units in the key names) so that tests can assert them and the
docs can print them.
"""

from __future__ import annotations

import math

import numpy as np

from pilegroup.constitutive.interface_law import PileSoilInterface
from pilegroup.constitutive.paper import TABLE1, interface_kwargs

GAMMA_W = 10.0  # kN/m3


def insitu_sigma_h(depth_m: float, layer: int = 2) -> float:
    """In-situ horizontal effective stress (kPa, compression positive) at a depth in Table 1.

    Water table at the ground surface; K0 = 1 - sin(phi) of the layer at that depth.
    """
    z_top, sv = 0.0, 0.0
    for lay in range(1, 11):
        r = TABLE1[lay]
        H = float(r["H"]) if lay < 10 else math.inf
        if depth_m <= z_top + H:
            sv += (float(r["gamma"]) - GAMMA_W) * (depth_m - z_top)
            return (1.0 - math.sin(math.radians(float(r["phi_deg"])))) * sv
        sv += (float(r["gamma"]) - GAMMA_W) * H
        z_top += H
    raise AssertionError("unreachable")  # pragma: no cover


def seed_zero_shear(depths_m=(1.0, 2.0, 5.0, 10.0, 19.0), taus_kPa=(0.0, 1.0, 5.0),
                    days: float = 317.0, layer: int = 2) -> list[dict]:
    """Constant normal stress (in situ) and constant small shear on a layer-2 interface.

    For each depth and shear: F of both variants (kPa), the closed-form slip rate
    ``<F>/eta dF/dtau`` (m/day) and the viscoplastic slip after ``days`` (m); and the time
    (days) in which the seed variant relaxes a held shear to 1 % (fixed slip, linearised
    rate constant ``k_s <F>/(eta sqrt(J2))`` at tau -> 0).
    """
    rows = []
    kw = interface_kwargs(layer)
    laws = {v: PileSoilInterface(**kw, variant=v) for v in ("default", "seed")}
    for z in depths_m:
        sn = -insitu_sigma_h(z, layer)
        for tau in taus_kPa:
            row = {"depth_m": z, "sigma_n_kPa": sn, "tau_kPa": tau}
            for v, law in laws.items():
                F = float(law.yield_function(np.array([[sn, tau, 0.0]]))[0])
                if v == "default":
                    g = 1.0 if tau > 0 else 0.0
                else:
                    g = tau / math.sqrt(sn * sn / 3.0 + tau * tau)
                rate = max(F, 0.0) / law.eta * g
                row[f"F_{v}_kPa"] = F
                row[f"slip_rate_{v}_m_per_day"] = rate
                row[f"slip_{v}_m_after_{days:g}d"] = rate * days
            law = laws["seed"]
            F0 = float(law.yield_function(np.array([[sn, 0.0, 0.0]]))[0])
            a, _ = law.hyperbola(np.array([sn]))
            lam = (1.0 / a[0]) * max(F0, 0.0) / (law.eta * abs(sn) / math.sqrt(3.0))
            row["seed_relax_to_1pct_days"] = math.log(100.0) / lam if lam > 0 else math.inf
            rows.append(row)
    return rows


def seed_threshold_pressure(layer: int = 2) -> float:
    """Normal pressure (kPa) above which the seed variant yields at zero shear.

    ``F = |sigma_n| / sqrt3 - alpha |sigma_n| - k = 0``  ->  ``p* = k / (1/sqrt3 - alpha)``.
    """
    law = PileSoilInterface(**interface_kwargs(layer), variant="seed")
    return law.k / (1.0 / math.sqrt(3.0) - law.alpha)


def explicit_stability_scan(factors=(0.25, 0.5, 0.9, 1.1, 1.5, 1.9, 2.1, 3.0, 10.0),
                            layer: int = 2, sigma_n: float = -66.0, n_tau: float = 2.0,
                            t_end_factor: float = 40.0, R_f: float | None = 0.0,
                            variant: str = "default") -> list[dict]:
    """Relaxation at fixed slip, explicit vs implicit, for steps dt = factor * eta / k_s.

    The shear is loaded instantaneously to ``n_tau`` times the yield shear, then held for
    ``t_end_factor * eta / k_s`` days (``tau0`` is capped at 80 % of the way from the yield
    shear to the hyperbola's asymptote when R_f > 0). ``R_f = 0`` (default) makes the shear
    spring linear, so the overstress obeys ``d u/dt = -(k_s/eta) u`` and the explicit scheme
    multiplies it by ``(1 - dt k_s/eta)`` per step: monotone for dt < eta/k_s, overshooting
    below the surface for eta/k_s < dt (then stuck: elastic inside the surface), oscillating
    with growth for
    dt > 2 eta/k_s once an overshoot reaches the opposite side of the surface (for
    tau0 = 2 tau_y that needs dt > 3 eta/k_s; for tau0 = 10 tau_y, dt > 1.22 eta/k_s).
    ``R_f = None`` keeps the layer's R_f.

    Returns per factor: dt (day), the final and the maximum |tau| (kPa) of both schemes, the
    exact final tau, and a classification of the explicit history.
    """
    kw = interface_kwargs(layer)
    if R_f is not None:
        kw["R_f"] = R_f
    rows = []
    ref = PileSoilInterface(**kw, variant=variant)
    a, b = ref.hyperbola(np.array([sigma_n]))
    ks = 1.0 / a[0]
    Fz = float(ref.yield_function(np.array([[sigma_n, 0.0, 0.0]]))[0])
    tau_y = max(-Fz, 0.0) if variant == "default" else 0.0
    tau0 = n_tau * tau_y if tau_y > 0 else 5.0
    if b[0] > 0.0:  # stay below the hyperbola's asymptote
        tau0 = min(tau0, tau_y + 0.8 * (1.0 / b[0] - tau_y))
    w0 = a[0] * tau0 / (1.0 - b[0] * tau0)
    t_end = t_end_factor * ref.eta / ks
    for fac in factors:
        dt = fac * ref.eta / ks
        nsteps = max(1, int(round(t_end / dt)))
        row = {"dt_over_eta_per_ks": fac, "dt_day": dt, "steps": nsteps, "k_s_kPa_per_m": ks,
               "tau_y_kPa": tau_y, "tau0_kPa": tau0}
        for integ in ("explicit", "implicit"):
            law = PileSoilInterface(**kw, variant=variant, integrator=integ)
            st = law.initial_state(1, np.array([sigma_n, 0.0, 0.0]))
            tr, st, _ = law.update(np.array([[0.0, w0, 0.0]]), st, 0.0)
            hist = [tr[0, 1]]
            z = np.zeros((1, 3))
            for _ in range(nsteps):
                tr, st, _ = law.update(z, st, dt)
                hist.append(tr[0, 1])
                if abs(tr[0, 1]) > 1e6 * tau0:
                    break
            h = np.array(hist)
            row[f"{integ}_tau_end_kPa"] = float(h[-1])
            row[f"{integ}_max_abs_tau_kPa"] = float(np.abs(h).max())
            row[f"{integ}_min_tau_kPa"] = float(h.min())
            if integ == "explicit":
                if np.abs(h[1:]).max() > 1.01 * tau0:
                    kind = "oscillating growth (diverges)"
                elif h.min() < tau_y - 1e-9 * tau0:
                    kind = "overshoot, ends inside the surface (wrong state)"
                else:
                    kind = "monotone"
                row["explicit_behaviour"] = kind
            else:
                row["implicit_monotone"] = bool(np.all(np.diff(h) <= 1e-12 * tau0))
        row["exact_tau_end_kPa"] = tau_y + (tau0 - tau_y) * math.exp(-ks / ref.eta * t_end) \
            if R_f == 0.0 and variant == "default" else float("nan")
        rows.append(row)
    return rows
