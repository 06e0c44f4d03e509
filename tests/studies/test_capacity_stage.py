"""The capacity stage: criteria on a curve, the limit load bracketed by the stepper's cut-backs,
keys checked, and a run whose foundation fails ending complete with its capacity."""

import csv
import json

import numpy as np
import pytest

from pilegroup.errors import ScenarioError
from pilegroup.solver import RunState, SolverStage, StepControl
from pilegroup.solver.step_protocol import StepInfo
from pilegroup.solver.stepping import _Run
from pilegroup.studies.results.capacity import (
    capacity_criteria,
    group_efficiency,
    settlement_load,
    tangent_stiffness,
)


# ---------------------------------------------------------------------------- criteria
def test_criteria_on_a_bilinear_curve():
    # stiffness 1e4 kN/m up to 500 kN, then 50 kN/m (0.5 % of the initial): plunging at 500 kN
    w = np.concatenate([np.linspace(0.0, 0.05, 11), 0.05 + np.linspace(0.01, 0.1, 10)])
    q = np.where(w <= 0.05, 1e4 * w, 500.0 + 50.0 * (w - 0.05))
    c = capacity_criteria(q, w, diameter_m=0.8, ratio=0.02)
    assert c["plunging"]["load_kN"] == pytest.approx(500.0)
    # 10 % of 0.8 m = 0.08 m, on the soft branch: 500 + 50 x 0.03
    assert c["settlement_10pct_d"]["load_kN"] == pytest.approx(501.5)
    assert c["ultimate_kN"] == pytest.approx(500.0) and c["governing"] == "plunging"
    assert c["initial_stiffness_kN_per_m"] == pytest.approx(1e4)
    # a threshold below the soft branch's ratio: no plunging, the settlement criterion governs
    c = capacity_criteria(q, w, diameter_m=0.8, ratio=0.001)
    assert c["plunging"]["load_kN"] is None and c["governing"] == "settlement_10pct_d"


def test_stepper_failure_is_the_plunging_load_with_a_bracket():
    w = np.array([0.0, 0.01, 0.02, 0.03])
    q = np.array([0.0, 100.0, 180.0, 240.0])
    end = {"reason": "no equilibrium", "failed_load_factor": 0.245}
    c = capacity_criteria(q, w, 1.0, 0.02, end, load_scale_kN=1000.0)
    assert c["plunging"]["load_kN"] == 240.0
    assert c["plunging"]["bracket_kN"] == [240.0, pytest.approx(245.0)]
    assert c["settlement_10pct_d"]["load_kN"] is None and c["ultimate_kN"] == 240.0


def test_curve_helpers():
    assert np.isnan(tangent_stiffness(np.array([0.0, 1.0]), np.array([0.0, 0.0]))).all()
    assert settlement_load(np.array([0.0, 10.0]), np.array([0.0, 0.01]), 0.02) is None
    assert settlement_load(np.array([0.0, 10.0]), np.array([0.0, 0.02]), 0.01) == 5.0
    assert group_efficiency(900.0, 9, 125.0) == pytest.approx(0.8)
    assert group_efficiency(900.0, 9, None) is None


# ---------------------------------------------------------------------------- solver stage
class LimitProblem:
    """A problem that has an equilibrium only up to load factor ``lam_limit``."""

    def __init__(self, lam_limit):
        self.lam_limit, self.lam, self.trial = lam_limit, 0.0, None
        self.load_factor = 0.0

    def solve_step(self, dt, lam):
        if lam > self.lam_limit:
            return StepInfo(converged=False, message="Newton diverged")
        self.trial = lam
        return StepInfo(converged=True, newton_its=2)

    def commit(self):
        self.lam = self.load_factor = self.trial

    def rollback(self):
        self.trial = None

    def fall_back_linear_solver(self, reason):
        return False


def test_capacity_stage_brackets_the_limit_by_cut_backs():
    pb = LimitProblem(0.6137)
    ts = StepControl(dt0=0.1, dt_max=0.1, dt_min=1e-4, cut=0.25)
    written = []
    stages = [SolverStage("cap", "capacity", duration=1.0, load_factor=1.0),
              SolverStage("after", "consolidation", duration=1.0)]
    state = RunState()
    _Run(pb, stages, ts, state, None).run(lambda p, t, s: written.append((t, s)), 1e-6, None)
    end = state.log.capacity_end
    assert end["reason"] == "no equilibrium"
    assert end["load_factor"] <= 0.6137 < end["failed_load_factor"]
    assert end["failed_load_factor"] - end["load_factor"] < 1e-4 / 0.25 + 1e-12
    assert pb.lam == pytest.approx(end["load_factor"])  # rolled back to the last equilibrium
    assert written[-1] == (pytest.approx(end["t_day"]), "cap")  # outputs at the end
    assert all(s == "cap" for _, s in written)  # nothing runs after a failed foundation
    assert state.done


def test_capacity_stage_carrying_its_largest_load_says_so():
    state = RunState()
    _Run(LimitProblem(2.0), [SolverStage("cap", "capacity", duration=1.0, load_factor=1.0)],
         StepControl(dt0=0.25), state, None).run(lambda p, t, s: None, 1e-6, None)
    assert state.log.capacity_end["reason"] == "max load"


# ---------------------------------------------------------------------------- scenario keys
CAPACITY = ('stages[2].kind="capacity"', "stages[2].max_load_kN=5000.0",
            "stages[2].duration_day=1.5")


def _load(small_pile, sets):
    from pilegroup.model import load_scenario
    from pilegroup.model.loader import parse_override

    return load_scenario(small_pile, dict(parse_override(kv) for kv in sets))


def test_capacity_keys(small_pile):
    sc = _load(small_pile, CAPACITY)
    assert sc.capacity_stage is not None and sc.total_cap_load() == 5000.0
    bad = {("stages[2].max_load_kN=300.0",): "must be > the cap load before it (500 kN)",
           ("stages[2].plunging_stiffness_ratio=1.5",): "plunging_stiffness_ratio",
           ("stages[2].single_pile_capacity_kN=-1.0",): "single_pile_capacity_kN",
           ("stages[2].cap_load_kN=10.0",): "not allowed for a capacity stage"}
    for extra, words in bad.items():
        with pytest.raises(ScenarioError) as exc:
            _load(small_pile, CAPACITY + extra)
        assert words in str(exc.value) and "\n" not in str(exc.value)
    with pytest.raises(ScenarioError, match="missing"):
        _load(small_pile, CAPACITY[:1] + CAPACITY[2:])


def test_capacity_stage_must_be_last(small_pile, run_cli, tmp_path):
    text = open(small_pile).read() + '\n[[stages]]\nname = "later"\nkind = "consolidation"\n'
    f = tmp_path / "later.toml"
    f.write_text(text.replace("end_day = 2.0", "end_day = 3.0"))
    r = run_cli(f, tmp_path / "out", sets=CAPACITY)
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert r.returncode == 2 and len(lines) == 1, r.stderr[-2000:]
    assert "stages[2].kind" in lines[0] and "must be the last stage" in lines[0]


# ---------------------------------------------------------------------------- a run
def test_capacity_run_fails_the_foundation_and_completes(small_pile, run_cli, tmp_path):
    """Q1-Q1 small pile: far past 10 % of D and past one diameter, the run is complete."""
    out = tmp_path / "cap"
    r = run_cli(small_pile, out, sets=(*CAPACITY, "outputs.xdmf=false",
                                       "stages[2].single_pile_capacity_kN=1000.0"))
    assert r.returncode == 0, r.stderr[-2000:]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "complete"
    cap = s["capacity"]
    assert cap["end"]["reason"] == "stopped" and "pile diameter" in cap["end"]["message"]
    with (out / "capacity.csv").open() as f:
        rows = [r for r in csv.DictReader(f)]
    group = [r for r in rows if r["pile"] == "0"]
    q = np.array([float(r["load_kN"]) for r in group])
    w = np.array([float(r["settlement_m"]) for r in group])
    assert len(group) >= 10 and w[-1] > 0.8 and np.all(np.diff(q) > 0)
    assert q[0] == pytest.approx(500.0)  # the curve starts at the load stage's end
    # the 10 % D load read again from the file, by hand
    i = int(np.argmax(w >= 0.08))
    q_w = q[i - 1] + (0.08 - w[i - 1]) / (w[i] - w[i - 1]) * (q[i] - q[i - 1])
    assert cap["group"]["settlement_10pct_d"]["load_kN"] == pytest.approx(q_w, rel=1e-6)
    assert cap["group"]["ultimate_kN"] <= q_w + 1e-6
    assert cap["group_efficiency"] == pytest.approx(cap["group"]["ultimate_kN"] / 1000.0)
    pile = cap["piles"][0]  # one pile carries the whole load (head force from its stress)
    assert pile["settlement_10pct_d"]["load_kN"] == pytest.approx(q_w, rel=0.02)
    assert (out / "plots" / "capacity.png").is_file()


def test_capacity_run_killed_inside_the_stage_resumes_to_the_same_capacity(small_pile, tmp_path):
    """A checkpoint at day 0.7 (inside the stage), SIGKILL, --resume: the straight run's curve."""
    import os
    import signal
    import subprocess
    import sys
    import time
    from pathlib import Path

    bin_ = Path(sys.executable).parent
    sets = (*CAPACITY, "outputs.xdmf=false", "outputs.plots=false",
            "time.output_days=[0.0, 0.5, 0.7, 2.0]")
    env = {**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}

    def cmd(out, resume=False):
        c = [str(bin_ / "pilegroup"), "run", small_pile, "--out", str(out)]
        return c + [a for kv in sets for a in ("--set", kv)] + (["--resume"] if resume else [])

    ref, run = tmp_path / "ref", tmp_path / "run"
    assert subprocess.run(cmd(ref), capture_output=True, env=env, timeout=300).returncode == 0
    proc = subprocess.Popen(cmd(run), stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL,
                            env=env)
    manifest = run / "checkpoint" / "manifest.json"
    deadline = time.monotonic() + 300
    try:
        while True:
            try:
                if json.loads(manifest.read_text())["t_day"] >= 0.7:
                    break
            except (OSError, ValueError, KeyError):
                pass
            assert proc.poll() is None, "the run ended before its checkpoint in the stage"
            assert time.monotonic() < deadline
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
    r = subprocess.run(cmd(run, resume=True), capture_output=True, text=True, env=env,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-2000:]
    assert (ref / "capacity.csv").read_text() == (run / "capacity.csv").read_text()
    a = json.loads((ref / "summary.json").read_text())["capacity"]
    b = json.loads((run / "summary.json").read_text())["capacity"]
    assert a["group"] == b["group"] and a["end"]["reason"] == b["end"]["reason"]
