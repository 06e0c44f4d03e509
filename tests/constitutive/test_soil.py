"""Mohr–Coulomb and Drucker–Prager soil laws (Mandel notation, tension positive).

References:
* drained triaxial compression failure deviator (closed form, MC; equal for the outer DP cone of
  Eq. 13): q_f = (2 c cos(phi) + 2 p0 sin(phi)) / (1 - sin(phi)), p0 = confining pressure;
* return-mapping optimality (de Souza Neto, Peric & Owen 2008, Sect. 8.2): returned stress on
  the surface, coaxial with the trial stress, and C^-1 (sigma_tr - sigma) a non-negative
  combination of the active potential gradients (apex: projection, no sign condition).
"""

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from pilegroup.constitutive.base import mandel_to_tensor, tensor_to_mandel
from pilegroup.constitutive.paper import soil_kwargs
from pilegroup.constitutive.soil import (
    MODE_APEX,
    MODE_EDGE_A,
    MODE_EDGE_B,
    MODE_FACE,
    DruckerPrager,
    MohrCoulomb,
    principal_stresses,
)
from pilegroup.errors import ConstitutiveError

LAYERS = [2, 5, 8]  # mud (phi 2.6), silt (phi 25), gravel (c = 0, phi 35)


def triaxial(law, p0, n_steps=60, eps_max_factor=4.0):
    """Drained triaxial compression: sigma_xx = sigma_yy = -p0 held, eps_zz driven."""
    st0 = law.initial_state(1, np.array([-p0, -p0, -p0, 0, 0, 0]))
    sf = math.sin(math.radians(law.phi_deg))
    qf = (2 * law.c * math.cos(math.radians(law.phi_deg)) + 2 * p0 * sf) / (1 - sf)
    d_ax = eps_max_factor * qf / law.E / n_steps
    state = st0
    its = []
    for _ in range(n_steps):
        # lateral strain eps_xx = eps_yy (axisymmetric; on the MC edge the split between xx and
        # yy is not unique, so the two-unknown Jacobian is singular there)
        x = 0.0
        for it in range(20):  # noqa: B007 (it is used after the loop)
            de = np.array([[x, x, -d_ax, 0, 0, 0]])
            sig, trial, D = law.update(de, state, 1.0)
            r = sig[0, 0] + p0
            if abs(r) <= 1e-12 * p0:
                break
            x -= r / (D[0, 0, 0] + D[0, 0, 1])
        else:
            raise AssertionError("triaxial Newton did not converge")
        assert abs(sig[0, 1] - sig[0, 0]) <= 1e-12 * p0
        its.append(it)
        state = trial
    q = sig[0, 0] - sig[0, 2]
    return q, qf, state, its


@pytest.mark.parametrize("layer", LAYERS)
@pytest.mark.parametrize("Law", [MohrCoulomb, DruckerPrager])
def test_triaxial_failure_deviator(Law, layer):
    """Reaches the closed-form MC failure deviator to 1e-8 relative."""
    law = Law(**soil_kwargs(layer))
    for p0 in (50.0, 200.0):
        q, qf, state, its = triaxial(law, p0)
        print(Law.__name__, layer, p0, "q", q, "q_f", qf, "Newton its", max(its))
        assert q == pytest.approx(qf, rel=1e-8)
        assert state["mode"][0, 0] > 0  # (MC: face/edge boundary sigma1 = sigma2, either branch)
        assert max(its) <= 3  # piecewise linear along this path


def test_dp_outer_cone_touches_mc_compression_meridian():
    kw = soil_kwargs(5)
    mc, dp = MohrCoulomb(**kw), DruckerPrager(**kw)
    p0 = 80.0
    sf = math.sin(math.radians(mc.phi_deg))
    qf = (2 * mc.c * math.cos(math.radians(mc.phi_deg)) + 2 * p0 * sf) / (1 - sf)
    comp = np.array([[-p0, -p0, -p0 - qf, 0, 0, 0]])  # s1 = s2 > s3
    ext = np.array([[-p0, -p0 - qf, -p0 - qf, 0, 0, 0]])  # s1 > s2 = s3
    assert abs(mc.yield_function(comp)[0]) < 1e-12 * qf
    assert abs(dp.yield_function(comp)[0]) < 1e-12 * qf
    assert dp.yield_function(ext)[0] < 0  # outside MC on the extension side: DP is outer


def random_rotation(rng):
    q, r = np.linalg.qr(rng.normal(size=(3, 3)))
    return q * np.sign(np.diag(r))


def trial_from_principal(s, Rot):
    return tensor_to_mandel(Rot @ np.diag(s) @ Rot.T)[None]


def check_return(law, sig_tr):
    """Property checks of one return: on surface, coaxial, flow rule signs; returns mode."""
    st0 = law.initial_state(1, sig_tr)
    sig, trial, _ = law.update(np.zeros((1, 6)), st0, 0.0)
    mode = int(trial["mode"][0, 0])
    scale = np.abs(principal_stresses(sig_tr)).max() + law.c
    f = law.yield_function(sig)[0]
    f_tr = law.yield_function(sig_tr)[0]
    if f_tr <= 1e-12 * scale:
        assert mode == 0 and np.array_equal(sig, sig_tr)
        return mode
    assert abs(f) <= 1e-10 * scale, (mode, f, scale)
    # coaxial with the trial stress
    A, B = mandel_to_tensor(sig)[0], mandel_to_tensor(sig_tr)[0]
    assert np.abs(A @ B - B @ A).max() <= 1e-10 * scale**2
    if isinstance(law, MohrCoulomb):
        s = np.linalg.eigvalsh(B)[::-1]
        h = np.array([v @ A @ v for v in np.linalg.eigh(B)[1].T[::-1]])
        assert np.all(np.diff(h) <= 1e-10 * scale)  # ordering kept
        K, G = law.K, law.G
        Dp = (K - 2 * G / 3) * np.ones((3, 3)) + 2 * G * np.eye(3)
        deps = np.linalg.solve(Dp, s - h)  # principal plastic strain increment
        sp = math.sin(math.radians(law.psi_deg))
        g13 = np.array([1 + sp, 0, -(1 - sp)])
        g23 = np.array([0, 1 + sp, -(1 - sp)])
        g12 = np.array([1 + sp, -(1 - sp), 0])
        if mode == MODE_FACE:
            lam = np.linalg.lstsq(g13[:, None], deps, rcond=None)[0]
            basis = g13[:, None]
        elif mode in (MODE_EDGE_A, MODE_EDGE_B):
            basis = np.column_stack([g13, g23 if mode == MODE_EDGE_A else g12])
            lam = np.linalg.lstsq(basis, deps, rcond=None)[0]
        else:
            assert mode == MODE_APEX
            assert np.allclose(h, law.c / math.tan(math.radians(law.phi_deg)),
                               rtol=0, atol=1e-10 * scale)
            return mode
        assert np.abs(basis @ lam - deps).max() <= 1e-9 * np.abs(deps).max()
        assert np.all(lam >= -1e-12 * scale / G), lam
    return mode


MC_LAWS = [MohrCoulomb(**soil_kwargs(2)), MohrCoulomb(**soil_kwargs(5), psi_deg=10.0),
           MohrCoulomb(**soil_kwargs(8), psi_deg=35.0), MohrCoulomb(**soil_kwargs(9))]


@pytest.mark.parametrize("law", MC_LAWS, ids=["mud", "silt-psi10", "gravel-assoc", "clay9"])
def test_returns_all_regions_sampled(law):
    """Random trial states hit face, both edges and apex; every return passes check_return."""
    rng = np.random.default_rng(7)
    modes = []
    for _ in range(400):
        s = np.sort(rng.normal(0.0, 150.0, 3))[::-1] + rng.normal(0, 60)
        modes.append(check_return(law, trial_from_principal(s, random_rotation(rng))))
    counts = np.bincount(modes, minlength=5)
    print(law, counts)
    assert np.all(counts[1:] > 0), counts


@settings(max_examples=150, deadline=None)
@given(
    s=st.lists(st.floats(-500.0, 300.0), min_size=3, max_size=3),
    law_i=st.integers(0, len(MC_LAWS) - 1),
    seed=st.integers(0, 2**31 - 1),
)
@example(s=[0.0, 0.0, -6.815315194868284e-301], law_i=2, seed=0)
def test_returns_land_on_surface_hypothesis(s, law_i, seed):
    # Principal stresses below 1e-6 kPa are zero: hypothesis also draws values such as 7e-301
    # kPa, whose yield function and tolerance (1e-12 x scale) fall into the subnormal range
    # where relative precision is lost; with c = 0 nothing lifts the scale (seen in CI).
    s = np.sort(np.where(np.abs(s) < 1e-6, 0.0, np.array(s)))[::-1]
    rot = random_rotation(np.random.default_rng(seed))
    check_return(MC_LAWS[law_i], trial_from_principal(s, rot))


@settings(max_examples=100, deadline=None)
@given(s=st.lists(st.floats(-500.0, 300.0), min_size=3, max_size=3),
       seed=st.integers(0, 2**31 - 1), psi=st.sampled_from([0.0, 10.0, 25.0]))
def test_dp_returns_on_surface(s, seed, psi):
    law = DruckerPrager(**soil_kwargs(5), psi_deg=psi)
    sig_tr = trial_from_principal(np.array(s), random_rotation(np.random.default_rng(seed)))
    sig, trial, _ = law.update(np.zeros((1, 6)), law.initial_state(1, sig_tr), 0.0)
    scale = np.abs(sig_tr).max() + law.c
    if law.yield_function(sig_tr)[0] > 1e-12 * scale:
        assert abs(law.yield_function(sig)[0]) <= 1e-10 * scale
        if trial["mode"][0, 0] == MODE_APEX:
            apex = law.k / (3 * law.alpha) * np.array([1, 1, 1, 0, 0, 0])
            np.testing.assert_allclose(sig[0], apex, atol=1e-10 * scale)
    else:
        assert np.array_equal(sig, sig_tr)


@pytest.mark.parametrize(
    "law",
    [MohrCoulomb(**soil_kwargs(2)), MohrCoulomb(**soil_kwargs(5), psi_deg=10.0),
     MohrCoulomb(**soil_kwargs(8), psi_deg=35.0), DruckerPrager(**soil_kwargs(2)),
     DruckerPrager(**soil_kwargs(5), psi_deg=10.0)],
    ids=["mc-mud", "mc-silt-psi10", "mc-gravel-assoc", "dp-mud", "dp-silt-psi10"],
)
def test_tangent_fd(law, fd_tangent):
    """Consistent tangent vs central differences: 1e-6 relative (Frobenius, per point)."""
    rng = np.random.default_rng(3)
    n = 300
    s0 = np.array([trial_from_principal(np.sort(rng.normal(-100, 60, 3))[::-1],
                                        random_rotation(rng))[0] for _ in range(n)])
    # admissible states: return them first, then pull half of them inside (deviator x 0.5)
    _, state, _ = law.update(np.zeros((n, 6)), law.initial_state(n, s0), 0.0)
    inside = np.arange(n) < n // 2
    sig0 = state["stress"]
    mean = sig0[:, :3].mean(axis=1, keepdims=True) * np.array([1, 1, 1, 0, 0, 0])
    sig0[inside] = mean[inside] + 0.5 * (sig0[inside] - mean[inside])
    size = np.where(inside, 0.5, 40.0)[:, None] / law.E  # small: elastic; large: plastic
    de = rng.normal(0, 1, (n, 6)) * size
    sig, trial, D = law.update(de, state, 0.0)
    modes = trial["mode"][:, 0].astype(int)
    # step: E h = 1e-3 kPa against stresses ~1e2 kPa (round-off ~1e-13, truncation ~1e-11)
    Dfd, same = fd_tangent(law, de, state, 1e-3 / law.E)
    nC = np.linalg.norm(law.C)
    # relative to |D|; apex (D = 0): relative to 1e-3 |C|
    err = np.linalg.norm(D - Dfd, axis=(1, 2)) / np.maximum(np.linalg.norm(D, axis=(1, 2)),
                                                             1e-3 * nC)
    for m in np.unique(modes):
        sel = (modes == m) & same
        print(law, "mode", m, "count", sel.sum(), "max rel err", err[sel].max(initial=0.0))
    assert np.sum(modes == 0) > 5 and np.sum(modes > 0) > 5
    print("stencils across a branch boundary:", np.sum(~same))
    assert same.mean() > 0.95
    assert err[same].max() <= 1e-6


@pytest.mark.parametrize("Law", [MohrCoulomb, DruckerPrager])
def test_newton_quadratic_mixed_control(Law):
    """One-point Newton: shear strains prescribed (principal axes rotate), normal stresses
    prescribed; the consistent tangent must give quadratic convergence (observed order ~2)."""
    law = Law(**soil_kwargs(5), psi_deg=10.0)
    p0 = 100.0
    state = law.initial_state(1, np.array([-p0, -1.2 * p0, -1.5 * p0, 0, 0, 0]))
    target = np.array([-p0, -1.2 * p0, -1.5 * p0])
    gam = np.array([0.02, -0.01, 0.015])
    x = np.zeros(3)
    errs = []
    for _ in range(30):
        sig, trial, D = law.update(np.concatenate([x, gam])[None], state, 0.0)
        r = sig[0, :3] - target
        errs.append(np.linalg.norm(r) / p0)
        if errs[-1] < 1e-14:
            break
        x -= np.linalg.solve(D[0][:3, :3], r)
    print(Law.__name__, "mode", trial["mode"][0, 0], "errors", errs)
    assert trial["mode"][0, 0] > 0  # plastic
    assert errs[-1] < 1e-14
    q = [math.log(errs[k + 1] / errs[k]) / math.log(errs[k] / errs[k - 1])
         for k in range(1, len(errs) - 1) if errs[k - 1] < 5e-2 and errs[k + 1] > 1e-13]
    print("observed orders", q)
    assert q, errs
    assert all(qk >= 1.8 for qk in q), q


def test_validation_and_state():
    with pytest.raises(ConstitutiveError, match="psi_deg"):
        MohrCoulomb(E=1e4, nu=0.3, c=1.0, phi_deg=20.0, psi_deg=25.0)
    with pytest.raises(ConstitutiveError, match="phi_deg"):
        DruckerPrager(E=1e4, nu=0.3, c=1.0, phi_deg=95.0)
    with pytest.raises(ConstitutiveError, match="no strength"):
        MohrCoulomb(E=1e4, nu=0.3, c=0.0, phi_deg=0.0)
    law = MohrCoulomb(**soil_kwargs(2))
    st0 = law.initial_state(4, np.array([-10.0, -10, -10, 0, 0, 0]))
    snap = {k: v.copy() for k, v in st0.items()}
    law.update(np.full((4, 6), -0.01), st0, 1.0)
    for k in st0:
        np.testing.assert_array_equal(st0[k], snap[k])
