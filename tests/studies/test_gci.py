"""Richardson extrapolation and GCI against Celik et al. (2008) and manufactured sequences."""

import math

import pytest

from pilegroup.studies.campaigns.gci import gci, observed_order


def _h(n):
    """Representative size of a 2D grid of n cells (Celik et al. 2008, Eq. 1, unit area)."""
    return 1.0 / math.sqrt(n)


#: Table 1 of Celik et al. (2008): cells N1, N2, N3 (2D grids); phi1, phi2, phi3; then p,
#: phi_ext21, e_a21 and GCI_fine21 as printed there (p to 0.01, percentages to 0.1 %). Its
#: e_ext21 row is not used: this file checks e_ext21 against its definition instead.
CELIK_TABLE_1 = [
    ((18000, 8000, 4500), (6.063, 5.972, 5.863), 1.53, 6.1685, 0.015, 0.022),
    ((18000, 4500, 980), (10.7880, 10.7250, 10.6050), 0.75, 10.8801, 0.006, 0.011),
    ((18000, 4500, 980), (6.0042, 5.9624, 6.0909), 1.51, 6.0269, 0.007, 0.005),
]


@pytest.mark.parametrize("cells, phi, p, ext, e_a, gci_fine", CELIK_TABLE_1)
def test_celik_worked_example(cells, phi, p, ext, e_a, gci_fine):
    g = gci(tuple(_h(n) for n in cells), phi)
    assert g.p == pytest.approx(p, abs=0.005)
    assert g.phi_ext == pytest.approx(ext, abs=0.00005)
    assert g.e_a21 == pytest.approx(e_a, abs=0.0005)
    assert g.gci_fine21 == pytest.approx(gci_fine, abs=0.0005)
    assert g.e_ext21 == pytest.approx(abs((g.phi_ext - phi[0]) / g.phi_ext), rel=1e-14)


def test_oscillatory_sign_is_reported():
    g = gci(tuple(_h(n) for n in (18000, 4500, 980)), (6.0042, 5.9624, 6.0909))
    assert g.oscillatory and "oscillatory" in g.note
    g = gci(tuple(_h(n) for n in (18000, 8000, 4500)), (6.063, 5.972, 5.863))
    assert not g.oscillatory and "monotonic" in g.note


@pytest.mark.parametrize("p", [0.5, 1.0, 2.0, 3.5])
@pytest.mark.parametrize("h", [(0.1, 0.3, 0.6), (0.6, 0.8, 1.0), (0.5, 1.0, 2.0),
                               (0.8, 1.0, 3.0), (0.1, 0.11, 1.0)])
def test_manufactured_sequence_is_recovered(p, h):
    f0, c = 2.5, -0.7
    g = gci(h, tuple(f0 + c * x ** p for x in h))
    assert g.p == pytest.approx(p, abs=1e-10)
    assert g.phi_ext == pytest.approx(f0, abs=1e-10)
    # the GCI of an exact power law bounds the true error of the finest value by Fs
    true = abs((f0 + c * min(h) ** p - f0) / (f0 + c * min(h) ** p))
    assert g.gci_fine21 == pytest.approx(1.25 * true, rel=1e-8)


def test_sizes_may_come_in_any_order():
    a = gci((0.1, 0.3, 0.6), (1.0, 1.1, 1.4))
    b = gci((0.6, 0.1, 0.3), (1.4, 1.0, 1.1))
    assert a == b


def test_equal_values_leave_the_order_undefined():
    g = gci((0.3, 0.6, 1.0), (1.0, 1.0, 1.2))
    assert not g.defined and math.isnan(g.phi_ext) and "same value" in g.note
    with pytest.raises(ValueError):
        gci((0.3, 0.3, 1.0), (1.0, 1.1, 1.2))


def test_constant_ratio_needs_no_iteration():
    # r21 = r32 = 2 and differences halving: p = 1 exactly (q = 0)
    assert observed_order(2.0, 2.0, 0.1, 0.2) == pytest.approx(1.0, abs=1e-14)
