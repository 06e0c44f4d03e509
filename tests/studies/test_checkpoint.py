"""Checkpoint and restart of ``pilegroup run``: kill, stop by signal, resume, compare.

Every run is a subprocess under a timeout (a hung rank fails the test instead of blocking CI).
The small scenario runs with steps of 0.05 day (about 40 steps), long enough to be stopped in
the middle; the resumed runs must reach the uninterrupted run's results to 1e-10 relative.
"""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import h5py
import numpy as np
import pytest

BIN = Path(sys.executable).parent
TIMEOUT = 300  # s, for every subprocess
SETS = ("outputs.plots=false", "numerics.time.dt_max_day=0.05",
        "numerics.time.dt_initial_day=0.05")
CSVS = ("settlement.csv", "pile_loads.csv", "pile_profiles.csv", "layer_history.csv",
        "interface_layers.csv", "load_settlement.csv")
RTOL = 1e-10


def _command(scenario, out, ranks=1, sets=SETS, resume=False):
    cmd = [str(BIN / "pilegroup"), "run", str(scenario), "--out", str(out)]
    cmd += [a for kv in sets for a in ("--set", kv)] + (["--resume"] if resume else [])
    return [str(BIN / "mpirun"), "-n", str(ranks), *cmd] if ranks > 1 else cmd


def _env(cache):
    return {**os.environ, "PILEGROUP_MESH_CACHE": str(cache)}


def _run(scenario, out, cache, **kw):
    return subprocess.run(_command(scenario, out, **kw), capture_output=True, text=True,
                          timeout=TIMEOUT, env=_env(cache))


def _manifest(out):
    try:
        return json.loads((Path(out) / "checkpoint" / "manifest.json").read_text())
    except (OSError, ValueError):
        return None


def _start_and_signal(scenario, out, cache, sig, ranks=1, after_day=0.0, sets=SETS):
    """Start a run, wait for a checkpoint at ``t >= after_day``, send ``sig``; the process."""
    err = Path(out).parent / f"stderr_{Path(out).name}.txt"
    with err.open("w") as f:
        proc = subprocess.Popen(_command(scenario, out, ranks, sets), stdout=subprocess.DEVNULL,
                                stderr=f, text=True, env=_env(cache))
    try:
        deadline = time.monotonic() + TIMEOUT
        while (m := _manifest(out)) is None or m["t_day"] < after_day:
            assert proc.poll() is None, f"run ended before the checkpoint: {err.read_text()}"
            assert time.monotonic() < deadline, "no checkpoint within the timeout"
            time.sleep(0.02)
        proc.send_signal(sig)
        proc.wait(timeout=TIMEOUT)
    finally:
        if proc.poll() is None:  # a hang: end it (the test fails on the timeout)
            proc.kill()
    return proc, err.read_text()


def _numbers(path):
    rows = list(csv.reader(path.open()))
    return rows[0], rows[1:]


def _max_rel_diff(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    den = np.maximum(np.abs(a), np.abs(b))
    return float(np.max(np.where(a == b, 0.0, np.abs(a - b) / np.where(den > 0, den, 1.0)),
                        initial=0.0))


def assert_same_results(ref, run):
    """Every CSV row for row (numbers to RTOL, text equal), and the full-precision series."""
    for name in CSVS:
        head_a, rows_a = _numbers(ref / name)
        head_b, rows_b = _numbers(run / name)
        assert head_a == head_b and len(rows_a) == len(rows_b), name
        for ra, rb in zip(rows_a, rows_b, strict=True):
            for x, y in zip(ra, rb, strict=True):
                try:
                    assert _max_rel_diff([float(x)], [float(y)]) <= RTOL, (name, ra, rb)
                except ValueError:
                    assert x == y, (name, ra, rb)
    sa = json.loads((ref / "summary_solver.json").read_text())
    sb = json.loads((run / "summary_solver.json").read_text())
    wa = [h["settlement_m"] for h in sa["settlement_m"]]
    wb = [h["settlement_m"] for h in sb["settlement_m"]]
    assert len(wa) == len(wb) and _max_rel_diff(wa, wb) <= RTOL
    assert [h["t"] for h in sa["history"]] == [h["t"] for h in sb["history"]]


def _pilegroup_lines(stderr):
    assert "Traceback" not in stderr, stderr[-3000:]
    return [ln for ln in stderr.splitlines() if ln.startswith("pilegroup:")]


@pytest.fixture(scope="module")
def reference(tmp_path_factory, scenario, cache):
    """The uninterrupted serial run."""
    out = tmp_path_factory.mktemp("reference") / "run"
    r = _run(scenario, out, cache)
    assert r.returncode == 0, r.stderr[-3000:]
    return out


def test_sigkill_then_resume_matches_uninterrupted_run(tmp_path, scenario, cache, reference):
    """Killed (no chance to save) after the checkpoint at 0.5 day, with wall-time checkpoints
    every 0.06 s as well (so the kill may land in a checkpoint write)."""
    out = tmp_path / "run"
    sets = (*SETS, "outputs.checkpoint_every_min=0.001")
    proc, _ = _start_and_signal(scenario, out, cache, signal.SIGKILL, after_day=0.5, sets=sets)
    assert proc.returncode == -signal.SIGKILL
    # killed mid-way: the run's watchdog says so (within moments of the kill)
    deadline = time.monotonic() + 10.0
    while (out / ".pilegroup.lock").exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["reason"].startswith("the run ended without a Python")
    t_saved = _manifest(out)["t_day"]
    assert 0.5 <= t_saved < 2.0
    r = _run(scenario, out, cache, sets=sets, resume=True)
    assert r.returncode == 0, r.stderr[-3000:]
    assert json.loads((out / "summary.json").read_text())["status"] == "complete"
    solver = json.loads((out / "summary_solver.json").read_text())
    assert solver["resumed_from_day"] == t_saved
    assert any(c["reason"] == "wall time" for c in solver["checkpoints"])
    assert_same_results(reference, out)


def _xdmf_series(path):
    """Times and datasets of every HDF5 file next to the XDMF files of a run."""
    out = {}
    for h5 in sorted(path.glob("results*.h5")):
        with h5py.File(h5, "r") as f:
            f.visititems(lambda n, d, h5=h5: out.__setitem__(f"{h5.name}/{n}", d[()])
                         if isinstance(d, h5py.Dataset) else None)
    return out


def test_sigterm_serial_stops_with_checkpoint_and_resumes(tmp_path, scenario, cache, reference):
    out = tmp_path / "run"
    proc, stderr = _start_and_signal(scenario, out, cache, signal.SIGTERM)
    assert proc.returncode == 143, stderr[-3000:]
    lines = _pilegroup_lines(stderr)
    assert len(lines) == 1 and lines[0].startswith("pilegroup: interrupted by SIGTERM at t = ")
    assert "--resume" in lines[0] and str(out / "checkpoint") in lines[0]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "interrupted" and s["signal"] == "SIGTERM"
    assert s["t_day"] == _manifest(out)["t_day"] < 2.0
    r = _run(scenario, out, cache, resume=True)
    assert r.returncode == 0, r.stderr[-3000:]
    assert_same_results(reference, out)
    # XDMF continued: the same times (none twice) and the same values
    for name in ("results.xdmf", "results_interface.xdmf"):
        assert (out / name).read_text().count("<Time ") == \
            (reference / name).read_text().count("<Time "), name
    a, b = _xdmf_series(reference), _xdmf_series(out)
    assert a.keys() == b.keys()
    assert max(_max_rel_diff(a[k], b[k]) for k in a if a[k].dtype.kind == "f") <= RTOL
    # a complete run is not run again
    r = _run(scenario, out, cache, resume=True)
    assert r.returncode == 0 and "is complete" in r.stderr and "nothing to resume" in r.stderr


@pytest.fixture(scope="module")
def stopped_on_two_ranks(tmp_path_factory, scenario, cache):
    """SIGUSR1 to ``mpirun -n 2`` (every mpirun forwards it to the ranks): (process, stderr,
    out)."""
    out = tmp_path_factory.mktemp("mpi") / "run"
    proc, stderr = _start_and_signal(scenario, out, cache, signal.SIGUSR1, ranks=2)
    return proc, stderr, out


def _assert_stopped_on_two_ranks(proc, stderr, out, sig):
    # both ranks stop at the same step boundary and exit 128 + sig; mpirun returns that code
    assert proc.returncode == 128 + sig, stderr[-3000:]
    lines = _pilegroup_lines(stderr)
    assert len(lines) == 1 and f"interrupted by {sig.name}" in lines[0], stderr[-3000:]
    assert lines[0].split("resume with: ")[1].startswith("mpirun -n 2 pilegroup run ")
    assert json.loads((out / "summary.json").read_text())["status"] == "interrupted"
    m = _manifest(out)
    assert m["ranks"] == 2 and len(m["files"]) == 2
    assert all((out / "checkpoint" / f).is_file() for f in m["files"])


@pytest.mark.mpi
def test_sigusr1_to_mpirun_stops_every_rank(stopped_on_two_ranks):
    _assert_stopped_on_two_ranks(*stopped_on_two_ranks, signal.SIGUSR1)


@pytest.mark.mpi
def test_sigterm_to_mpirun_stops_every_rank(tmp_path, scenario, cache,
                                            needs_mpirun_forwarding_sigterm):
    needs_mpirun_forwarding_sigterm()
    out = tmp_path / "run"
    proc, stderr = _start_and_signal(scenario, out, cache, signal.SIGTERM, ranks=2)
    _assert_stopped_on_two_ranks(proc, stderr, out, signal.SIGTERM)


@pytest.mark.mpi
def test_resume_on_another_rank_count_is_refused(stopped_on_two_ranks, scenario, cache):
    _, _, out = stopped_on_two_ranks
    r = _run(scenario, out, cache, resume=True)
    assert r.returncode == 2
    assert _pilegroup_lines(r.stderr) == [
        f"pilegroup: invalid input: --resume = '1 rank(s)': the checkpoint in "
        f"{out / 'checkpoint'} was written by 2 rank(s) and resumes on as many only (its "
        "state is saved per rank, for that mesh partition)"]


def test_resume_without_checkpoint_is_refused(tmp_path, scenario, cache):
    r = _run(scenario, tmp_path / "empty", cache, resume=True)
    assert r.returncode == 2
    lines = _pilegroup_lines(r.stderr)
    assert len(lines) == 1 and lines[0].startswith("pilegroup: invalid input: --resume = ")
    assert "no checkpoint in" in lines[0]


def test_trim_xdmf_keeps_the_first_times_and_appends_after_them(tmp_path):
    from dolfinx import fem, io, mesh
    from mpi4py import MPI

    from pilegroup.solver.exports import trim_xdmf

    msh = mesh.create_unit_cube(MPI.COMM_SELF, 2, 2, 2, mesh.CellType.hexahedron)
    u = fem.Function(fem.functionspace(msh, ("Lagrange", 1)), name="u")
    path = tmp_path / "r.xdmf"
    with io.XDMFFile(msh.comm, str(path), "w") as f:
        f.write_mesh(msh)
    for t in (0.0, 0.5, 1.0):
        u.x.array[:] = t
        with io.XDMFFile(msh.comm, str(path), "a") as f:
            f.write_function(u, t)
    trim_xdmf(path, 2)
    assert path.read_text().count("<Time ") == 2
    with h5py.File(tmp_path / "r.h5", "r") as f:
        assert sorted(f["Function/u"]) == ["0", "0_5"]
    u.x.array[:] = 3.0
    with io.XDMFFile(msh.comm, str(path), "a") as f:
        f.write_function(u, 1.0)
    assert path.read_text().count("<Time ") == 3
    with h5py.File(tmp_path / "r.h5", "r") as f:
        assert sorted(f["Function/u"]) == ["0", "0_5", "1"]
        assert np.all(f["Function/u/1"][()] == 3.0)


@pytest.mark.parametrize("value", [-1.0, float("nan"), float("inf")])
def test_checkpoint_interval_is_validated(value):
    from pilegroup.model import ScenarioError, load_scenario

    with pytest.raises(ScenarioError, match=r"outputs\.checkpoint_every_min = .*must be > 0"):
        load_scenario("single_pile", {"outputs.checkpoint_every_min": value})
    assert load_scenario("single_pile", {"outputs.checkpoint_every_min": 0.0}) \
        .outputs.checkpoint_every_min == 0.0
