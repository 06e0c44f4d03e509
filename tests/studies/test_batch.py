"""``pilegroup batch``: cases side by side on MPI groups, resume, failures, bad plans.

Every run is a subprocess under a timeout (a dead rank ends the test instead of hanging it);
the cases are the coarse ``small_pile`` without XDMF and plots.
"""

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pilegroup.studies.cli import commands as cli

BIN = Path(sys.executable).parent
FAST = '{"outputs.xdmf" = false, "outputs.plots" = false}'
#: Overrides that pass validation but cannot converge: Newton may take 2 iterations to reach a
#: relative residual of 1e-14, and a step may not be cut.
DIVERGES = ('{"numerics.newton_atol" = 1e-14, "numerics.newton_rtol" = 1e-14, '
            '"numerics.time.max_newton" = 2, "numerics.time.easy_newton" = 1, '
            '"numerics.time.dt_min_day" = 0.25}')
#: A slower case: 20 steps of 0.1 day.
SLOW = ('{"numerics.time.dt_initial_day" = 0.1, "numerics.time.dt_max_day" = 0.1, '
        '"numerics.time.dt_min_day" = 0.1}')


def _plan(small_pile, cases):
    f = Path(small_pile).with_name("plan.toml")
    f.write_text(f'[batch]\nscenario = "{Path(small_pile).name}"\nset = {FAST}\n{cases}')
    return f


def _command(plan, out, ranks=1, per_case=1, python=None):
    cmd = [str(BIN / "pilegroup"), "batch", str(plan), "--out", str(out), "--ranks-per-case",
           str(per_case), "--no-progress"]
    if python is not None:
        cmd = [sys.executable, "-c", python, *cmd[1:]]
    if ranks > 1:
        cmd = [str(BIN / "mpirun"), "-n", str(ranks), *cmd]
    return cmd


def _env(tmp_path):
    return {**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}


def _cases(out):
    return {c["name"]: c for c in json.loads((out / "batch.json").read_text())["cases"]}


def _summary(run):
    path = run / "summary.json"
    return json.loads(path.read_text()) if path.is_file() else {}


@pytest.mark.mpi
def test_two_cases_run_at_once_on_two_ranks(tmp_path, small_pile):
    plan = _plan(small_pile, '[sweep]\n"interface.mode" = ["viscoplastic", "elastic"]\n')
    out = tmp_path / "batch"
    r = subprocess.run([*_command(plan, out, ranks=2), "--memory", "6GB"], capture_output=True,
                       text=True, timeout=300, env=_env(tmp_path))
    assert r.returncode == 0, r.stderr[-3000:]
    cases = _cases(out)
    assert set(cases) == {"mode=viscoplastic", "mode=elastic"}
    for c in cases.values():  # side by side on one node: each case plans on half of 6 GB
        memory = _summary(Path(c["run_dir"]))["memory"]
        assert memory["limit_mb"] == pytest.approx(3072.0)
        assert memory["budget_mb_per_rank"] <= 3072.0
    a, b = cases.values()
    assert a["status"] == b["status"] == "complete" and a["ranks"] == b["ranks"] == 1
    assert max(a["start"], b["start"]) < min(a["end"], b["end"]), (a, b)  # side by side
    for c in (a, b):
        assert _summary(Path(c["run_dir"]))["status"] == "complete"
        assert c["unknowns"] > 0 and c["newton"] > 0 and len(c["peak_rss_mb_per_rank"]) == 1
        assert 0.0 < c["rss_at_start_mb"] <= c["peak_rss_mb_max"]
        assert c["output_days"] == [0.0, 0.5, 2.0] and c["settlement_m"][-1] > 0.0
        assert set(c["head_force_kN"]) == {"1"} and c["layer_friction_kPa"]
    rows = (out / "batch.csv").read_text().splitlines()
    assert len(rows) == 3 and "settlement_m@2d" in rows[0]


def test_killed_batch_resumes_and_skips_the_finished_case(tmp_path, small_pile):
    plan = _plan(small_pile, f'[[case]]\nname = "first"\n[[case]]\nname = "second"\n'
                 f'set = {SLOW}\n')
    out = tmp_path / "batch"
    proc = subprocess.Popen(_command(plan, out), stdout=subprocess.DEVNULL,
                            stderr=subprocess.DEVNULL, env=_env(tmp_path))
    try:
        deadline = time.monotonic() + 240  # timeout of the killed run
        while time.monotonic() < deadline and proc.poll() is None:
            if _summary(out / "first").get("status") == "complete":
                break
            time.sleep(0.02)
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert _summary(out / "first")["status"] == "complete"
    assert _summary(out / "second").get("status") != "complete", "killed too late"
    assert set(_cases(out)) == {"first", "second"}  # the killed batch left a whole batch.json
    first = json.loads((out / "first" / "batch_case.json").read_text())
    r = subprocess.run(_command(plan, out), capture_output=True, text=True, timeout=300,
                       env=_env(tmp_path))
    assert r.returncode == 0, r.stderr[-3000:]
    cases = _cases(out)
    assert cases["first"]["skipped"] and cases["first"]["start"] == first["start"]
    assert not cases["second"]["skipped"] and cases["second"]["status"] == "complete"
    assert cases["second"]["start"] > first["start"]
    assert "first: complete (complete before, skipped)" in r.stdout


def _record(run):
    path = run / "batch_case.json"
    try:
        return json.loads(path.read_text())
    except (OSError, ValueError):
        return {}


@pytest.mark.parametrize(("ranks", "sig"), [
    (1, signal.SIGTERM), pytest.param(2, signal.SIGUSR1, marks=pytest.mark.mpi),
    pytest.param(2, signal.SIGTERM, marks=pytest.mark.mpi)])
def test_a_stop_signal_records_the_running_case_interrupted(tmp_path, small_pile, ranks, sig,
                                                            needs_mpirun_forwarding_sigterm):
    """SIGTERM or SIGUSR1 (to mpirun: forwarded to every rank) stops the running cases at a
    step boundary; their records say interrupted, no other case starts, exit 128 + sig."""
    if ranks > 1 and sig == signal.SIGTERM:
        needs_mpirun_forwarding_sigterm()
    plan = _plan(small_pile, f'[[case]]\nname = "slow"\nset = {SLOW}\n'
                 f'[[case]]\nname = "next"\nset = {SLOW}\n')
    out = tmp_path / "batch"
    proc = subprocess.Popen(_command(plan, out, ranks=ranks, per_case=ranks),
                            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                            env=_env(tmp_path))
    try:
        deadline = time.monotonic() + 240
        while not any(_record(out / c).get("status") == "running" for c in ("slow", "next")):
            assert proc.poll() is None and time.monotonic() < deadline
            time.sleep(0.02)
        proc.send_signal(sig)
        _, stderr = proc.communicate(timeout=240)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 128 + sig, stderr[-3000:]
    assert [ln for ln in stderr.splitlines() if ln.startswith("pilegroup:")] == [
        f"pilegroup: batch interrupted by {sig.name}; run the plan again to run the cases not "
        "complete"]
    records = {c: _record(out / c) for c in ("slow", "next")}
    started = [c for c, r in records.items() if r]
    assert len(started) == 1, records  # the other case was not taken after the signal
    rec = records[started[0]]
    assert rec["status"] == "interrupted" and rec["message"].startswith(
        f"interrupted by {sig.name} at t = ")
    assert _summary(out / started[0])["status"] == "interrupted"
    assert _cases(out)[started[0]]["status"] == "interrupted"


def test_a_failed_case_leaves_the_other_and_exits_1(tmp_path, small_pile, monkeypatch, capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    plan = _plan(small_pile, f'[[case]]\nname = "ok"\n[[case]]\nname = "diverges"\n'
                 f'set = {DIVERGES}\n')
    out = tmp_path / "batch"
    assert cli.main(["batch", str(plan), "--out", str(out), "--no-progress"]) == 1
    cases = _cases(out)
    assert cases["ok"]["status"] == "complete" and cases["ok"]["settlement_m"][-1] > 0.0
    assert _summary(out / "ok")["status"] == "complete"
    bad = cases["diverges"]
    assert bad["status"] == "failed" and bad["message"].startswith("StepFailure: ")
    assert _summary(out / "diverges")["status"] == "failed"
    assert "diverges: failed" in capsys.readouterr().out
    assert "ok,complete" in (out / "batch.csv").read_text()


@pytest.mark.parametrize("cases, argv, line", [
    ('[[case]]\nname = "fine"\n[[case]]\nname = "wrong"\nset = {"numerics.mesh.size_m" = -1.0}\n',
     [], "pilegroup: invalid input: case 'wrong': numerics.mesh.size_m = -1.0 (m): must be "),
    ('[[case]]\nname = "fine"\n[cases]\nname = "b"\n', [],
     "pilegroup: invalid input: plan.toml: plan.cases = {'name': 'b'}: unknown key; allowed "
     "keys: batch, sweep, case"),
    ('[[case]]\nname = "fine"\n', ["--ranks-per-case", "2"],
     "pilegroup: invalid input: --ranks-per-case = 2: must divide the number of MPI ranks (1)"),
])
def test_bad_plan_exits_2_with_one_line_before_running(tmp_path, small_pile, capsys, cases,
                                                        argv, line):
    out = tmp_path / "batch"
    plan = _plan(small_pile, cases)
    assert cli.main(["batch", str(plan), "--out", str(out), *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith(line), err
    assert not out.exists()


#: A batch whose runs fail on rank 1 only ("alone": rank 0 waits in a collective call) or on
#: both ranks of the group ("all").
SCRIPT = r"""
import sys
from mpi4py import MPI
from pilegroup.studies.batch import execute as batch
from pilegroup.studies.cli import commands as cli

def fail(sc, out, comm=None, **kwargs):
    if MPI.COMM_WORLD.rank == 1:
        raise IndexError("index 7 is out of bounds (only on this rank)")
    if MODE == "all":
        raise KeyError("rank 0 too")
    comm.Barrier()

MODE = sys.argv.pop(1)
batch.AGREE_TIMEOUT_S = 2.0
batch.run_scenario = fail
sys.exit(cli.main(sys.argv[1:]))
"""


@pytest.mark.mpi
@pytest.mark.parametrize("mode", ["alone", "all"])
def test_failure_in_a_two_rank_group(tmp_path, small_pile, mode):
    plan = _plan(small_pile, '[[case]]\nname = "a"\n[[case]]\nname = "b"\n')
    out = tmp_path / "batch"
    cmd = _command(plan, out, ranks=2, per_case=2, python=SCRIPT)
    cmd.insert(cmd.index("-c") + 2, mode)
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120, env=_env(tmp_path))
    assert r.returncode == 1, r.stderr[-3000:]
    if mode == "all":  # every rank raised: recorded, and the batch went on to the other case
        cases = _cases(out)
        assert [c["status"] for c in cases.values()] == ["failed", "failed"]
        assert cases["a"]["message"] == "KeyError: 'rank 0 too'"  # the group's first rank's
        return
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert len(lines) == 1 and lines[0].startswith(
        "pilegroup: rank 1 of 2 failed alone in case 'a': IndexError: index 7"), r.stderr
    record = json.loads((out / "a" / "batch_case.json").read_text())
    assert record["status"] == "failed" and record["rank"] == 1
