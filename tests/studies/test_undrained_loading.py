"""``pilegroup verify undrained-loading``: a uniform fill gives a uniform undrained pressure.

On the meshes the mesher makes (bundled layouts and seeded random ones), with the default
discretisation; tolerance 2 % (studies/verification/undrained_cases.py).
"""

import numpy as np
import pytest

from pilegroup.model import scenario_from_dict
from pilegroup.studies.verification.undrained_cases import (
    fill_scenario,
    random_layout,
    undrained_loading,
)


@pytest.mark.parametrize("seed", [1, 2, 3, 4])
def test_random_layouts_are_valid_and_repeatable(seed):
    a, b = random_layout(seed), random_layout(seed)
    assert a == b
    sc = scenario_from_dict(fill_scenario(a))
    assert sc.numerics.element == "Q2Q1" and sc.stages[-1].kind == "surcharge"


def test_uniform_fill_gives_uniform_pressure_on_five_meshes():
    res = undrained_loading("fast")
    meshes = res.details["meshes"]
    assert len(meshes) >= 5
    assert res.passed, meshes
    for m in meshes:
        assert m["nodes"] > 100
        # the pressure is the fill's, not zero: the check reads the loaded state
        assert 0.97 * 60.0 < m["p_min_kPa"] <= m["p_max_kPa"] < 1.03 * 60.0
    assert np.isfinite(res.error) and res.error <= 0.02
