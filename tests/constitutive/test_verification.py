"""The numbers quoted in docs/model.md (interface: seed variant, explicit stability)."""

import math

import pytest

from pilegroup.constitutive.experiments import (
    explicit_stability_scan,
    insitu_sigma_h,
    seed_threshold_pressure,
    seed_zero_shear,
)


def test_insitu_stress():
    # layer 1: 0.4 m of gamma' = 7.8; layer 2: gamma' = 6.9, K0 = 1 - sin(2.6 deg)
    sv = 0.4 * 7.8 + 9.6 * 6.9
    assert insitu_sigma_h(10.0) == pytest.approx((1 - math.sin(math.radians(2.6))) * sv,
                                                  rel=1e-12)


def test_seed_creeps_under_normal_pressure_alone():
    p_star = seed_threshold_pressure(2)
    assert p_star == pytest.approx(11.72, abs=0.01)  # kPa, k / (1/sqrt3 - alpha)
    rows = {(r["depth_m"], r["tau_kPa"]): r for r in seed_zero_shear()}
    r = rows[(10.0, 1.0)]
    assert r["F_seed_kPa"] > 30.0 and r["F_default_kPa"] < -9.0
    assert r["slip_seed_m_after_317d"] > 0.04 and r["slip_default_m_after_317d"] == 0.0
    assert rows[(1.0, 1.0)]["F_seed_kPa"] < 0  # sigma_h' = 6.9 kPa < p*


def test_explicit_stability_limits():
    rows = {r["dt_over_eta_per_ks"]: r
            for r in explicit_stability_scan(n_tau=10.0, factors=(0.5, 0.9, 1.1, 1.9, 3.0))}
    for f, r in rows.items():
        # implicit: monotone and converged to the exact relaxed shear for every step size
        assert r["implicit_monotone"]
        assert r["implicit_tau_end_kPa"] == pytest.approx(r["exact_tau_end_kPa"], rel=1e-4), f
    assert rows[0.5]["explicit_behaviour"] == "monotone"
    assert rows[0.9]["explicit_behaviour"] == "monotone"
    assert rows[0.9]["explicit_tau_end_kPa"] == pytest.approx(rows[0.9]["exact_tau_end_kPa"],
                                                              rel=1e-6)
    assert rows[1.1]["explicit_behaviour"].startswith("overshoot")
    assert rows[1.9]["explicit_behaviour"].startswith("overshoot")
    assert rows[3.0]["explicit_behaviour"].startswith("oscillating growth")
