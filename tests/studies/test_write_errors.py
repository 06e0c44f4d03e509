"""An output file that cannot be written fails the run (exit 1, ``summary.json`` ``failed``).

The write is made to fail by a directory in the file's place (root may write a read-only file).
The message names the file, not its temporary name; files written before stay complete.
"""

import csv
import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from pilegroup.studies.cli import commands as cli

FAST = ("outputs.plots=false", "outputs.xdmf=false")


def _run(small_pile, out, sets=FAST):
    return cli.main(["run", small_pile, "--out", str(out),
                     *[a for kv in sets for a in ("--set", kv)]])


def _lines(capsys):
    return [ln for ln in capsys.readouterr().err.splitlines() if ln.startswith("pilegroup:")]


@pytest.mark.parametrize("name", ["settlement.csv", "summary_solver.json"])
def test_failed_write_fails_the_run_naming_the_file(name, small_pile, tmp_path, monkeypatch,
                                                      capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    (out / name).mkdir(parents=True)
    assert _run(small_pile, out) == 1
    why = f"cannot write {out / name}: Is a directory"
    assert _lines(capsys) == [f"pilegroup: run failed: {why}"]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["reason"] == f"OutputError: {why}"
    assert json.loads((out / "scenario.json").read_text())["name"]  # complete before: readable
    assert not list(out.glob(".*.tmp")) and not list(out.glob(".settlement.csv.*"))


def test_failed_checkpoint_fails_the_run_and_earlier_rows_stay_readable(small_pile, tmp_path,
                                                                         monkeypatch, capsys):
    """The checkpoint at t = 0 follows the exports at t = 0: their files stay complete."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    out.mkdir()
    (out / "checkpoint").write_text("a file in the checkpoint folder's place")
    assert _run(small_pile, out) == 1
    why = f"cannot write {out / 'checkpoint' / 'state-000001-rank0000.npz'}: Not a directory"
    assert _lines(capsys) == [f"pilegroup: run failed: {why}"]
    rows = list(csv.reader((out / "settlement.csv").open()))
    assert len(rows) == 2 and float(rows[1][0]) == 0.0  # the header and the row at t = 0
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["reason"] == f"OutputError: {why}"


def test_summary_json_not_written_fails_the_run(small_pile, tmp_path, monkeypatch, capsys,
                                               caplog):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    (out / "summary.json").mkdir(parents=True)
    assert _run(small_pile, out) == 1
    assert _lines(capsys) == [f"pilegroup: run failed: cannot write {out / 'summary.json'}: "
                              "Is a directory"]
    assert "no summary.json of the stopped run" in caplog.text
    assert json.loads((out / "summary_solver.json").read_text())["complete"] is True


def test_figure_not_written_fails_the_run(small_pile, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    (out / "plots" / "settlement_time.png").mkdir(parents=True)
    assert _run(small_pile, out, sets=("outputs.xdmf=false",)) == 1
    why = f"cannot write {out / 'plots' / 'settlement_time.png'}: Is a directory"
    assert _lines(capsys) == [f"pilegroup: run failed: {why}"]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["reason"] == f"OutputError: {why}"


@pytest.mark.mpi
def test_failed_write_on_rank_0_ends_both_ranks(small_pile, tmp_path):
    """Rank 0 writes the CSV files: its failure ends rank 1 too (no hang), exit 1."""
    bin_ = Path(sys.executable).parent
    out = tmp_path / "run"
    (out / "settlement.csv").mkdir(parents=True)
    r = subprocess.run([str(bin_ / "mpirun"), "-n", "2", str(bin_ / "pilegroup"), "run",
                        small_pile, "--out", str(out), *[a for kv in FAST for a in ("--set", kv)]],
                       capture_output=True, text=True, timeout=300,
                       env={**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path)})
    assert r.returncode == 1, r.stderr[-3000:]
    why = f"cannot write {out / 'settlement.csv'}: Is a directory"
    assert [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")] == [
        f"pilegroup: rank 0 of 2 failed: {why}"]
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and s["rank"] == 0 and s["reason"] == f"OutputError: {why}"


def test_xdmf_not_written_fails_the_run(small_pile, tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    out = tmp_path / "run"
    (out / "results.h5").mkdir(parents=True)
    assert _run(small_pile, out, sets=("outputs.plots=false",)) == 1
    why = f"cannot write {out / 'results.h5'}: Failed to create HDF5 file."
    assert _lines(capsys) == [f"pilegroup: run failed: {why}"]
    assert json.loads((out / "summary.json").read_text())["reason"] == f"OutputError: {why}"
