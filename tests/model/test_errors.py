"""The error family and the shared value checks (pilegroup.errors, pilegroup.validate)."""

import math
import re

import numpy as np
import pytest

from pilegroup.constitutive.soil import LinearElastic
from pilegroup.errors import (
    ConstitutiveError,
    PilegroupError,
    ScenarioError,
    SolverError,
    SolverInputError,
)
from pilegroup.solver.inputs import ElasticSolid
from pilegroup.validate import (
    require_finite,
    require_in_range,
    require_non_negative,
    require_one_of,
    require_positive,
)


def test_every_input_error_is_a_pilegroup_error_and_a_value_error():
    for cls in (ScenarioError, ConstitutiveError, SolverInputError):
        assert issubclass(cls, PilegroupError) and issubclass(cls, ValueError)
    assert issubclass(SolverInputError, SolverError)
    with pytest.raises(PilegroupError):
        LinearElastic(E=-1.0, nu=0.3)


@pytest.mark.parametrize(("check", "value", "message"), [
    (require_finite, math.nan, "d = nan (m): must be a finite number"),
    (require_finite, True, "d = True (m): must be a finite number"),
    (require_finite, "1.0", "d = '1.0' (m): must be a finite number"),
    (require_positive, 0.0, "d = 0.0 (m): must be a finite number > 0"),
    (require_positive, math.inf, "d = inf (m): must be a finite number"),
    (require_non_negative, -1e-300, "d = -1e-300 (m): must be a finite number >= 0"),
])
def test_checks_name_key_value_unit_and_rule(check, value, message):
    with pytest.raises(ScenarioError) as info:
        check("d", value, "m")
    err = info.value
    assert (err.key, err.unit) == ("d", "m") and err.value is value
    assert str(err) == message


def test_checks_accept_numpy_and_python_numbers():
    for v in (1, 2.5, np.float64(3.0), np.int64(4), np.float32(0.5)):
        require_positive("x", v)
        require_non_negative("x", v)
        require_in_range("x", v, 0.0, 4.0, hi_open=False)


@pytest.mark.parametrize(("lo_open", "hi_open", "interval"), [
    (False, False, "[0, 1]"), (True, False, "(0, 1]"), (False, True, "[0, 1)"),
    (True, True, "(0, 1)"),
])
def test_range_bounds_and_message(lo_open, hi_open, interval):
    require_in_range("r", 0.5, 0.0, 1.0, lo_open=lo_open, hi_open=hi_open)
    for v in (0.0, 1.0, math.nan, -math.inf):
        rejected = math.isnan(v) or math.isinf(v) or (v == 0.0 and lo_open) or (
            v == 1.0 and hi_open)
        if rejected:
            with pytest.raises(ScenarioError, match=re.escape(f"must be in {interval}")):
                require_in_range("r", v, 0.0, 1.0, lo_open=lo_open, hi_open=hi_open)
        else:
            require_in_range("r", v, 0.0, 1.0, lo_open=lo_open, hi_open=hi_open)


def test_the_error_class_says_who_rejected_the_value():
    with pytest.raises(ConstitutiveError, match=r"^E = -1.0 \(kPa\): must be a finite number > 0$"):
        LinearElastic(E=-1.0, nu=0.3)
    with pytest.raises(SolverInputError, match=r"^nu = 0.5 \(-\): must be in \(-1, 0.5\)$"):
        ElasticSolid(E=1.0, nu=0.5)
    with pytest.raises(SolverInputError, match="must be one of 'a', 'b'"):
        require_one_of("choice", "c", ("a", "b"), error=SolverInputError)
