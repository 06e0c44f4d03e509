"""The command line: help texts, mesh and run on the small bundled scenario, serial and MPI."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from pilegroup.studies.cli.commands import build_parser, main
from pilegroup.studies.run.pipeline import GEOSTATIC_TOL_M

BIN = Path(sys.executable).parent


@pytest.mark.parametrize("argv", [[], ["scenario"], ["scenario", "show"], ["scenario", "validate"],
                                  ["run"], ["mesh"], ["verify"], ["bench"], ["batch"],
                                  ["combinations"], ["study"], ["study", "mesh"]])
def test_every_command_has_help(argv, capsys):
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args([*argv, "--help"])
    assert info.value.code == 0
    out = capsys.readouterr().out
    assert "usage: pilegroup" in out and len(out.splitlines()) >= 5


def test_verify_rejects_unknown_case(capsys):
    assert main(["verify", "nonsense"]) == 2
    assert "CASE = 'nonsense'" in capsys.readouterr().err


@pytest.mark.parametrize("quadrature", ["nodal", "gauss"])
def test_mesh_and_run_single_pile(tmp_path, monkeypatch, small_pile, quadrature):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    if quadrature != "nodal":  # the interface law at facet Gauss points: same outputs
        text = Path(small_pile).read_text()
        assert 'mode = "viscoplastic"\n' in text
        Path(small_pile).write_text(text.replace(
            'mode = "viscoplastic"\n', f'mode = "viscoplastic"\nquadrature = "{quadrature}"\n'))
    assert main(["mesh", small_pile, "--out", str(tmp_path / "m"), "--no-png"]) == 0
    s = json.loads((tmp_path / "m" / "mesh_summary.json").read_text())
    assert s["cells"] > 100 and s["min_scaled_jacobian"] > 0.2 and s["shaft_groups"] == 2
    assert (tmp_path / "m" / "mesh.xdmf").is_file()
    assert main(["run", small_pile, "--out", str(tmp_path / "r")]) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["mesh"]["cells"] == s["cells"]
    resolved = json.loads((tmp_path / "r" / "scenario.json").read_text())
    assert resolved["name"] == "single_pile"
    assert resolved["interface"]["quadrature"] == quadrature
    hist = summary["solver"]["settlement_m"]
    assert [h["t_day"] for h in hist] == [0.0, 0.5, 2.0]
    # the pile settles under load and keeps settling while the soil consolidates
    assert 0 < hist[1]["settlement_m"] < hist[2]["settlement_m"]
    # single_pile uses the viscoplastic interface: separate pile and soil fields
    assert summary["solver"]["interface_mode"] == "viscoplastic"
    assert summary["solver"]["geostatic_max_u_m"] < GEOSTATIC_TOL_M
    for name in ("results.xdmf", "results_structure.xdmf", "results_interface.xdmf",
                 "pile_profiles.csv", "pile_loads.csv", "layer_history.csv",
                 "interface_layers.csv", "plots/friction_profiles.png",
                 "plots/settlement_time.png"):
        assert (tmp_path / "r" / name).is_file(), name
    # per pile and layer at the output times; the centre pile's rows are its step history's
    per_pile = (tmp_path / "r" / "interface_layers.csv").read_text().splitlines()
    steps = (tmp_path / "r" / "layer_history.csv").read_text().splitlines()
    assert per_pile[0] == steps[0]
    last = [r for r in per_pile[1:] if r.startswith("2,")]
    assert last and set(last) <= set(steps[1:])
    # the head load of the single pile is the applied load (axial force due to the load)
    loads = (tmp_path / "r" / "pile_loads.csv").read_text().splitlines()
    column = loads[0].split(",").index("head_force_kN")
    assert float(loads[-1].split(",")[column]) == pytest.approx(500.0, rel=0.02)


@pytest.mark.mpi
def test_run_under_mpirun_gives_serial_mesh(tmp_path, small_pile):
    env = {"PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}
    import os

    env = dict(os.environ, **env)
    outs = {}
    for n in (1, 2):
        out = tmp_path / f"r{n}"
        r = subprocess.run([str(BIN / "mpirun"), "-n", str(n), str(BIN / "pilegroup"), "run",
                            small_pile, "--out", str(out)],
                           capture_output=True, text=True, env=env, timeout=600)
        assert r.returncode == 0, r.stderr[-3000:]
        outs[n] = json.loads((out / "summary.json").read_text())
    assert outs[2]["ranks"] == 2
    assert outs[1]["mesh"]["cells"] == outs[2]["mesh"]["cells"]
    assert outs[1]["mesh"]["vertices"] == outs[2]["mesh"]["vertices"]
    # the same answer in parallel (direct solver: to round-off; 1e-8 relative)
    w1 = [h["settlement_m"] for h in outs[1]["solver"]["settlement_m"]]
    w2 = [h["settlement_m"] for h in outs[2]["solver"]["settlement_m"]]
    assert w2 == pytest.approx(w1, rel=1e-8)


def test_run_stop_after_mesh(tmp_path, monkeypatch, small_pile):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    assert main(["run", small_pile, "--out", str(tmp_path / "r"),
                 "--stop-after", "mesh"]) == 0
    summary = json.loads((tmp_path / "r" / "summary.json").read_text())
    assert summary["stages_done"] == ["validate", "mesh"] and summary["solver"] is None
    assert not (tmp_path / "r" / "results.xdmf").exists()
