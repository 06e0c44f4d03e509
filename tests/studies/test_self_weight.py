"""The self-weight settlement closed form against a column computed by hand."""

import dataclasses

import pytest

from pilegroup.model import load_scenario
from pilegroup.studies.campaigns.self_weight import oedometric_modulus, self_weight_settlement


def test_oedometric_modulus_of_nu_zero_is_E_and_grows_with_nu():
    assert oedometric_modulus(1000.0, 0.0) == pytest.approx(1000.0)
    # nu = 0.25: (0.75) / (1.25 * 0.5) = 1.2
    assert oedometric_modulus(1000.0, 0.25) == pytest.approx(1200.0)


def test_two_layer_column_by_hand():
    sc = load_scenario("pier667")
    lay = list(sc.layers)
    # two layers: 2 m (gamma 20, E 10 MPa) over the rest (gamma 18, E 20 MPa), both nu = 0.25
    # (E_oed = 1.2 E: 12 and 24 MPa)
    top = dataclasses.replace(lay[0], thickness_m=2.0, gamma_kN_per_m3=20.0, E_MPa=10.0,
                              nu=0.25)
    rest = dataclasses.replace(lay[1], thickness_m=None, gamma_kN_per_m3=18.0, E_MPa=20.0,
                               nu=0.25)
    sc2 = dataclasses.replace(sc, layers=(top, rest))
    res = self_weight_settlement(sc2, gamma_w=10.0)
    depth = sc.site.depth_m
    # layer 1: gamma' = 10, s = 2 * (0 + 10 * 2 / 2) / 12000 m
    assert res[0].settlement_m == pytest.approx(20.0 / 12000.0, rel=1e-12)
    # layer 2: top stress 20 kPa, gamma' = 8, H = depth - 2
    h = depth - 2.0
    assert res[1].settlement_m == pytest.approx(h * (20.0 + 4.0 * h) / 24000.0, rel=1e-12)
    assert (res[1].top_m, res[1].bottom_m) == (2.0, depth)
