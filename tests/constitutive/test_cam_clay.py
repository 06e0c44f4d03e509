"""Modified Cam Clay at material points (Mandel notation, tension positive).

References:
* Roscoe & Burland (1968), Wood (1990) *Soil behaviour and critical state soil mechanics*:
  isotropic normal compression ``e = e_N - lambda ln p'``, unloading ``e = e_k - kappa ln p'``;
  undrained path from isotropic NC ``p'/p'0 = (M^2/(M^2 + eta^2))^Lambda``; the critical state
  ``q = M p'``;
* the consistent tangent against central differences (1e-6, as the other laws' tests).
"""

import math

import numpy as np
import pytest

from pilegroup.constitutive.cam_clay import ModifiedCamClay, mcc_undrained_path
from pilegroup.constitutive.critical_state import (
    eta_k0,
    eta_k0nc,
    k0_stress,
    m_from_k0nc,
    pq,
    shear_ratio,
)
from pilegroup.errors import ConstitutiveError

CLAY = {"lam": 0.25, "kappa": 0.05, "e0": 1.5}
LAWS = {
    "nu-nc": ModifiedCamClay(**CLAY, M=1.0, nu=0.25),
    "G-ocr": ModifiedCamClay(lam=0.3, kappa=0.03, e0=1.2, M=1.2, G=3000.0, OCR=4.0),
    "phi-pop": ModifiedCamClay(lam=0.15, kappa=0.02, e0=0.8, phi_cs_deg=30.0, nu=0.3,
                               POP=40.0),
}


def random_states(law, n, rng):
    """Admissible states: random stresses (p' 20-300 kPa), p_c on or beyond the ellipse."""
    p = rng.uniform(20.0, 300.0, n)
    s = np.zeros((n, 6))
    s[:, :3] = -p[:, None] + rng.normal(0.0, 0.25, (n, 3)) * p[:, None]
    s[:, 3:] = rng.normal(0.0, 0.25, (n, 3)) * p[:, None]
    p0, q0, _ = pq(s)
    keep = p0 > 5.0
    s = s[keep]
    pc = law.pc_through(p0[keep], q0[keep]) * rng.choice([1.0, 1.0, 1.3, 3.0], keep.sum())
    return law.initial_state(s.shape[0], s, pc0=pc)


@pytest.mark.parametrize("name", sorted(LAWS))
def test_tangent_fd(name, fd_tangent):
    """Consistent tangent vs central differences: 1e-6 relative (Frobenius, per point)."""
    law = LAWS[name]
    rng = np.random.default_rng(11)
    state = random_states(law, 400, rng)
    n = state["stress"].shape[0]
    de = rng.normal(0.0, 1.0, (n, 6)) * 10.0 ** rng.uniform(-5.0, -2.0, (n, 1))
    sig, trial, D = law.update(de, state, 0.0)
    # h: ~1e-3 kPa of stress at K ~ 1e4 kPa; round-off ~1e-13, truncation ~1e-12
    Dfd, same = fd_tangent(law, de, state, 1e-7)
    err = np.linalg.norm(D - Dfd, axis=(1, 2)) / np.linalg.norm(D, axis=(1, 2))
    mode = trial["mode"][:, 0]
    for m in (0, 1):
        print(name, "mode", m, "count", np.sum((mode == m) & same),
              "max rel err", err[(mode == m) & same].max(initial=0.0))
    assert np.sum(mode == 0) > 20 and np.sum(mode == 1) > 20
    assert same.mean() > 0.95
    assert err[same].max() <= 1e-6
    # plastic points end on the surface, elastic ones inside
    f = law.yield_function(sig, trial["pc"]) / trial["pc"][:, 0] ** 2
    assert np.abs(f[mode == 1]).max() <= 1e-12
    assert f[mode == 0].max() <= 1e-12


def test_large_increments_return_to_the_surface():
    """Increments up to 20 % strain (Newton's first iterates) still land on the surface."""
    law = LAWS["G-ocr"]
    rng = np.random.default_rng(2)
    state = random_states(law, 2000, rng)
    n = state["stress"].shape[0]
    de = rng.normal(0.0, 1.0, (n, 6)) * 10.0 ** rng.uniform(-6.0, -0.7, (n, 1))
    sig, trial, D = law.update(de, state, 0.0)
    assert np.all(np.isfinite(sig)) and np.all(np.isfinite(D))
    plastic = trial["mode"][:, 0] == 1
    f = law.yield_function(sig, trial["pc"]) / trial["pc"][:, 0] ** 2
    assert plastic.sum() > 100
    assert np.abs(f[plastic]).max() <= 1e-10


def test_isotropic_compression_and_unloading_lines():
    """Isotropic NC loading follows e = e_N - lambda ln p', unloading e = e_k - kappa ln p'."""
    law = LAWS["nu-nc"]
    p0 = 50.0
    st = law.initial_state(1, -p0 * np.array([1.0, 1, 1, 0, 0, 0]), pc0=p0)
    ev = 0.0
    for d in [-0.004] * 25 + [0.002] * 10:  # compression, then swelling
        st_new = law.update(np.array([[d, d, d, 0, 0, 0]]), st, 0.0)[1]
        ev -= 3 * d
        st = st_new
        if d < 0:
            p_nc = -st["stress"][0, 0]
            assert np.isclose(st["pc"][0, 0], p_nc, rtol=1e-12)  # on the NCL
    p = -st["stress"][0, 0]
    e = law.e0 - (1 + law.e0) * ev
    p_max = st["pc"][0, 0]
    e_ref = law.e0 - law.lam * math.log(p_max / p0) + law.kappa * math.log(p_max / p)
    assert abs(e - e_ref) <= 1e-12


def test_undrained_path_and_critical_state():
    """Undrained compression from isotropic NC: Wood's path, ending at q = M p'."""
    law = ModifiedCamClay(**CLAY, phi_cs_deg=25.0, G=2500.0)
    p0 = 80.0
    st = law.initial_state(1, -p0 * np.array([1.0, 1, 1, 0, 0, 0]), pc0=p0)
    d = 2e-3
    for _ in range(150):
        sig, st, _ = law.update(np.array([[d / 2, d / 2, -d, 0, 0, 0]]), st, 0.0)
        p, q, _ = pq(sig)
        assert abs(p[0] - mcc_undrained_path(p0, q / p, law)[0]) <= 1e-12 * p0
    assert q[0] / p[0] == pytest.approx(law.m, rel=1e-4)


def test_newton_quadratic_mixed_control():
    """One-point Newton (normal stresses held, shear strains given): order ~2."""
    law = LAWS["nu-nc"]
    state = law.initial_state(1, np.array([-100.0, -80.0, -120.0, 0, 0, 0]))
    target = np.array([-110.0, -90.0, -140.0])
    gam = np.array([0.004, -0.002, 0.003])
    x = np.zeros(3)
    errs = []
    for _ in range(30):
        sig, trial, D = law.update(np.concatenate([x, gam])[None], state, 0.0)
        r = sig[0, :3] - target
        errs.append(np.linalg.norm(r) / 100.0)
        if errs[-1] < 1e-14:
            break
        x -= np.linalg.solve(D[0][:3, :3], r)
    assert trial["mode"][0, 0] == 1
    assert errs[-1] < 1e-14
    q = [math.log(errs[k + 1] / errs[k]) / math.log(errs[k] / errs[k - 1])
         for k in range(1, len(errs) - 1) if errs[k - 1] < 5e-2 and errs[k + 1] > 1e-13]
    print("errors", errs, "orders", q)
    assert q and all(qk >= 1.8 for qk in q), (errs, q)


def test_k0nc_initial_state_on_the_surface():
    """K0-NC helper: OCR = 1 puts the K0 state on the ellipse; OCR, POP scale sigma'_p."""
    law = LAWS["nu-nc"]
    k0 = law.k0nc()
    g = shear_ratio(law.kap_t, law.nu)
    # the law's own K0nc is the inverse of the Soft Soil relation M(K0nc)
    assert m_from_k0nc(k0, law.lam_t, law.kap_t, law.nu) == pytest.approx(law.m, rel=1e-12)
    assert eta_k0(k0) == pytest.approx(eta_k0nc(law.m, law.lam_t, law.kap_t, g), rel=1e-12)
    sv = np.array([10.0, 50.0, 200.0])
    s0 = k0_stress(sv, k0)
    st = law.initial_state(3, s0)
    assert np.abs(law.yield_function(s0, st["pc"])).max() <= 1e-12 * st["pc"].max() ** 2
    st4 = ModifiedCamClay(**CLAY, M=1.0, nu=0.25, OCR=4.0).initial_state(3, s0)
    np.testing.assert_allclose(st4["pc"], 4.0 * st["pc"], rtol=1e-12)
    stp = ModifiedCamClay(**CLAY, M=1.0, nu=0.25, POP=30.0).initial_state(3, s0)
    p, q, _ = pq(k0_stress(sv + 30.0, k0))
    np.testing.assert_allclose(stp["pc"][:, 0], law.pc_through(p, q), rtol=1e-12)
    # a given p_c below the one through the stress is raised to it
    st_low = law.initial_state(3, s0, pc0=1.0)
    np.testing.assert_allclose(st_low["pc"], st["pc"], rtol=1e-12)


@pytest.mark.parametrize(("kwargs", "key"), [
    ({"lam": 0.05, "kappa": 0.05, "e0": 1.0, "M": 1.0, "nu": 0.3}, "kappa"),
    ({"lam": 0.05, "kappa": 0.08, "e0": 1.0, "M": 1.0, "nu": 0.3}, "kappa"),
    ({"lam": -0.1, "kappa": 0.05, "e0": 1.0, "M": 1.0, "nu": 0.3}, "lam"),
    ({**CLAY, "M": 1.0, "nu": 0.3, "OCR": 0.8}, "OCR"),
    ({**CLAY, "M": 1.0, "nu": 0.3, "POP": -5.0}, "POP"),
    ({**CLAY, "M": 1.0, "nu": 0.3, "OCR": 2.0, "POP": 5.0}, "OCR or POP"),
    ({**CLAY, "M": 1.0, "phi_cs_deg": 25.0, "nu": 0.3}, "exactly one of M"),
    ({**CLAY, "nu": 0.3}, "exactly one of M"),
    ({**CLAY, "M": 1.0, "nu": 0.3, "G": 100.0}, "exactly one of nu"),
    ({**CLAY, "M": 1.0, "nu": 0.5}, "nu"),
    ({**CLAY, "M": 1.0, "G": 0.0}, "G"),
    ({"lam": 0.25, "kappa": 0.05, "e0": 0.0, "M": 1.0, "nu": 0.3}, "e0"),
    ({**CLAY, "M": 3.5, "nu": 0.3}, "M"),
    ({**CLAY, "M": 1.0, "nu": 0.3, "K0nc": 1.2}, "K0nc"),
])
def test_validation(kwargs, key):
    """Bad parameters: one line naming the key (and the allowed range)."""
    with pytest.raises(ConstitutiveError, match=key) as info:
        ModifiedCamClay(**kwargs)
    assert "\n" not in str(info.value)


def test_state_not_mutated_and_initial_stress_required():
    law = LAWS["nu-nc"]
    with pytest.raises(ConstitutiveError, match="p' > 0"):
        law.initial_state(2, None)
    with pytest.raises(ConstitutiveError, match="p' > 0"):
        law.initial_state(2, np.array([10.0, 10, 10, 0, 0, 0]))
    st0 = law.initial_state(4, np.array([-50.0, -50, -80, 0, 0, 0]))
    snap = {k: v.copy() for k, v in st0.items()}
    law.update(np.full((4, 6), -0.01), st0, 1.0)
    for k in st0:
        np.testing.assert_array_equal(st0[k], snap[k])
