"""The soft-soil verification cases (one material point each, no mesh): registered, passing.

Closed forms: Wood (1990) undrained path of Modified Cam Clay, the normal compression line
(Roscoe & Burland 1968), the logarithmic creep of Soft Soil Creep (Vermeer & Neher 1999).
"""

import json
from dataclasses import asdict

import pytest

from pilegroup.fileio import json_default
from pilegroup.studies.verification import CASES
from pilegroup.studies.verification.registry import run_case

NAMES = ("mcc-undrained-triaxial", "mcc-compression-line", "ssc-creep")


def test_registered_under_their_names():
    assert all(name in CASES for name in NAMES)


@pytest.mark.parametrize(("name", "bound"), [
    ("mcc-undrained-triaxial", 1e-12),  # the path is exact at every step (exact exponentials)
    ("mcc-compression-line", 5e-4),  # first order in the step: 1.0e-4 at 40 steps
    ("ssc-creep", 8e-3),  # backward Euler, times growing by 10 % a step: 5.1e-3
])
def test_case_passes(name, bound):
    res = run_case(name, "fast", pair="Q1Q1", preset="direct")  # options it does not take
    print(res.line())
    assert res.passed and res.error <= bound < res.tolerance
    assert res.reference and res.steps > 0
    json.dumps(asdict(res), default=json_default)  # the --json output
