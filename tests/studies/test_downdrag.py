"""Downdrag: the neutral-plane reading (pure) and the two verification cases through the pipeline.

The cases run ``pilegroup run``'s pipeline on a single pile in consolidating clay
(studies/verification/downdrag_cases.py, references and tolerances there); the file's tests
also run under ``mpirun -n 2``.
"""

import math

import numpy as np
import pytest

from pilegroup.studies.results.downdrag import neutral_plane
from pilegroup.studies.verification.downdrag_cases import (
    Q_KN,
    TAU_F,
    D,
    downdrag_end_bearing,
    downdrag_floating,
)


def _profile(z):
    """A pile of 20 m with 100 kN on the head, negative friction 10 kN/m to 8.3 m (its neutral
    plane), positive below: N = 100 + 10 z above, 100 + 10 zn - 10 (z - zn) below."""
    zn = 8.3
    return np.where(z <= zn, 100.0 + 10.0 * z, 100.0 + 10.0 * zn - 10.0 * (z - zn))


@pytest.mark.parametrize("n", [21, 34])
def test_neutral_plane_is_found_between_stations(n):
    z = np.linspace(0.25, 19.75, n)
    s_pile = np.full(n, 0.01)
    s_soil = 0.02 * (1 - z / 20.0)  # equal to the pile's at z = 10 m
    npl = neutral_plane(z, _profile(z), s_pile, s_soil)
    # a kink between stations: the parabola through the three stations around the largest
    # value places it within a station spacing, for any spacing
    assert abs(npl.depth_m - 8.3) < (z[1] - z[0])
    assert npl.head_load_kN == pytest.approx(_profile(z)[0])
    assert npl.dragload_kN == pytest.approx(npl.max_force_kN - npl.head_load_kN)
    assert npl.downdrag_m == pytest.approx(0.01)
    assert npl.equal_settlement_depth_m == pytest.approx(10.0)


def test_neutral_plane_of_a_smooth_profile_does_not_depend_on_the_stations():
    def force(z):
        return 500.0 - 2.0 * (z - 7.4) ** 2

    found = [neutral_plane(z, force(z), 0 * z, 0 * z).depth_m
             for z in (np.linspace(0.3, 15.0, 17), np.linspace(0.1, 14.8, 40))]
    assert found == pytest.approx([7.4, 7.4], abs=1e-9)


def test_no_negative_friction_gives_no_dragload():
    z = np.linspace(0.5, 10.0, 20)
    npl = neutral_plane(z, 300.0 - 20.0 * z, 0.01 + 0 * z, 0.0 * z)
    assert npl.dragload_kN == 0.0 and npl.depth_m == pytest.approx(z[0])
    assert math.isnan(npl.equal_settlement_depth_m)


def test_downdrag_end_bearing_case():
    r = downdrag_end_bearing()
    assert r.passed, r.line()
    assert r.details["reference_kN"] == pytest.approx(Q_KN + math.pi * D * TAU_F * 10.0)
    assert 9.0 < r.details["neutral_plane_depth_m"] <= 10.0  # at the stiff layer
    assert r.dofs > 0 and r.steps > 0


def test_downdrag_floating_case():
    r = downdrag_floating()
    assert r.passed, r.line()
    assert r.details["error_of_L"] <= 0.10 and r.details["settlement_error"] <= 0.05
    assert r.details["dragload_kN"] > 0.0


@pytest.mark.mpi
def test_downdrag_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, timeout=900)
