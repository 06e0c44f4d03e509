"""Downdrag closed forms (studies/results/downdrag.py): pure numpy/scipy, no mesh, no MPI.

(a) the neutral plane read from hand-built profiles; (b) the unified method's force balance
against hand calculations; (c) the radial consolidation series of Randolph & Wroth (1979)
against its initial condition, an independent finite-volume solution of the same PDE
(method of lines, scipy ``solve_ivp``) and its limits at large time.
"""

import math

import numpy as np
import pytest
from scipy import sparse
from scipy.integrate import solve_ivp

from pilegroup.studies.results.downdrag import (
    beta_friction,
    cavity_expansion_pressure,
    effective_vertical_stress,
    end_bearing_force,
    force_balance,
    friction_integral,
    initial_excess_pressure,
    neutral_plane,
    radial_consolidation_coefficient,
    radial_excess_pressure,
    radial_series,
    time_factor,
    unified_force_profile,
)

# -- (a) neutral plane from profiles -----------------------------------------------------------

L_PILE, U_PILE, Q_HEAD = 20.0, math.pi * 0.6, 400.0
ZN, A_SLOPE = 7.3, 3.0  # friction f = A (z - ZN) kPa (positive supporting): negative above ZN


def _linear_friction_profiles(z):
    """Friction linear in depth through zero at ZN: dN/dz = -U f, so
    N = Q - U A (z^2/2 - ZN z), largest at ZN with N_max = Q + U A ZN^2 / 2 (quadratic in z).
    Pile settlement 10 mm at the head, shortening 0.2 mm/m; the soil settles more above ZN and
    less below: s_soil = s_pile + 1e-3 (ZN - z), equal at ZN."""
    N = Q_HEAD - U_PILE * A_SLOPE * (z**2 / 2 - ZN * z)
    s_pile = 0.010 - 2e-4 * z
    return N, s_pile, s_pile + 1e-3 * (ZN - z)


@pytest.mark.parametrize("dz", [0.5, 0.37])
def test_neutral_plane_of_linear_friction_is_the_analytical_one(dz):
    z = np.arange(dz / 2, L_PILE, dz)  # element mid-heights: no station at the head nor at ZN
    N, s_pile, s_soil = _linear_friction_profiles(z)
    npl = neutral_plane(z, N, s_pile, s_soil, head_load=Q_HEAD)
    assert abs(npl.depth_m - ZN) < 1e-9 * L_PILE
    assert npl.dragload_kN == pytest.approx(U_PILE * A_SLOPE * ZN**2 / 2, rel=1e-9)
    assert npl.head_load_kN == Q_HEAD
    assert npl.downdrag_m == pytest.approx(0.010 - 2e-4 * ZN, rel=1e-9)
    assert npl.equal_settlement_depth_m == pytest.approx(ZN, rel=1e-9)


def test_neutral_plane_does_not_depend_on_the_station_spacing():
    found = []
    for z in (np.linspace(0.25, 19.75, 40), np.linspace(0.1, 19.9, 67)):
        N, s_pile, s_soil = _linear_friction_profiles(z)
        found.append(neutral_plane(z, N, s_pile, s_soil).depth_m)
    assert abs(found[0] - found[1]) < 1e-6 * L_PILE


@pytest.mark.parametrize("n", [41, 81, 161])
def test_neutral_plane_at_a_kink_is_within_a_station_spacing(n):
    # beta friction f = 2 z (a jump from -2 zn to +2 zn at zn): N has a kink there
    bal = force_balance(L_PILE, U_PILE, lambda z: 2.0 * z, Q_HEAD, 150.0)
    z = np.linspace(0.0, L_PILE, n)
    N = unified_force_profile(z, U_PILE, lambda s: 2.0 * s, Q_HEAD, bal.depth_m)
    npl = neutral_plane(z, N, 0 * z, 0 * z)
    h = z[1] - z[0]
    assert abs(npl.depth_m - bal.depth_m) < h  # measured 0.033, 0.022, 0.0006 m
    # the parabola cuts the corner: less than half a spacing of the slope U f(zn) = U 2 zn
    # (measured -2.6, -2.5, -2.0 kN)
    assert abs(npl.max_force_kN - bal.max_force_kN) < U_PILE * 2.0 * bal.depth_m * h / 2


def test_no_negative_friction_puts_the_neutral_plane_at_the_head():
    z = np.arange(0.25, 10.0, 0.5)
    npl = neutral_plane(z, 300.0 - 20.0 * z, 0.01 + 0 * z, 0.0 * z, head_load=305.0)
    assert npl.depth_m == 0.0 and npl.dragload_kN == 0.0 and npl.max_force_kN == 305.0
    assert npl.downdrag_m == pytest.approx(0.01)
    assert math.isnan(npl.equal_settlement_depth_m)


def test_end_bearing_pile_has_its_neutral_plane_at_the_toe():
    # fully mobilised negative friction f = 15 kPa over the whole pile, toe on rock
    z = np.linspace(0.0, L_PILE, 41)
    f = 15.0
    N = Q_HEAD + U_PILE * f * z
    npl = neutral_plane(z, N, 0.004 + 0 * z, 0.05 * (1 - z / 25.0))
    assert npl.depth_m == L_PILE
    ref = end_bearing_force(Q_HEAD, U_PILE, lambda s: f + 0 * s, L_PILE)
    assert npl.max_force_kN == pytest.approx(ref, rel=1e-12)
    assert npl.dragload_kN == pytest.approx(U_PILE * f * L_PILE, rel=1e-12)
    assert math.isnan(npl.equal_settlement_depth_m)  # the soil settles more all along


# -- (b) force balance ------------------------------------------------------------------------


def test_force_balance_with_uniform_friction_matches_the_hand_calculation():
    # Q + U f zn = U f (L - zn) + Rt  =>  2 U f zn = U f L - (Q - Rt)
    #                                 =>  zn = (L - (Q - Rt) / (U f)) / 2.
    # L = 20 m, d = 0.6 m (U = 1.885 m), f = 25 kPa (U f = 47.124 kN/m), Q = 800, Rt = 300 kN:
    # (Q - Rt)/(U f) = 10.610 m, zn = 4.695 m, N(zn) = 800 + 47.124 * 4.695 = 1021.2 kN.
    L, U, f, Q, Rt = 20.0, math.pi * 0.6, 25.0, 800.0, 300.0
    zn = (L - (Q - Rt) / (U * f)) / 2
    assert zn == pytest.approx(4.695, abs=1e-3)
    for friction in (lambda z: f + 0 * z, ([0.0, L], [f, f])):
        b = force_balance(L, U, friction, Q, Rt)
        assert b.depth_m == pytest.approx(zn, abs=1e-9 * L)
        assert b.max_force_kN == pytest.approx(Q + U * f * zn, rel=1e-12)
        assert b.max_force_kN == pytest.approx(1021.2, abs=0.1)
        assert b.dragload_kN == pytest.approx(U * f * zn, rel=1e-12)
        assert b.toe_force_kN == pytest.approx(Rt, rel=1e-9)
        assert b.positive_shaft_kN == pytest.approx(U * f * (L - zn), rel=1e-9)


def test_force_balance_with_friction_growing_with_depth():
    # f = k z: F(z) = k z^2 / 2, and F(zn) = (F(L) + (Rt - Q)/U) / 2 gives
    # zn = sqrt(L^2 / 2 + (Rt - Q) / (U k)).
    L, U, k, Q, Rt = 20.0, math.pi * 0.6, 2.5, 800.0, 300.0
    zn = math.sqrt(L**2 / 2 + (Rt - Q) / (U * k))
    z = np.linspace(0.0, L, 11)
    for friction in (lambda s: k * s, (z, k * z)):
        b = force_balance(L, U, friction, Q, Rt)
        assert b.depth_m == pytest.approx(zn, abs=1e-9 * L)
        assert b.max_force_kN == pytest.approx(Q + U * k * zn**2 / 2, rel=1e-10)


def test_force_balance_limits():
    U, f = math.pi * 0.6, 10.0  # U f L = 377 kN
    toe = force_balance(20.0, U, lambda z: f + 0 * z, 100.0, 2000.0)
    assert toe.depth_m == 20.0 and toe.toe_force_kN == pytest.approx(100.0 + U * f * 20.0)
    with pytest.raises(ValueError, match="no equilibrium"):
        force_balance(20.0, U, lambda z: f + 0 * z, 1000.0, 100.0)


def test_beta_friction_against_a_hand_calculation():
    # two layers 4 m and 10 m (the second continues below 14 m), buoyant weights 8 and 7,
    # fill 20 kPa: sigma'_v(2) = 20 + 16 = 36, (6) = 20 + 32 + 14 = 66, (20) = 20 + 32 + 112 = 164
    thk, g, q = [4.0, 10.0], [8.0, 7.0], 20.0
    sv = effective_vertical_stress(np.array([0.0, 2.0, 4.0, 6.0, 20.0]), thk, g, q)
    assert sv == pytest.approx([20.0, 36.0, 52.0, 66.0, 164.0], rel=1e-14)
    t20, t25 = math.tan(math.radians(20.0)), math.tan(math.radians(25.0))
    f = beta_friction(np.array([2.0, 4.0, 6.0]), thk, g, K=[0.8, 1.0], delta_deg=[20.0, 25.0],
                      adhesion_kPa=[5.0, 0.0], surcharge_kPa=q)
    assert f == pytest.approx([5.0 + 0.8 * 36.0 * t20, 52.0 * t25, 66.0 * t25], rel=1e-14)

    # the callable with the layer boundary as a break point against the exact integral of the
    # piecewise-linear profile with its jump at 4 m (a repeated station)
    def fz(z):
        return beta_friction(z, thk, g, [0.8, 1.0], [20.0, 25.0], [5.0, 0.0], q)

    zs = np.array([0.0, 4.0, 4.0, 14.0, 18.0])
    fs = np.r_[fz(np.array([0.0])), 5.0 + 0.8 * 52.0 * t20, fz(zs[2:])]
    for zq in (3.0, 9.0, 18.0):
        assert friction_integral(fz, zq, breaks=[4.0]) == pytest.approx(
            friction_integral((zs, fs), zq), rel=1e-11)
    a = force_balance(18.0, math.pi * 0.5, fz, 300.0, 200.0, breaks=[4.0])
    b = force_balance(18.0, math.pi * 0.5, (zs, fs), 300.0, 200.0)
    assert a.depth_m == pytest.approx(b.depth_m, abs=1e-9)
    assert end_bearing_force(300.0, math.pi * 0.5, fz, 14.0, breaks=[4.0]) == pytest.approx(
        300.0 + math.pi * 0.5 * float(friction_integral((zs, fs), 14.0)), rel=1e-11)


# -- (c) radial consolidation around a driven pile --------------------------------------------

R0, RHO = 1.0, 20.0  # r* = 20 r0; the plastic radius of G/c_u = 100 is R = 10 r0
CU, G_SHEAR = 20.0, 2000.0


def _initial():
    du_max, R = cavity_expansion_pressure(CU, G_SHEAR, R0)
    return du_max, R


def _finite_volumes(drained, times, n=2000):
    """The PDE in s = r/r0, T on n vertex-centred finite volumes (uniform s), zero flux at
    s = 1, u = 0 or zero flux at s = rho; BDF with the exact sparse Jacobian. Returns u at the
    shaft at ``times``."""
    s = np.linspace(1.0, RHO, n + 1)
    h = s[1] - s[0]
    c = 0.5 * (s[1:] + s[:-1]) / h  # face radius / spacing
    V = s * h
    V[0], V[-1] = ((1 + h / 2) ** 2 - 1) / 2, (RHO**2 - (RHO - h / 2) ** 2) / 2
    diag = np.zeros(n + 1)
    diag[:-1] -= c
    diag[1:] -= c
    A = (sparse.diags(1 / V) @ sparse.diags([diag, c, c], [0, 1, -1])).tocsc()
    du_max, R = _initial()
    u0 = initial_excess_pressure(s * R0, R0, du_max, R)
    if drained:
        A, u0 = A[:-1, :-1], u0[:-1]
    sol = solve_ivp(lambda t, u: A @ u, (0.0, max(times)), u0, method="BDF", jac=A,
                    t_eval=times, rtol=1e-10, atol=1e-10 * du_max)
    assert sol.success
    return sol.y[0]


def test_cavity_expansion_and_consolidation_helpers():
    du_max, R = _initial()
    assert R == pytest.approx(10.0 * R0) and du_max == pytest.approx(CU * math.log(100.0))
    E, nu, k = 3000.0, 0.3, 1e-4
    G, lam = E / (2 * (1 + nu)), E * nu / ((1 + nu) * (1 - 2 * nu))
    ch = radial_consolidation_coefficient(k, E, nu)
    assert ch == pytest.approx(k * (lam + 2 * G) / 9.81, rel=1e-14)
    assert time_factor(ch, np.array([10.0]), 0.3) == pytest.approx(ch * 10.0 / 0.09)


@pytest.mark.parametrize("drained", [True, False])
def test_series_reproduces_the_initial_pressure(drained):
    du_max, R = _initial()
    ser = radial_series(R0, RHO * R0, du_max, R, drained=drained, n_terms=200)
    r = np.linspace(R0, RHO * R0, 20001)
    u0 = initial_excess_pressure(r, R0, du_max, R)
    e = radial_excess_pressure(ser, r, 0.0) - u0
    l2 = math.sqrt(np.trapezoid(r * e**2, r) / np.trapezoid(r * u0**2, r))
    assert l2 < 0.01  # measured 5.4e-4 (200 terms)


@pytest.mark.parametrize("drained", [True, False])
def test_series_matches_finite_volumes_at_the_shaft(drained):
    du_max, R = _initial()
    times = [0.1, 1.0, 10.0, 100.0]
    ref = _finite_volumes(drained, times)
    ser = radial_series(R0, RHO * R0, du_max, R, drained=drained, n_terms=200)
    u = radial_excess_pressure(ser, R0, np.array(times))
    err = np.abs(u - ref) / np.abs(ref)
    print(f"drained={drained}: series {u} kPa, relative difference {err}")
    assert np.all(err < 0.005)  # measured <= 1e-5 (T = 0.1 .. 100)
    # by T = 100 the outer boundary shows: 3.66 kPa drained, 5.26 kPa impermeable
    other = radial_series(R0, RHO * R0, du_max, R, drained=not drained, n_terms=200)
    assert abs(radial_excess_pressure(other, R0, 100.0) - u[-1]) > 0.2 * abs(u[-1])


def test_impermeable_outer_radius_tends_to_the_mean_and_drained_to_zero():
    du_max, R = _initial()
    # area-weighted mean of u0: int_r0^R r ln(R/r) dr = (R^2 - r0^2)/4 - r0^2 ln(R/r0)/2
    r_out = RHO * R0
    mean = (du_max / math.log(R / R0) * ((R**2 - R0**2) / 4 - R0**2 * math.log(R / R0) / 2)
            / ((r_out**2 - R0**2) / 2))
    closed = radial_series(R0, r_out, du_max, R, drained=False)
    assert closed.mean_kPa == pytest.approx(mean, rel=1e-10)
    r = np.array([R0, 5.0 * R0, r_out])
    assert radial_excess_pressure(closed, r, 1e4) == pytest.approx([mean] * 3, rel=1e-10)
    drained = radial_series(R0, r_out, du_max, R, drained=True)
    u = radial_excess_pressure(drained, R0, np.array([1.0, 10.0, 100.0, 1e3, 1e4]))
    assert np.all(np.diff(u) < 0.0) and abs(u[-1]) < 1e-9 * du_max
