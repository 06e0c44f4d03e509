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

The stabilisation parameter tau = 3 / (lambda + 2 mu) (Q1-Q1) or 2 / (lambda + 2 mu) (Q2-Q1)
(``solver/forms.py::projection_tau``, docs/solver.md) makes the column's undrained pressure
operator the lumped mass matrix for any cell heights, widths and Poisson's ratio; a tau half as
large overshoots, and so does Taylor-Hood without the term.
"""

import numpy as np
import pytest
from mpi4py import MPI

from pilegroup.geometry.box import build_box, graded_levels
from pilegroup.solver import Discretisation
from pilegroup.studies import verification as ver
from pilegroup.studies.verification.common import ElasticSoil
from pilegroup.studies.verification.consolidation import TerzaghiColumn, p_along

T_STEP = 1e-6
TOL = 0.02
#: Bulk modulus of water, kPa (2.2 GPa at 20 degrees C).
K_W = 2.2e6


def undrained_pressure(soil=None):
    col = TerzaghiColumn() if soil is None else TerzaghiColumn(soil=soil)
    soil = col.soil
    E, nu, n = soil.E, soil.nu, soil.porosity
    m_v = (1 + nu) * (1 - 2 * nu) / (E * (1 - nu))
    return col.q * m_v / (m_v + n / K_W)


def errors(nodes, p0):
    """Largest |p| and largest jump between adjacent nodes below the drained one, over p0."""
    assert nodes[0] == pytest.approx(0.0, abs=1e-9)  # the drained top
    return {"max_error": abs(np.abs(nodes).max() - p0) / p0,
            "adjacent": np.abs(np.diff(nodes[1:])).max() / p0, "nodes": nodes / p0}


def tiny_step(pair, stab_factor=1.0, stabilise=True):
    r = ver.first_step_oscillation(pair, stabilise, nz=16, T_first=T_STEP, undrained_first=False,
                                   stab_factor=stab_factor)
    return errors(r["nodes"], undrained_pressure())


def test_undrained_pressure_is_the_columns_own():
    assert undrained_pressure() == pytest.approx(TerzaghiColumn().p0, rel=1e-12)
    assert 0.99 < undrained_pressure() / TerzaghiColumn().q < 1.0  # water nearly incompressible


@pytest.mark.parametrize("pair", ["Q1Q1", "Q2Q1"])
def test_a_tiny_step_has_no_oscillation(pair):
    r = tiny_step(pair)
    assert r["max_error"] < TOL, r["nodes"]
    assert r["adjacent"] < TOL, r["nodes"]


@pytest.mark.parametrize("pair", ["Q1Q1", "Q2Q1"])
def test_half_the_parameter_overshoots(pair):
    r = tiny_step(pair, stab_factor=0.5)
    assert r["max_error"] > 5 * TOL, r["nodes"]


def test_unstabilised_taylor_hood_overshoots():
    """Without the term Q2-Q1 overshoots next to the drained node (1D: 1.267 p0, then 0.93)."""
    r = tiny_step("Q2Q1", stabilise=False)
    assert r["max_error"] > 10 * TOL, r["nodes"]


@pytest.mark.parametrize("pair", ["Q1Q1", "Q2Q1"])
@pytest.mark.parametrize("nu", [0.3, 0.42])
def test_graded_flat_cells_have_no_oscillation(nu, pair):
    """A 3 m x 0.5 m column of 12 cells graded 1:4 (0.38 m at the top, 1.52 m at the bottom)."""
    soil = ElasticSoil(nu=nu)
    col = TerzaghiColumn(soil=soil)
    z = graded_levels(-col.H, 0.0, 12, ratio=4.0)
    md = build_box(MPI.COMM_WORLD, (0.0, 3.0), (0.0, 0.5), z, 1, 1)
    pb = col.problem(md, Discretisation(pair=pair))
    info = pb.solve_step(T_STEP * col.H**2 / col.cv, 1.0)
    assert info.converged, info.message
    r = errors(p_along(pb, z[::-1], 1.5, 0.25), undrained_pressure(soil))
    assert r["max_error"] < TOL, r["nodes"]
    assert r["adjacent"] < TOL, r["nodes"]
