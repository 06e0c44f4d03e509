"""A failure on one rank ends every rank with one line and a failed summary (no hang)."""

import json
import subprocess
import sys
import time
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent

#: A run whose solve raises on rank 1 only while rank 0 waits in a collective call: without
#: the abort, rank 0 would wait for ever.
SCRIPT = r"""
import sys
import time
from mpi4py import MPI
from pilegroup.studies.cli import commands as cli
from pilegroup.studies.run import job as run

def solve_on_one_rank(*args, **kwargs):
    if MPI.COMM_WORLD.rank == 1:
        raise IndexError("index 7 is out of bounds (only on this rank)")
    MPI.COMM_WORLD.barrier()

run.run_coupled = solve_on_one_rank
sys.exit(cli.main(["run", sys.argv[1], "--out", sys.argv[2]]))
"""


@pytest.mark.mpi
def test_one_rank_failure_ends_every_rank(tmp_path, small_pile, monkeypatch):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    r = subprocess.run([str(BIN / "mpirun"), "-n", "2", sys.executable, "-c", SCRIPT,
                        small_pile, str(out)], capture_output=True, text=True, timeout=300)
    assert r.returncode != 0
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert lines == ["pilegroup: rank 1 of 2 failed: IndexError: index 7 is out of bounds "
                     "(only on this rank)"], r.stderr[-2000:]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["rank"] == 1 and "IndexError" in s["reason"]
    assert (out / "scenario.json").is_file() and (out / "mesh" / "mesh.xdmf").is_file()


def test_collective_failure_writes_failed_summary(tmp_path, small_pile, monkeypatch):
    from pilegroup.errors import StepFailure
    from pilegroup.studies.cli import commands as cli
    from pilegroup.studies.run import job as run

    def fail(*args, **kwargs):
        raise StepFailure("stage 'load': step at t = 0.5 day failed")

    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(run, "run_coupled", fail)
    assert cli.main(["run", small_pile, "--out", str(tmp_path / "run")]) == 1
    s = json.loads((tmp_path / "run" / "summary.json").read_text())
    assert s["status"] == "failed" and s["rank"] is None
    assert s["reason"] == "StepFailure: stage 'load': step at t = 0.5 day failed"


def test_a_run_that_fails_before_its_first_output_warns_of_nothing(tmp_path, small_pile,
                                                                    monkeypatch, caplog):
    """A failure before any output time (here in the geostatic stage) is the one piece of news:
    no warning that the folder is "not a run output folder" for the figures it cannot draw."""
    from pilegroup.errors import StepFailure
    from pilegroup.studies.cli import commands as cli
    from pilegroup.studies.run import job as run

    def fail(*args, **kwargs):
        raise StepFailure("geostatic stage 'geostatic': max |u| = 2.0e-04 m > 0.0001 m")

    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(run, "run_coupled", fail)
    with caplog.at_level("INFO"):
        assert cli.main(["run", small_pile, "--out", str(tmp_path / "run")]) == 1
    assert not [r for r in caplog.records if r.levelname == "WARNING"], caplog.text
    assert "no plots: the run stopped before its first output" in caplog.text


def _pilegroup_lines(stderr):
    return [ln for ln in stderr.splitlines() if ln.startswith("pilegroup:")]


def _mpirun(args, timeout=120, **kw):
    """``mpirun -n 2 ARGS`` under a timeout; returns the completed process and its wall."""
    t0 = time.perf_counter()
    r = subprocess.run([str(BIN / "mpirun"), "-n", "2", *args], capture_output=True, text=True,
                       timeout=timeout, **kw)
    return r, time.perf_counter() - t0


@pytest.mark.mpi
def test_verify_collective_failure_prints_one_line(tmp_path):
    # the Gauss-point interface needs Q1 displacements: every rank rejects Q2Q1 alike
    r, _ = _mpirun([str(BIN / "pilegroup"), "verify", "shaft-capacity", "--pair", "Q2Q1",
                    "--interface-quadrature", "gauss"], cwd=tmp_path)
    assert r.returncode == 1, r.stderr[-2000:]
    lines = _pilegroup_lines(r.stderr)
    assert len(lines) == 1 and lines[0].startswith("pilegroup: failed: InterfaceCoupling"), \
        r.stderr[-2000:]
    assert "Traceback" not in r.stderr


#: ``pilegroup verify`` whose case raises on rank 1 only while rank 0 waits in a collective call.
VERIFY_SCRIPT = r"""
import sys
import time
from mpi4py import MPI
from pilegroup.studies.cli import commands as cli
from pilegroup.studies.verification import runner

def case_failing_on_one_rank(name, size="fast", **overrides):
    if MPI.COMM_WORLD.rank == 1:
        raise KeyError("state 'gap' missing (only on this rank)")
    MPI.COMM_WORLD.barrier()

runner.run_case = case_failing_on_one_rank
sys.exit(cli.main(["verify", "terzaghi"]))
"""


@pytest.mark.mpi
def test_verify_one_rank_failure_ends_every_rank(tmp_path):
    r, wall = _mpirun([sys.executable, "-c", VERIFY_SCRIPT], cwd=tmp_path)
    assert r.returncode == 1, r.stderr[-2000:]
    assert _pilegroup_lines(r.stderr) == [
        "pilegroup: rank 1 of 2 failed: KeyError: \"state 'gap' missing (only on this rank)\""]
    assert wall < 60  # rank 0, waiting in the barrier, was ended


@pytest.mark.mpi
def test_bench_failure_on_rank_0_ends_the_job(tmp_path):
    # rank 0 drives the cases and cannot create its output folder under a file
    (tmp_path / "file").write_text("")
    r, wall = _mpirun([str(BIN / "pilegroup"), "bench", "stability", "--out",
                       str(tmp_path / "file" / "out"), "--cases", "dt_whole_run"])
    assert r.returncode == 1, r.stderr[-2000:]
    lines = _pilegroup_lines(r.stderr)
    assert len(lines) == 1 and lines[0].startswith(
        "pilegroup: rank 0 of 2 failed: NotADirectoryError"), r.stderr[-2000:]
    assert wall < 60


def test_load_beyond_capacity_ends_the_run_failed(tmp_path, small_pile, monkeypatch):
    """200 MN on the small pile: the run ends with exit 1, a failed summary and one line
    naming the stage, time, load factor and settlement, not ``complete`` metres down."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    r = subprocess.run([str(BIN / "pilegroup"), "run", small_pile, "--out", str(out),
                        "--set", "stages[1].cap_load_kN=200000", "--set", "outputs.plots=false"],
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 1, r.stderr[-3000:]
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert len(lines) == 1 and "exceeds the pile diameter 0.8 m" in lines[0], lines
    assert "stage 'loading'" in lines[0] and "load factor" in lines[0] and " day" in lines[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed"
