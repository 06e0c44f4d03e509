"""The command line: help texts, mesh and run on the small bundled scenario, serial and MPI."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from pilegroup.studies.cli import build_parser, main

BIN = Path(sys.executable).parent


@pytest.mark.parametrize("argv", [[], ["scenario"], ["scenario", "show"], ["scenario", "validate"],
                                  ["run"], ["mesh"], ["verify"], ["bench"]])
def test_every_command_has_help(argv, capsys):
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args([*argv, "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    assert "usage: pilegroup" in out and len(out.splitlines()) >= 5


def test_verify_rejects_unknown_case(capsys):
    assert main(["verify", "nonsense"]) == 2
    assert "CASE = 'nonsense'" in capsys.readouterr().err


def test_mesh_and_run_single_pile(tmp_path, monkeypatch):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    assert main(["mesh", "single_pile", "--out", str(tmp_path / "m"), "--no-png"]) == 0
    s = json.loads((tmp_path / "m" / "mesh_summary.json").read_text())
    assert s["cells"] > 1000 and s["min_scaled_jacobian"] > 0.2 and s["shaft_groups"] == 2
    assert (tmp_path / "m" / "mesh.xdmf").is_file()
    assert main(["run", "single_pile", "--out", str(tmp_path / "r")]) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["mesh"]["cells"] == s["cells"]
    assert json.loads((tmp_path / "r" / "scenario.json").read_text())["name"] == "single_pile"


@pytest.mark.mpi
def test_run_under_mpirun_gives_serial_mesh(tmp_path):
    env = {"PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}
    import os

    env = dict(os.environ, **env)
    outs = {}
    for n in (1, 2):
        out = tmp_path / f"r{n}"
        r = subprocess.run([str(BIN / "mpirun"), "-n", str(n), str(BIN / "pilegroup"), "run",
                            "single_pile", "--out", str(out)], capture_output=True, text=True,
                           env=env, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        outs[n] = json.loads((out / "summary.json").read_text())
    assert outs[2]["ranks"] == 2
    assert outs[1]["mesh"]["cells"] == outs[2]["mesh"]["cells"]
    assert outs[1]["mesh"]["vertices"] == outs[2]["mesh"]["vertices"]
