"""Piles installed into ground that is already moving: a fill at day -20, piles at day 0.

The small pile (the bundled single_pile, coarsened) with a site-wide 30 kPa fill placed from
day -20 and the pile installed at day 0 (an ``installation`` stage), loaded over day 0-0.5.
Runs are subprocesses under a timeout (``pilegroup run``), serial; steps of at most 0.25 day,
so that a run can be stopped after the installation and resumed.
"""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

BIN = Path(sys.executable).parent
TIMEOUT = 300  # s, every subprocess
SETS = ("outputs.plots=false", "numerics.time.dt_max_day=0.25", "numerics.time.dt_initial_day=0.05")

STAGES = '''[[stages]]
name = "geostatic"
kind = "geostatic"

[[stages]]
name = "fill"
kind = "surcharge"
surcharge_kPa = 30.0
duration_day = 1.0

[[stages]]
name = "settling"
kind = "consolidation"
until_day = 0.0

[[stages]]
name = "piles"
kind = "installation"

[[stages]]
name = "loading"
kind = "load"
cap_load_kN = 500.0
duration_day = 0.5

[[stages]]
name = "consolidation"
kind = "consolidation"

[time]
start_day = -20.0
end_day = 5.0
output_days = [-20.0, -19.0, 0.0, 0.5, 2.0, 5.0]

'''


@pytest.fixture(scope="module")
def scenario(tmp_path_factory, small_pile_source):
    text = small_pile_source
    f = tmp_path_factory.mktemp("scenario") / "installed_later.toml"
    f.write_text(text[:text.index("[[stages]]")] + STAGES + text[text.index("[numerics]"):])
    return f


def _command(scenario, out, resume=False):
    cmd = [str(BIN / "pilegroup"), "run", str(scenario), "--out", str(out)]
    return cmd + [a for kv in SETS for a in ("--set", kv)] + (["--resume"] if resume else [])


@pytest.fixture(scope="module")
def run(tmp_path_factory, scenario):
    out = tmp_path_factory.mktemp("later") / "run"
    r = subprocess.run(_command(scenario, out), capture_output=True, text=True, timeout=TIMEOUT)
    assert r.returncode == 0, r.stderr[-3000:]
    return out


def _rows(path):
    with path.open() as fh:
        return list(csv.DictReader(fh))


def test_the_ground_moves_before_the_pile_and_the_pile_after(run):
    assert json.loads((run / "summary.json").read_text())["status"] == "complete"
    settle = {(float(r["t_day"]), r["stage"]): float(r["settlement_m"])
              for r in _rows(run / "settlement.csv")}
    assert [t for t, _ in settle] == [-20.0, -19.0, 0.0, 0.0, 0.5, 2.0, 5.0]
    assert all(settle[k] == 0.0 for k in settle if k[0] <= 0.0)  # held until installed
    assert settle[(0.5, "loading")] > 5e-3
    prof = _rows(run / "settlement_profiles.csv")
    surface = {(float(r["t_day"]), i): float(r["soil_settlement_m"]) for i, r in enumerate(prof)
               if r["pile"] == "0" and float(r["depth_m"]) == 0.0}
    by_time = {}
    for (t, i), s in surface.items():
        by_time.setdefault(t, []).append((i, s))
    # the free field settles under the fill before the pile exists (3-6 mm) ...
    assert 2e-3 < sorted(by_time[0.0])[0][1] < 2e-2
    # ... and from the installation on counts from its settlement then
    assert sorted(by_time[0.0])[1][1] == 0.0
    assert abs(by_time[2.0][0][1]) < sorted(by_time[0.0])[0][1]
    # the soil beside the pile: the interface's jump counts from the installation
    beside = [float(r["soil_settlement_m"]) for r in prof
              if r["pile"] == "1" and r["t_day"] == "0"]
    assert beside[-len(beside) // 2:] == [0.0] * (len(beside) - len(beside) // 2)


def test_resume_after_the_installation_matches_the_straight_run(tmp_path, scenario, run):
    out = tmp_path / "run"
    err = tmp_path / "stderr.txt"
    with err.open("w") as fh:
        proc = subprocess.Popen(_command(scenario, out), stdout=subprocess.DEVNULL, stderr=fh,
                                text=True)
    try:
        deadline = time.monotonic() + TIMEOUT
        manifest = out / "checkpoint" / "manifest.json"
        while True:
            try:
                if json.loads(manifest.read_text())["t_day"] > 0.2:
                    break
            except (OSError, ValueError, KeyError):
                pass
            assert proc.poll() is None, f"run ended before the checkpoint: {err.read_text()}"
            assert time.monotonic() < deadline, "no checkpoint within the timeout"
            time.sleep(0.02)
        proc.send_signal(signal.SIGTERM)
        proc.wait(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:
            proc.kill()
    r = subprocess.run(_command(scenario, out, resume=True), capture_output=True, text=True,
                       timeout=TIMEOUT, env=os.environ)
    assert r.returncode == 0, r.stderr[-3000:]
    for name in ("settlement.csv", "settlement_profiles.csv", "neutral_plane.csv"):
        a, b = _rows(run / name), _rows(out / name)
        assert len(a) == len(b), name
        for ra, rb in zip(a, b, strict=True):
            for k in ra:
                try:
                    x, y = float(ra[k]), float(rb[k])
                except ValueError:
                    assert ra[k] == rb[k], (name, k)
                    continue
                assert x == pytest.approx(y, rel=1e-9, abs=1e-15), (name, k, ra, rb)
    assert np.isfinite(float(_rows(out / "settlement.csv")[-1]["settlement_m"]))
