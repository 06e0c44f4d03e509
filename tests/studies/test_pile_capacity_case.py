"""The pile-capacity verification case and the base bearing limit it verifies.

The case runs ``pilegroup run``'s pipeline on a single pile with a capacity stage
(studies/verification/capacity_cases.py, reference and tolerance there); the file's tests also
run under ``mpirun -n 2``. The scenario key ``layers.interface.base_bearing_kPa`` reaches the
base laws only, and a limit the in-situ stress already exceeds is refused.
"""

import math

import pytest

from pilegroup.errors import ScenarioError
from pilegroup.model import scenario_from_dict
from pilegroup.studies.run.pipeline import interface_coupling
from pilegroup.studies.verification.capacity_cases import (
    OVERLOAD,
    STEPS,
    capacity_reference,
    pile_capacity,
    pile_capacity_scenario,
)


def test_reference_is_the_textbook_sum_for_the_circle():
    """d = 1 m, L = 5 m: shaft k pi d L with k = 2 c / sqrt 3, toe 9 c_u pi d^2 / 4."""
    ref = capacity_reference()
    assert ref["shaft_kN"] == pytest.approx(2 * 20.0 / math.sqrt(3) * math.pi * 5.0, rel=1e-14)
    assert ref["toe_kN"] == pytest.approx(9 * 20.0 * math.pi / 4, rel=1e-14)


def test_pile_capacity_case():
    r = pile_capacity()
    assert r.passed, r.line()
    d = r.details
    assert d["governing"] == "plunging" and d["end"]["message"] == "both criteria reached"
    # the plunging load is a point of the ramp: within two of its steps of the closed form
    step = OVERLOAD * capacity_reference()["ultimate_kN"] / STEPS
    assert abs(d["ultimate_kN_run"] - d["ultimate_kN"]) <= 2 * step
    # the pile's own curve reads its head force below the top element layer's mid-height
    assert d["pile_curve_ultimate_kN"] < d["ultimate_kN_run"]
    assert d["settlement_10pct_d_kN"] > d["plunging_kN"]


def test_base_bearing_reaches_the_base_laws_only():
    sc = scenario_from_dict(pile_capacity_scenario())
    laws = interface_coupling(sc, 0.25).laws
    qb = sc.layers[0].interface.base_bearing_kPa
    assert [law.bearing for law in laws] == [None, qb]


def _with_bearing(value):
    doc = pile_capacity_scenario()
    doc["layers"][0]["interface"]["base_bearing_kPa"] = value
    return doc


@pytest.mark.parametrize(("value", "match"), [
    (0.0, r"layers\[0\]\.interface\.base_bearing_kPa \(layer 1\) = 0\.0 \(kPa\): must be a "
          r"finite number > 0"),
    (2.0e5, r"base_bearing_kPa \(layer 1\) = 200000\.0 \(kPa\): must be in \[1, 100000\]"),
    (40.0, r"layers\[0\]\.interface\.base_bearing_kPa \(layer 1\) = 40\.0 \(kPa\): must exceed "
           r"the in-situ vertical effective stress at the toe of pile 1 \(40\.95 kPa at 5 m\)"),
])
def test_bad_base_bearing_is_refused(value, match):
    with pytest.raises(ScenarioError, match=match):
        scenario_from_dict(_with_bearing(value))


@pytest.mark.mpi
def test_pile_capacity_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, timeout=600)
