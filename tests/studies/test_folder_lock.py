"""One run per output folder: a second run stops at once, a killed run's lock is taken over.

The holders are real processes (subprocesses under a timeout): the lock is the kernel's
``flock``, which only another process can find held.
"""

import json
import logging
import os
import platform
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from pilegroup.studies.run.folder_lock import LOCK_FILE, folder_lock

BIN = Path(sys.executable).parent
TIMEOUT = 300  # s, for every subprocess
#: A process that holds the lock of the folder argv[1] until it is ended.
HOLDER = r"""
import sys, time
from pilegroup.studies.run.folder_lock import folder_lock
with folder_lock(sys.argv[1]):
    print("locked", flush=True)
    time.sleep(600)
"""


def _env(tmp_path):
    return {**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}


def _pilegroup_lines(stderr):
    assert "Traceback" not in stderr, stderr[-3000:]
    return [ln for ln in stderr.splitlines() if ln.startswith("pilegroup:")]


def _hold(folder):
    """A process that holds ``folder``'s lock (ready when this returns)."""
    proc = subprocess.Popen([sys.executable, "-c", HOLDER, str(folder)], stdout=subprocess.PIPE,
                            text=True)
    assert proc.stdout.readline() == "locked\n"
    return proc


def _who(folder):
    return json.loads((folder / LOCK_FILE).read_text())


def _busy_line(folder, who):
    return (f"pilegroup: invalid input: --out = '{folder}': is in use by another run (PID "
            f"{who['pid']} on host {who['host']}, started {who['started']}); wait for it to "
            "end or choose another --out")


@pytest.fixture
def held(tmp_path):
    folder = tmp_path / "run"
    proc = _hold(folder)
    yield folder, proc
    proc.kill()
    proc.wait(timeout=TIMEOUT)


def test_second_run_into_a_held_folder_exits_2_at_once(held, small_pile, tmp_path):
    folder, proc = held
    who = _who(folder)
    assert who["pid"] == proc.pid and who["host"] == platform.node()
    r = subprocess.run([str(BIN / "pilegroup"), "run", small_pile, "--out", str(folder)],
                       capture_output=True, text=True, timeout=TIMEOUT, env=_env(tmp_path))
    assert r.returncode == 2, r.stderr[-3000:]
    assert _pilegroup_lines(r.stderr) == [_busy_line(folder, who)]
    assert sorted(p.name for p in folder.iterdir()) == [LOCK_FILE]  # nothing written
    assert _who(folder) == who


@pytest.mark.mpi
def test_second_run_on_two_ranks_exits_2_with_one_line(held, small_pile, tmp_path):
    folder, _ = held
    r = subprocess.run([str(BIN / "mpirun"), "-n", "2", str(BIN / "pilegroup"), "run",
                        small_pile, "--out", str(folder)], capture_output=True, text=True,
                       timeout=TIMEOUT, env=_env(tmp_path))
    assert r.returncode == 2, r.stderr[-3000:]
    assert _pilegroup_lines(r.stderr) == [_busy_line(folder, _who(folder))]


def test_two_runs_into_one_folder(small_pile, tmp_path):
    """A real run holds its folder while it runs and leaves no lock file when it ends."""
    folder = tmp_path / "run"
    cmd = [str(BIN / "pilegroup"), "run", small_pile, "--out", str(folder), "--set",
           "outputs.plots=false"]
    first = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             env=_env(tmp_path))
    try:
        deadline = time.monotonic() + TIMEOUT
        while not (folder / "scenario.json").is_file():
            assert first.poll() is None, first.stderr.read()[-3000:]
            assert time.monotonic() < deadline
            time.sleep(0.02)
        who = _who(folder)
        assert who["pid"] == first.pid and "pilegroup run" in who["command"]
        # paused while the second one tries (a small run may otherwise end first on a busy
        # machine): it still holds its folder
        first.send_signal(signal.SIGSTOP)
        try:
            second = subprocess.run(cmd, capture_output=True, text=True, timeout=TIMEOUT,
                                    env=_env(tmp_path))
        finally:
            first.send_signal(signal.SIGCONT)
        assert second.returncode == 2
        assert _pilegroup_lines(second.stderr) == [_busy_line(folder, who)]
        assert first.wait(timeout=TIMEOUT) == 0
    finally:
        if first.poll() is None:
            first.kill()
    assert json.loads((folder / "summary.json").read_text())["status"] == "complete"
    assert not (folder / LOCK_FILE).exists()


def test_lock_of_a_killed_run_is_taken_over_with_one_warning(tmp_path, caplog):
    folder = tmp_path / "run"
    proc = _hold(folder)
    who = _who(folder)
    proc.send_signal(signal.SIGKILL)
    proc.wait(timeout=TIMEOUT)
    assert (folder / LOCK_FILE).is_file()  # left behind, its flock released by the kernel
    with caplog.at_level(logging.WARNING), folder_lock(folder):
        assert _who(folder)["pid"] == os.getpid()
    assert [r.getMessage() for r in caplog.records] == [
        f"taking over the lock of {folder} left by PID {who['pid']} on host {who['host']}, "
        f"started {who['started']}, which has ended"]
    assert not (folder / LOCK_FILE).exists()


def test_stale_lock_file_without_a_name_is_taken_over(tmp_path, caplog):
    folder = tmp_path / "run"
    folder.mkdir()
    (folder / LOCK_FILE).write_text("{not json")
    with caplog.at_level(logging.WARNING), folder_lock(folder), folder_lock(folder):
        pass  # the second is a re-entry of the same process: no-op
    assert len(caplog.records) == 1 and "has not yet written its name" in caplog.text


def test_batch_case_into_a_held_folder_is_not_run(small_pile, tmp_path, monkeypatch, capsys):
    from pilegroup.studies.cli import commands as cli

    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    plan = Path(small_pile).with_name("plan.toml")
    plan.write_text(f'[batch]\nscenario = "{Path(small_pile).name}"\n'
                    'set = {"outputs.xdmf" = false, "outputs.plots" = false}\n'
                    '[[case]]\nname = "held"\n')
    out = tmp_path / "batch"
    proc = _hold(out / "held")
    try:
        (out / "held" / "theirs.txt").write_text("the other run's file")
        assert cli.main(["batch", str(plan), "--out", str(out), "--no-progress"]) == 1
        assert (out / "held" / "theirs.txt").read_text() == "the other run's file"
        assert not (out / "held" / "batch_case.json").exists()
    finally:
        proc.kill()
        proc.wait(timeout=TIMEOUT)
