"""The stress suite (``pilegroup bench stability``): a fast subset of its cases and its checks.

Every case must finish or stop cleanly (exit 1 with one line and a failed summary, or exit 2
when the scenario rejects a value) and never write a NaN; a case that hangs is killed at its
timeout and is a row of the table.
"""

import json
import math
import os
import subprocess
import sys
import time
import tomllib

import h5py
import numpy as np
import pytest

from pilegroup.errors import ScenarioError
from pilegroup.model.loader import apply_overrides, parse_override, scenario_from_dict
from pilegroup.studies.bench import stability as bs
from pilegroup.studies.bench.benchrun import Finished, run_isolated
from pilegroup.studies.bench.small_pile import small_pile_scenario, small_pile_text

#: The fast subset: a 1e-6 day step, the whole run in one step per stage, the lowest
#: permeability the scenario accepts, a permeability it rejects, a load the stepper gives up on.
FAST = ("dt_1e-6_only", "dt_whole_run", "k_lowest", "k_x1e-12", "load_x1000_dtmin")


@pytest.fixture(scope="module")
def fast_rows(tmp_path_factory):
    out = tmp_path_factory.mktemp("bench_stability")
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PILEGROUP_MESH_CACHE", str(out / "cache"))
        # no figures: the subset checks the numbers the runs write (the full bench plots)
        rows = bs.bench_stability(out, FAST, timeout=300, extra_sets=("outputs.plots=false",))
    return out, {r["case"]: r for r in rows}


def test_fast_cases_finish_or_stop_cleanly(fast_rows):
    out, rows = fast_rows
    assert list(rows) == list(FAST)
    for name, r in rows.items():
        assert r["clean"], r
        assert r["nan"] == "no" and bs.nonfinite_files(out / name) == [], r
    for name in ("dt_1e-6_only", "dt_whole_run", "k_lowest"):
        assert rows[name]["status"] == "complete" and rows[name]["exit"] == 0
        assert json.loads((out / name / "summary.json").read_text())["status"] == "complete"
    # one step per stage: geostatic, loading, consolidation
    assert rows["dt_1e-6_only"]["steps"] == rows["dt_whole_run"]["steps"] == 3
    assert rows["k_x1e-12"]["status"] == "invalid input" and rows["k_x1e-12"]["exit"] == 2
    assert "k_m_per_day" in rows["k_x1e-12"]["message"]


def test_a_load_far_above_capacity_stops_with_one_line(fast_rows):
    out, rows = fast_rows
    r = rows["load_x1000_dtmin"]
    assert (r["status"], r["exit"]) == ("stopped", 1)
    assert r["full_message"].startswith("pilegroup: failed: no equilibrium beyond load factor")
    s = json.loads((out / "load_x1000_dtmin" / "summary.json").read_text())
    assert s["status"] == "failed" and s["reason"].startswith("StepFailure: no equilibrium")
    # the run summary up to the failure: the steps done and the cut-backs that failed
    solver = json.loads((out / "load_x1000_dtmin" / "summary_solver.json").read_text())
    assert solver["complete"] is False and solver["failure"] in r["full_message"]
    assert r["steps"] == solver["steps"] >= 1 and r["rejected"] == solver["rejected_steps"] >= 1


def test_capacity_and_memory_entries(tmp_path, monkeypatch):
    """A failed foundation in a capacity stage is complete with its capacity; a mesh too large
    for the machine is refused before meshing with one line."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    rows = {r["case"]: r for r in bs.bench_stability(
        tmp_path, ["capacity", "memory_too_large"], timeout=300,
        extra_sets=("outputs.plots=false",))}
    cap = rows["capacity"]
    assert (cap["status"], cap["exit"], cap["clean"]) == ("complete", 0, True), cap
    assert cap["message"].startswith("capacity ") and cap["settlement_mm"] > 800.0
    est, peak = (float(x) for x in cap["memory_mb"].split(" / "))
    assert 0.5 <= est / peak <= 2.0
    mem = rows["memory_too_large"]
    assert (mem["status"], mem["exit"], mem["clean"]) == ("invalid input", 2, True), mem
    assert "MB per rank estimated" in mem["full_message"]
    assert not (tmp_path / "memory_too_large" / "mesh").exists()


def test_tables_are_written(fast_rows):
    out, rows = fast_rows
    data = json.loads((out / "bench_stability.json").read_text())
    assert [d["case"] for d in data] == list(FAST)
    md = (out / "bench_stability.md").read_text()
    assert md.count("\n| ") == len(FAST) + 1  # header and one row per case
    assert all(f"| {name} |" in md for name in FAST)


def test_unknown_case_is_invalid_input(tmp_path):
    with pytest.raises(ScenarioError, match="nonsense"):
        bs.bench_stability(tmp_path, ["nonsense"])


def test_cases_scale_the_scenario_values():
    sc = small_pile_scenario()
    cases = {c.name: c for c in bs.stress_cases(sc)}

    def values(name):
        return dict(parse_override(kv) for kv in cases[name].sets)

    assert values("k_x1000") == {f"layers[{j}].k_m_per_day": pytest.approx(1e3 * lay.k_m_per_day)
                                 for j, lay in enumerate(sc.layers)}
    assert values("E_x0.01") == {f"layers[{j}].E_MPa": pytest.approx(0.01 * lay.E_MPa)
                                 for j, lay in enumerate(sc.layers)}
    assert values("load_x10") == {"stages[1].cap_load_kN": 10 * sc.total_cap_load()}
    groups = {c.group for c in cases.values()}
    assert groups == {"time step", "permeability", "stiffness", "load", "interface", "element",
                      "soft soil", "capacity", "memory"}
    ssc = values("ssc_unloading")
    lam = 100.0 / (sc.layers[0].E_MPa * 1000.0 * math.log(2.0))
    assert ssc["layers[0].lambda_star"] == pytest.approx(lam, rel=1e-5)
    assert ssc["layers[0].mu_star"] == pytest.approx(lam / 25.0, rel=1e-5)
    assert ssc["stages[2].cap_load_kN"] == 0.0
    for name in ("ssc_load_x10", "mcc_unloading"):  # each a valid scenario
        scenario_from_dict(apply_overrides(tomllib.loads(small_pile_text()), values(name)))


def test_nonfinite_files_reads_numbers_not_words(tmp_path):
    (tmp_path / "ok.csv").write_text("t_day,stage,value\n0,nan_stage,1.5\n")
    (tmp_path / "ok.json").write_text(json.dumps({"reason": "NaN/inf stress from the law"}))
    assert bs.nonfinite_files(tmp_path) == []
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "bad.csv").write_text("t_day,value\n0,nan\n")
    (tmp_path / "bad.json").write_text(json.dumps({"x": [1.0, math.inf]}))
    with h5py.File(tmp_path / "bad.h5", "w") as f:
        f["Function/p/0"] = np.array([1.0, np.nan])
    with h5py.File(tmp_path / "ok.h5", "w") as f:
        f["Function/p/0"] = np.array([1.0, 2.0])
    assert bs.nonfinite_files(tmp_path) == ["bad.h5", "bad.json", "sub/bad.csv"]


def test_classify_outcomes():
    failed = {"status": "failed"}
    line = "pilegroup: failed: no equilibrium beyond load factor 0.5 (250 kN)"
    assert bs.classify(Finished(1, "", line + "\n", 1.0), failed) == ("stopped", line)
    two = Finished(1, "", line + "\n" + line + "\n", 1.0)
    assert bs.classify(two, failed)[0] == "crashed"  # one line per rank is not one line
    tb = Finished(1, "", "Traceback (most recent call last):\n  ...\nValueError: x\n", 1.0)
    assert bs.classify(tb, failed)[0] == "traceback"
    abort = Finished(1, "", "pilegroup: run failed: ValueError: x\n", 1.0)
    assert bs.classify(abort, failed)[0] == "crashed"  # an unexpected exception
    assert bs.classify(Finished(None, "", "", 5.0), None)[0] == "timeout"
    assert bs.classify(Finished(0, "{}", "", 1.0), None)[0] == "crashed"  # no summary


def test_run_isolated_kills_the_whole_group_at_the_timeout():
    # a child that starts a grandchild and hangs: both end at the timeout
    code = ("import subprocess, sys, time\n"
            "p = subprocess.Popen(['sleep', '120'])\n"
            "print(p.pid, flush=True)\n"
            "time.sleep(120)\n")
    t0 = time.perf_counter()
    fin = run_isolated([sys.executable, "-c", code], timeout=2)
    assert fin.timed_out and time.perf_counter() - t0 < 30
    grandchild = int(fin.stdout.split()[0])
    for _ in range(50):
        try:
            os.kill(grandchild, 0)
        except ProcessLookupError:
            break
        time.sleep(0.1)
    else:
        status = subprocess.run(["ps", "-o", "stat=", "-p", str(grandchild)],
                                capture_output=True, text=True).stdout.strip()
        assert status.startswith("Z"), f"process {grandchild} still runs ({status})"
