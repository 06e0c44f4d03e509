"""The self-weight settlement closed form against a column computed by hand."""

import dataclasses

import pytest

from pilegroup.model import load_scenario
from pilegroup.model.units import GAMMA_WATER as GW
from pilegroup.studies.campaigns.self_weight import oedometric_modulus, self_weight_settlement


def test_oedometric_modulus_of_nu_zero_is_E_and_grows_with_nu():
    assert oedometric_modulus(1000.0, 0.0) == pytest.approx(1000.0)
    # nu = 0.25: (0.75) / (1.25 * 0.5) = 1.2
    assert oedometric_modulus(1000.0, 0.25) == pytest.approx(1200.0)


def _two_layers(wt=0.0, **rest):
    """pier667 as two layers: 2 m (gamma 20, dry 16, E 10 MPa) over the rest (gamma 18, E 20
    MPa), both nu = 0.25 (E_oed = 1.2 E: 12 and 24 MPa), the water table ``wt`` m down."""
    sc = load_scenario("pier667")
    lay = list(sc.layers)
    top = dataclasses.replace(lay[0], thickness_m=2.0, gamma_kN_per_m3=20.0, E_MPa=10.0,
                              nu=0.25, gamma_unsat_kN_per_m3=16.0)
    low = dataclasses.replace(lay[1], thickness_m=None, gamma_kN_per_m3=18.0, E_MPa=20.0,
                              nu=0.25, **rest)
    return dataclasses.replace(sc, site=dataclasses.replace(sc.site, water_table_depth_m=wt),
                               layers=(top, low), reference=None)  # the paper's: 10 layers


def test_two_layer_column_by_hand():
    sc = _two_layers()
    res = self_weight_settlement(sc)
    depth = sc.site.depth_m
    # layer 1: gamma' = 20 - gw, s = 2 * (0 + gamma' * 2 / 2) / 12000 m
    assert res[0].settlement_m == pytest.approx(2.0 * (20.0 - GW) / 12000.0, rel=1e-12)
    # layer 2: top stress 2 gamma'_1, gamma' = 18 - gw, H = depth - 2
    h, s2 = depth - 2.0, 2.0 * (20.0 - GW)
    assert res[1].settlement_m == pytest.approx(h * (s2 + (18.0 - GW) * h / 2) / 24000.0,
                                                rel=1e-12)
    assert (res[1].top_m, res[1].bottom_m) == (2.0, depth)


def test_water_table_below_the_ground_by_hand():
    """The water table 1 m down: the first metre carries its dry weight (16), the rest of the
    top layer and the layer below their buoyant weight."""
    sc = _two_layers(1.0)
    res = self_weight_settlement(sc)
    s1 = 16.0 * 1.0  # at the water table
    s2 = s1 + (20.0 - GW) * 1.0  # at the layer boundary
    top = 1.0 * (0.0 + s1) / 2 + 1.0 * (s1 + s2) / 2
    assert res[0].settlement_m == pytest.approx(top / 12000.0, rel=1e-12)
    h = sc.site.depth_m - 2.0
    assert res[1].settlement_m == pytest.approx(h * (s2 + (18.0 - GW) * h / 2) / 24000.0,
                                                rel=1e-12)


def test_seepage_at_rest_takes_off_the_effective_stress():
    """The lower layer held 1 m above the ground (artesian, the water table at the surface):
    its pore pressure at rest is gw x 1 m above the hydrostatic one, the top layer's rises linearly
    to it, and the effective stress that compresses the soil is less by that much."""
    sc = _two_layers(0.0, piezometric_depth_m=-1.0)
    res = self_weight_settlement(sc)
    u = 1.0 * GW
    s2 = 2.0 * (20.0 - GW) - u
    assert res[0].settlement_m == pytest.approx(2.0 * (0.0 + s2) / 2 / 12000.0, rel=1e-12)
    h = sc.site.depth_m - 2.0
    assert res[1].settlement_m == pytest.approx(h * (s2 + (18.0 - GW) * h / 2) / 24000.0,
                                                rel=1e-12)
