"""The cap-action verification cases (studies/verification/lateral_cases.py), fast sizes."""

import pytest

from pilegroup.studies.verification import lateral_cases as lat


def test_randolph_closed_form_is_reciprocal_and_scales():
    # Betti: the rotation per unit H equals the deflection per unit M
    u_m, _, _ = lat.randolph_head(0.0, 1.0, 0.6, 30e6, 3846.0, 0.3)
    _, t_h, lc = lat.randolph_head(1.0, 0.0, 0.6, 30e6, 3846.0, 0.3)
    assert u_m == pytest.approx(t_h, rel=1e-12)
    # l_c = d (E_p / G*)^(2/7), G* = G (1 + 3 nu / 4)
    assert lc == pytest.approx(0.6 * (30e6 / (3846.0 * 1.225)) ** (2 / 7), rel=1e-12)
    u1, t1, _ = lat.randolph_head(50.0, 20.0, 0.6, 30e6, 3846.0, 0.3)
    u2, t2, _ = lat.randolph_head(100.0, 40.0, 0.6, 30e6, 3846.0, 0.3)
    assert (u2, t2) == pytest.approx((2 * u1, 2 * t1), rel=1e-12)


def test_cap_equilibrium():
    r = lat.cap_equilibrium(size="fast")
    assert r.tolerance == 1e-6 and r.passed, r.details


def test_rigid_cap_moment():
    r = lat.rigid_cap_moment(size="fast")
    assert r.tolerance == 0.05 and r.passed, r.details
    # the axial forces carry most of the moment; the rest is the piles' own head moments
    assert 0.9 < r.details["axial_share_of_moment"] < 1.0


@pytest.mark.slow
def test_lateral_single_pile():
    r = lat.lateral_single_pile(size="fast")
    assert r.tolerance == 0.05 and r.passed, r.details
    assert r.details["element"] == "Q2Q1"


def test_stiffness_day_ends_the_scenario_at_a_stage_end_or_in_consolidation():
    from pilegroup.model import ScenarioError, load_scenario
    from pilegroup.studies.run.stiffness import scenario_until

    sc = load_scenario("pier667_lateral")
    at2 = scenario_until(sc, 2.0)
    assert [st.name for st in at2.stages] == ["geostatic", "loading", "braking"]
    assert at2.time.end_day == 2.0 and at2.time.output_days == (0.0, 1.0, 2.0)
    at30 = scenario_until(sc, 30.0)
    assert at30.stages[-1].until_day == 30.0 and at30.time.output_days[-1] == 30.0
    with pytest.raises(ScenarioError, match="inside the load stage 'braking'"):
        scenario_until(sc, 1.5)
    with pytest.raises(ScenarioError, match=r"must be in \(0, 317\]"):
        scenario_until(sc, 400.0)
