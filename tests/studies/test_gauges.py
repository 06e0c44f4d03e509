"""The field method (Eqs. 1-3, studies/results/gauges.py) against values derived by hand.

A linear strain profile eps(z) = a + b z (compression positive, z depth) on a pile of modulus
E, area A and circumference U gives, by hand:

* Eq. 1: N(z) = E A (a + b z), linear;
* Eq. 2: N_i - N_{i+1} = -E A b l_i, so f = -E A b / U on every interval (constant);
* Eq. 3: the trapezoid rule is exact for a linear strain, so below the first section
  w(z) = w0 - integral_0^z eps = w0 - a z - b z^2 / 2 (quadratic), except for the first
  interval, from the pile top to section 1, whose strain is taken as eps(z_1) (no gauge at the
  top): it shortens by z_1 (a + b z_1) instead of a z_1 + b z_1^2 / 2, i.e. b z_1^2 / 2 more.
"""

import numpy as np
import pytest

from pilegroup.studies.results.gauges import field_reduction, interval_means, nearest_times

E, A, U = 3.0e7, 0.5, 2.5  # kPa, m^2, m
a, b = 4.0e-4, -5.0e-6  # strain at the top, per m of depth
W0 = 0.012  # m


def test_linear_strain_gives_linear_force_constant_friction_quadratic_displacement():
    z = np.array([1.0, 4.0, 8.0, 11.5])
    N, f, w = field_reduction(z, a + b * z, E, A, U, W0)
    # E A = 1.5e7 kN: N = 1.5e7 (4e-4 - 5e-6 z) = 6000 - 75 z kN
    assert N == pytest.approx([5925.0, 5700.0, 5400.0, 5137.5], rel=1e-12)
    # f = -E A b / U = 1.5e7 * 5e-6 / 2.5 = 30 kPa on the three intervals, none below the last
    assert f[:3] == pytest.approx([30.0, 30.0, 30.0], rel=1e-12)
    assert np.isnan(f[3])
    # w = W0 - a z - b z^2 / 2 - b z_1^2 / 2 with z_1 = 1 m (the top interval's extra b z_1^2/2)
    expected = [0.012 - 4e-4 * 1.0 + 2.5e-6 * 1.0 + 2.5e-6,
                0.012 - 4e-4 * 4.0 + 2.5e-6 * 16.0 + 2.5e-6,
                0.012 - 4e-4 * 8.0 + 2.5e-6 * 64.0 + 2.5e-6,
                0.012 - 4e-4 * 11.5 + 2.5e-6 * 132.25 + 2.5e-6]
    assert w == pytest.approx(expected, rel=1e-12)


def test_a_section_at_the_pile_top_makes_the_displacement_exactly_quadratic():
    z = np.array([0.0, 2.0, 5.0])
    _, _, w = field_reduction(z, a + b * z, E, A, U, W0)
    assert w == pytest.approx([0.012, 0.012 - 8e-4 + 1e-5, 0.012 - 2e-3 + 6.25e-5], rel=1e-12)


def test_uniform_strain_has_no_friction_and_shortens_linearly():
    z = np.array([0.5, 3.0])
    N, f, w = field_reduction(z, [1e-4, 1e-4], E, A, U, 0.0)
    assert N == pytest.approx([1500.0, 1500.0])
    assert f[0] == 0.0
    assert w == pytest.approx([-0.5e-4, -3.0e-4], rel=1e-12)


@pytest.mark.parametrize("depths", [[2.0, 1.0], [1.0, 1.0], [-0.5, 1.0], []])
def test_depths_must_increase_from_the_ground(depths):
    with pytest.raises(ValueError, match="strictly increasing"):
        field_reduction(depths, np.zeros(len(depths)), E, A, U, 0.0)


def test_one_strain_per_section():
    with pytest.raises(ValueError, match="3 strains for 2 gauge depths"):
        field_reduction([1.0, 2.0], [0.0, 0.0, 0.0], E, A, U, 0.0)


def test_interval_means_of_a_piecewise_linear_profile():
    # v = z^2 sampled at z = 0, 1, 2, 3; over [0.5, 2.5] the interpolant has the values
    # 0.5, 1, 4, 6.5 at 0.5, 1, 2, 2.5: trapezoids 0.375 + 2.5 + 2.625 = 5.5 over 2 m = 2.75
    z = np.array([0.0, 1.0, 2.0, 3.0])
    m = interval_means(z, z**2, [0.5, 2.5, 3.0])
    assert m[0] == pytest.approx(2.75, rel=1e-12)
    # [2.5, 3]: linear from 6.5 to 9, mean 7.75
    assert m[1] == pytest.approx(7.75, rel=1e-12)
    assert np.isnan(m[2])


def test_nearest_output_times_leave_out_the_reference_time():
    assert nearest_times([0.0, 0.5, 2.0], (0, 30, 89, 180, 317)) == [0.5, 2.0]
    assert nearest_times([0.0, 1.0, 31.0, 90.0, 200.0, 317.0], (0, 30, 89, 180, 317)) \
        == [1.0, 31.0, 90.0, 200.0, 317.0]
    assert nearest_times([0.0], (0, 30)) == []


def test_scenario_lists_gauge_sections_top_down():
    import dataclasses

    from pilegroup.model import ScenarioError, load_scenario

    out = load_scenario("single_pile").outputs
    with pytest.raises(ScenarioError, match=r"gauge_depths_m\[2\] = 4.0 \(m\): must be greater"):
        dataclasses.replace(out, gauge_depths_m=(1.0, 4.0, 4.0))
