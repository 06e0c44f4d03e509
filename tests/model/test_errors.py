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


def test_a_long_value_is_shortened_in_messages():
    from pilegroup.errors import describe

    msg = str(ScenarioError("scenario.name", "x" * 10_000, "must be at most 64 characters"))
    assert msg == f"scenario.name = '{'x' * 59}... (10000 characters): must be at most 64 " \
        "characters"
    long_list = list(range(5000))
    shown = describe("time.output_days", long_list, "too many")
    assert shown.startswith("time.output_days = [0, 1, 2,") and len(shown) < 130
    assert f"... ({len(str(long_list))} characters): too many" in shown
    assert describe("k", "short", "ok") == "k = 'short': ok"  # short values unchanged


def test_a_scenario_file_that_is_not_utf8_is_invalid_input(tmp_path, capsys):
    from pilegroup.model import load_scenario
    from pilegroup.studies.cli.commands import main

    f = tmp_path / "latin1.toml"
    f.write_bytes('[scenario]\nname = "Müller"\n'.encode("latin-1"))
    with pytest.raises(ScenarioError, match=re.escape(
            f"file = '{f}': is not UTF-8 text (byte 20 of 27 is 0xfc); save it as UTF-8 TOML")):
        load_scenario(f)
    assert main(["run", str(f), "--out", str(tmp_path / "run")]) == 2
    lines = capsys.readouterr().err.splitlines()
    assert lines == [f"pilegroup: invalid input: file = '{f}': is not UTF-8 text (byte 20 of 27 "
                     "is 0xfc); save it as UTF-8 TOML"]
    assert main(["scenario", "validate", str(f)]) == 2
