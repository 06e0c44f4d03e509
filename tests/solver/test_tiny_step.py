"""Terzaghi's column loaded in one drained step of c_v dt / H^2 = 1e-6: no checkerboard.

The exact excess pressure at T_v = c_v t / H^2 = 1e-6 equals its undrained value p0 everywhere
but in a boundary layer under the drained top about 4 sqrt(c_v t) = 4e-3 H = 4 cm thick
(Terzaghi's series, ``terzaghi_series``), far thinner than one cell (H / 16 = 0.625 m). So every
pressure node below the drained one should hold p0: the largest |p| within 2 % of p0, and no
node-to-node oscillation (adjacent nodes below the drained one within 2 % of p0 of each other).

The undrained value of a 1D column (no lateral strain) under a load q, grains incompressible:
the volume lost by the soil is the water's compression, -eps_v = S p with S = n / K_w, and
equilibrium gives q = sigma'_zz + p = M (-eps_v) + p with M = 1 / m_v the oedometric modulus, so

    p0 = q / (1 + M S) = q m_v / (m_v + S)

(Verruijt, Theory and Problems of Poroelasticity, 2016, ch. 2: the initial pressure of the
oedometer test; with incompressible water S = 0 and p0 = q).
"""

import numpy as np
import pytest

from pilegroup.studies import verification as ver
from pilegroup.studies.verification.consolidation import TerzaghiColumn

T_STEP = 1e-6
TOL = 0.02
#: Bulk modulus of water, kPa (2.2 GPa at 20 degrees C).
K_W = 2.2e6


def undrained_pressure():
    col = TerzaghiColumn()
    E, nu, n = col.soil.E, col.soil.nu, col.soil.porosity
    m_v = (1 + nu) * (1 - 2 * nu) / (E * (1 - nu))
    return col.q * m_v / (m_v + n / K_W)


def one_step_1d_optimal_q1q1_factor():
    """stab_factor with tau = 3 / (lambda + 2 mu) instead of 1 / (2 mu).

    On a column one cell wide, with p varying in z only, the full minus one-point mass of a Q1
    cell of height h is (h^2 / 12) int p' q', so the projection term is the perturbation
    beta int dp' q' with beta = tau h^2 / 12. The 1D analysis of the stabilised P1-P1 pair gives
    beta = h^2 / (4 (lambda + 2 mu)) for a monotone pressure at any step (Aguilar, Gaspar,
    Lisbona & Rodrigo, Int. J. Numer. Meth. Engng 75, 2008; Rodrigo, Gaspar, Hu & Zikatanov,
    Comput. Methods Appl. Mech. Engrg 298, 2016): tau = 3 / (lambda + 2 mu).
    """
    soil = TerzaghiColumn().soil
    G = soil.E / (2 * (1 + soil.nu))
    M = soil.E * (1 - soil.nu) / ((1 + soil.nu) * (1 - 2 * soil.nu))
    return (3.0 / M) * (2.0 * G)


def tiny_step(pair, stab_factor=1.0):
    r = ver.first_step_oscillation(pair, True, nz=16, T_first=T_STEP, undrained_first=False,
                                   stab_factor=stab_factor)
    nodes = r["nodes"]
    assert nodes[0] == pytest.approx(0.0, abs=1e-9)  # the drained top
    p0 = undrained_pressure()
    below = nodes[1:]
    return {"max_error": abs(np.abs(r["profile"]).max() - p0) / p0,
            "adjacent": np.abs(np.diff(below)).max() / p0, "nodes": nodes / p0}


def test_undrained_pressure_is_the_columns_own():
    assert undrained_pressure() == pytest.approx(TerzaghiColumn().p0, rel=1e-12)
    assert 0.99 < undrained_pressure() / TerzaghiColumn().q < 1.0  # water nearly incompressible


def test_q1q1_with_the_1d_optimal_stabilisation_has_no_oscillation():
    r = tiny_step("Q1Q1", one_step_1d_optimal_q1q1_factor())
    assert r["max_error"] < TOL, r["nodes"]
    assert r["adjacent"] < TOL, r["nodes"]


# The pairs as the verification runs them overshoot next to the drained node (measured: max |p|
# 1.267 p0 for Q2-Q1, 1.134 p0 for Q1-Q1 with tau = 1/(2G); the nodes below swing back to
# 0.93 p0 and 0.98 p0). Strict: the test fails once a change removes the overshoot.
@pytest.mark.xfail(strict=True, raises=AssertionError,
                   reason="overshoot next to the drained node at c_v dt / h^2 << 1")
@pytest.mark.parametrize("pair", ["Q2Q1", "Q1Q1"])
def test_verification_pairs_at_a_tiny_step(pair):
    r = tiny_step(pair)
    assert r["max_error"] < TOL, r["nodes"]
    assert r["adjacent"] < TOL, r["nodes"]
