"""Soft Soil Creep at material points (Mandel notation, tension positive, days).

References:
* Vermeer & Neher (1999), PLAXIS Material Models manual (Soft Soil Creep model): the creep
  rate ``(mu*/tau)(p_eq/p_p^eq)^((lambda*-kappa*)/mu*)``; under constant stress
  ``eps_v^c = mu* ln(1 + t/tau_c)``, ``tau_c = tau (p_p^eq/p_eq)^beta``; ``M`` from ``K0nc``
  (the manual's formula, written out below independently of the code);
* the consistent tangent against central differences (1e-6, as the other laws' tests).
"""

import math

import numpy as np
import pytest

from pilegroup.constitutive.critical_state import k0_stress, pq
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep, ssc_creep_strain
from pilegroup.errors import ConstitutiveError

CLAY = {"lambda_star": 0.10, "kappa_star": 0.02, "mu_star": 0.004, "phi_deg": 25.0}
LAWS = {
    "nc": SoftSoilCreep(**CLAY),
    "ocr": SoftSoilCreep(lambda_star=0.15, kappa_star=0.015, mu_star=0.006, phi_deg=20.0,
                         nu_ur=0.2, OCR=1.5, tau=2.0),
}


def manual_m(k0, lam, kap, nu):
    """M of the PLAXIS manual (Soft Soil model) from K0nc, lambda*, kappa*, nu_ur."""
    r = lam / kap
    return 3.0 * math.sqrt((1 - k0) ** 2 / (1 + 2 * k0) ** 2
                           + (1 - k0) * (1 - 2 * nu) * (r - 1)
                           / ((1 + 2 * k0) * (1 - 2 * nu) * r - (1 - k0) * (1 + nu)))


def random_states(law, n, rng):
    p = rng.uniform(20.0, 300.0, n)
    s = np.zeros((n, 6))
    s[:, :3] = -p[:, None] + rng.normal(0.0, 0.2, (n, 3)) * p[:, None]
    s[:, 3:] = rng.normal(0.0, 0.2, (n, 3)) * p[:, None]
    s = s[pq(s)[0] > 5.0]
    st = law.initial_state(s.shape[0], s)
    st["pp"] = st["pp"] * rng.uniform(0.99, 1.5, (s.shape[0], 1))
    return st


def test_m_from_k0nc_is_the_manuals():
    for law in LAWS.values():
        assert law.m == pytest.approx(manual_m(law.k0nc, law.lambda_star, law.kappa_star,
                                               law.nu_ur), rel=1e-14)
    assert LAWS["nc"].k0nc == pytest.approx(1 - math.sin(math.radians(25.0)))


@pytest.mark.parametrize("name", sorted(LAWS))
@pytest.mark.parametrize("dt", [1e-4, 1.0, 1e3])
def test_tangent_fd(name, dt, fd_tangent):
    """Consistent tangent vs central differences: 1e-6 relative (Frobenius, per point)."""
    law = LAWS[name]
    rng = np.random.default_rng(7)
    state = random_states(law, 300, rng)
    n = state["stress"].shape[0]
    de = rng.normal(0.0, 1.0, (n, 6)) * 10.0 ** rng.uniform(-5.0, -2.0, (n, 1))
    sig, trial, D = law.update(de, state, dt)
    Dfd, _ = fd_tangent(law, de, state, 1e-7, dt)  # ~1e-3 kPa of stress at K ~ 1e4 kPa
    err = np.linalg.norm(D - Dfd, axis=(1, 2)) / np.linalg.norm(D, axis=(1, 2))
    p, q, _ = pq(sig)
    print(name, dt, "max rel err", err.max(), "largest eta/M", (q / p).max() / law.m)
    assert err.max() <= 1e-6
    assert (q / p).max() <= law.m * (1 + 1e-12)  # the viscous limit of the shear stress
    assert np.all(trial["pp"] >= state["pp"])  # creep only compacts


def test_trial_beyond_the_ellipse_top_and_large_increments():
    """Trial stresses with eta > M and strains up to 20 %: finite, eta <= M after the step."""
    law = LAWS["ocr"]
    rng = np.random.default_rng(3)
    state = random_states(law, 2000, rng)
    n = state["stress"].shape[0]
    de = rng.normal(0.0, 1.0, (n, 6)) * 10.0 ** rng.uniform(-6.0, -0.7, (n, 1))
    for dt in (1e-9, 1.0, 1e5):
        sig, trial, D = law.update(de, state, dt)
        assert np.all(np.isfinite(sig)) and np.all(np.isfinite(D))
        p, q, _ = pq(sig)
        assert (q / p).max() <= law.m * (1 + 1e-12)


def test_instantaneous_step_is_elastic():
    law = LAWS["nc"]
    st = law.initial_state(1, k0_stress(100.0, law.k0nc)[0])
    de = np.array([[1e-4, -2e-4, -3e-4, 1e-4, 0, 0]])
    sig, trial, D = law.update(de, st, 0.0)
    np.testing.assert_array_equal(trial["pp"], st["pp"])
    np.testing.assert_array_equal(trial["eps_c"], st["eps_c"])
    K = 100.0 * (1 + 2 * law.k0nc) / 3 / law.kappa_star  # K at p_n, in the tangent at d = 0
    D0 = law.update(np.zeros((1, 6)), st, 0.0)[2][0]
    assert D0[:3, :3].sum() / 9.0 == pytest.approx(K, rel=1e-12)


def test_normally_consolidated_rate_is_mu_over_tau():
    """At OCR = 1 (p_eq = p_p^eq) the creep rate is mu*/tau: a tiny step under held stress."""
    law = LAWS["ocr"]
    st = law.initial_state(1, k0_stress(100.0, law.k0nc)[0], pp0=0.0)  # raised to p_eq
    assert float(law.creep_time(st["stress"], st["pp"])[0]) == pytest.approx(law.tau)
    dt, target = 1e-6, st["stress"][0]
    d = np.zeros(6)
    for _ in range(20):
        sig, trial, D = law.update(d[None], st, dt)
        d -= np.linalg.solve(D[0], sig[0] - target)
    assert -trial["eps_c"][0, :3].sum() / dt == pytest.approx(law.mu_star / law.tau, rel=1e-5)


def test_constant_stress_creep_is_logarithmic():
    """Held stress from an over-consolidated state: mu* ln(1 + t/tau_c) within 0.5 %.

    Backward Euler at times growing by 4.7 % a step lags by about mu* h/2 (0.34 % here).
    """
    law = LAWS["nc"]
    s0 = k0_stress(100.0, law.k0nc)[0]
    st = law.initial_state(1, s0, pp0=1.05 * law.equivalent_pressure(s0[None])[0])
    tau_c = float(law.creep_time(st["stress"], st["pp"])[0])
    assert tau_c == pytest.approx(law.tau * 1.05**law.beta)
    times = np.geomspace(1e-3 * tau_c, 1e3 * tau_c, 300)
    t_prev, ev, errs = 0.0, 0.0, []
    for t in times:
        d = np.zeros(6)
        for _ in range(20):
            sig, trial, D = law.update(d[None], st, t - t_prev)
            r = sig[0] - s0
            if np.abs(r).max() < 1e-10:
                break
            d -= np.linalg.solve(D[0], r)
        st, t_prev, ev = trial, t, ev - d[:3].sum()
        errs.append(abs(ev - ssc_creep_strain(t, tau_c, law.mu_star)))
    ref_end = ssc_creep_strain(times[-1], tau_c, law.mu_star)
    print("max error / creep strain at the end", max(errs) / ref_end)
    assert max(errs) / ref_end <= 5e-3


def test_oedometer_reaches_k0nc():
    """Oedometric compression at a constant strain rate tends to sigma'_h = K0nc sigma'_v."""
    law = LAWS["nc"]
    st = law.initial_state(1, k0_stress(50.0, 0.8)[0])
    for _ in range(400):  # 0.1 % per day, 40 % strain in total
        st = law.update(np.array([[0, 0, -1e-3, 0, 0, 0]]), st, 1.0)[1]
    s = st["stress"][0]
    assert s[0] / s[2] == pytest.approx(law.k0nc, rel=1e-3)  # measured 1.2e-4


def test_initial_state_from_ocr_and_pop():
    law = LAWS["ocr"]
    sv = np.array([20.0, 100.0])
    s0 = k0_stress(sv, law.k0nc)
    st = law.initial_state(2, s0)
    np.testing.assert_allclose(st["pp"][:, 0], law.equivalent_pressure(k0_stress(1.5 * sv,
                                                                                 law.k0nc)))
    pop = SoftSoilCreep(**CLAY, POP=25.0)
    np.testing.assert_allclose(pop.initial_state(2, s0)["pp"][:, 0],
                               pop.equivalent_pressure(k0_stress(sv + 25.0, pop.k0nc)))


@pytest.mark.parametrize(("kwargs", "key"), [
    ({**CLAY, "kappa_star": 0.10}, "kappa_star"),
    ({**CLAY, "kappa_star": 0.2}, "kappa_star"),
    ({**CLAY, "lambda_star": 0.0}, "lambda_star"),
    ({**CLAY, "mu_star": -0.001}, "mu_star"),
    ({**CLAY, "mu_star": 0.0}, "mu_star"),
    ({**CLAY, "OCR": 0.9}, "OCR"),
    ({**CLAY, "POP": -1.0}, "POP"),
    ({**CLAY, "OCR": 1.2, "POP": 10.0}, "OCR or POP"),
    ({**CLAY, "phi_deg": 0.0}, "phi_deg"),
    ({**CLAY, "c": -1.0}, "c"),
    ({**CLAY, "nu_ur": 0.5}, "nu_ur"),
    ({**CLAY, "tau": 0.0}, "tau"),
    ({**CLAY, "K0nc": 1.0}, "K0nc"),
    ({**CLAY, "kappa_star": 0.09, "K0nc": 0.05}, "K0nc"),  # no ellipse gives this K0nc
])
def test_validation(kwargs, key):
    """Bad parameters: one line naming the key (and the allowed range)."""
    with pytest.raises(ConstitutiveError, match=key) as info:
        SoftSoilCreep(**kwargs)
    assert "\n" not in str(info.value)


def test_state_not_mutated():
    law = LAWS["nc"]
    st0 = law.initial_state(4, np.array([-50.0, -50, -80, 0, 0, 0]))
    snap = {k: v.copy() for k, v in st0.items()}
    law.update(np.full((4, 6), -0.01), st0, 1.0)
    for k in st0:
        np.testing.assert_array_equal(st0[k], snap[k])
