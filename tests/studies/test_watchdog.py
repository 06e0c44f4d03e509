"""studies/run/watchdog.py: a run whose process dies without Python still says ``failed``.

Each case runs a small process (no MPI, no DOLFINx) that takes a folder's lock as a run does,
enters :func:`watched` and then ends as the case says; the folder is checked after it. The
two-rank cases through ``mpirun`` are in tests/geometry/test_layouts_property.py.
"""

import faulthandler
import json
import subprocess
import sys
import time
import types
from pathlib import Path

import pytest

from pilegroup.studies.run import watchdog
from pilegroup.studies.run.watchdog import LOCK_FILE, fatal_file, watched

CHILD = """
import fcntl, json, os, signal, sys, time, types
from pathlib import Path
from pilegroup.studies.run.watchdog import watched
out, how = Path(sys.argv[1]), sys.argv[2]
out.mkdir(parents=True, exist_ok=True)
fd = os.open(out / ".pilegroup.lock", os.O_RDWR | os.O_CREAT, 0o644)
fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
with watched(out, types.SimpleNamespace(rank=0, size=1), "case", time.perf_counter(), fd):
    if how == "abort":
        os.abort()
    if how == "kill":
        os.kill(os.getpid(), signal.SIGKILL)
    if how == "own record":
        (out / "summary.json").write_text(json.dumps({"status": "failed", "reason": "own"}))
        os._exit(1)
"""


def _run(tmp_path: Path, how: str) -> tuple[subprocess.CompletedProcess, Path]:
    out = tmp_path / "run"
    r = subprocess.run([sys.executable, "-c", CHILD, str(out), how], capture_output=True,
                       text=True, timeout=60)
    deadline = time.monotonic() + 10.0  # the watchdog writes, then removes the lock file
    while (out / LOCK_FILE).exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    return r, out


def _summary(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def test_a_normal_block_leaves_nothing(tmp_path):
    r, out = _run(tmp_path, "normal")
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in out.iterdir()) == [LOCK_FILE]  # the run's lock: not freed


@pytest.mark.parametrize("how, reason", [
    ("abort", "the run died: Fatal Python error: Aborted, in <module> (<string>, line 11)"),
    ("kill", "the run ended without a Python error: killed by a signal"),
])
def test_a_process_killed_by_a_signal_leaves_a_failed_summary(tmp_path, how, reason):
    r, out = _run(tmp_path, how)
    assert r.returncode < 0
    s = _summary(out)
    assert s["status"] == "failed" and s["reason"].startswith(reason), s["reason"]
    assert s["scenario"] == "case" and s["ranks"] == 1 and s["wall_s"] >= 0.0
    assert s["rank"] == (0 if how == "abort" else None)
    assert f"pilegroup: run failed: {s['reason']}" in r.stderr.splitlines()
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]  # lock and fatal file gone


def test_the_runs_own_failure_record_is_kept(tmp_path):
    r, out = _run(tmp_path, "own record")
    assert r.returncode == 1
    assert _summary(out) == {"status": "failed", "reason": "own"}
    assert "pilegroup: run failed" not in r.stderr
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]


def test_faulthandler_is_as_before_after_nested_blocks(tmp_path):
    was = faulthandler.is_enabled()
    one = types.SimpleNamespace(rank=0, size=1)
    with watched(tmp_path, one, "a", time.perf_counter(), None):
        (tmp_path / "in").mkdir()
        with watched(tmp_path / "in", one, "b", time.perf_counter(), None):
            assert fatal_file(tmp_path / "in", 0).exists()
        assert faulthandler.is_enabled() and fatal_file(tmp_path, 0).exists()
    assert faulthandler.is_enabled() == was and watchdog._fatal_files == []
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["in"]
