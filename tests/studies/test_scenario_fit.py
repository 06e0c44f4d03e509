"""``pilegroup fit scenario``: back-analysis of a "measured" settlement history (slow tier).

The measured layouts (settlement.csv, gauges.csv) are read back against their own run (fast).

The measurement is a run of the bundled ``single_pile`` (coarsened by ``--set`` as the small
scenario of the fast tests, output every quarter day to 2 days) with the mud's modulus 2.0 MPa
instead of 3.0; the fit starts from the scenario's 3.0 MPa (50 % off) and must recover it
within 5 %. Then the same command again: every run is complete, nothing runs again (resume).
Measured on the shared 2-core machine: docs/results.md ("Back-analysis").
"""

import json
import time

import numpy as np
import pytest

from pilegroup.errors import ScenarioError
from pilegroup.studies.cli.commands import main
from pilegroup.studies.lab.fit_plots import write_scenario_fit_figure
from pilegroup.studies.lab.fit_stats import FitResult
from pilegroup.studies.lab.scenario_fit import ScenarioFit, VaryKey, case_name, read_measured

COARSE = ("numerics.mesh.size_m=1.0", "numerics.mesh.n_circ_min=8",
          "numerics.mesh.far_field_size_m=8.0", "numerics.mesh.dz_max_m=4.0",
          "numerics.mesh.dz_surface_m=2.0", "numerics.mesh.dz_toe_m=2.0",
          "numerics.mesh.dz_max_deep_m=8.0", "time.end_day=2.0",
          "time.output_days=[0,0.25,0.5,1,2]", "outputs.xdmf=false")
SETS = [a for s in COARSE for a in ("--set", s)]
KEY, TRUE, START = "layers[0].E_MPa", 2.0, 3.0


@pytest.mark.slow
def test_back_analysis_recovers_the_modulus(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    meas = tmp_path / "measured"
    assert main(["run", "single_pile", *SETS, "--set", f"{KEY}={TRUE}", "--out", str(meas)]) == 0
    argv = ["fit", "scenario", "single_pile", "--data", str(meas / "settlement.csv"),
            "--vary", f"{KEY}=1:6", *SETS, "--out", str(tmp_path / "fit"), "--no-progress",
            "--json"]
    capsys.readouterr()
    t0 = time.monotonic()
    assert main(argv) == 0
    wall = time.monotonic() - t0
    got = json.loads(capsys.readouterr().out)
    assert got["start"] == [START]  # the scenario's value: 50 % above the truth
    assert got[KEY] == pytest.approx(TRUE, rel=0.05)
    assert got["runs"] == len(got["evaluations_record"]) <= 60
    assert all(r["status"] == "complete" for r in got["evaluations_record"])
    with capsys.disabled():
        print(f"\nback-analysis: {KEY} = {got[KEY]:.6g} (true {TRUE}), {got['runs']} runs, "
              f"{wall:.0f} s, misfit {got['misfit']:.3g} m")
    assert (tmp_path / "fit" / "fit.png").is_file()
    assert json.loads((tmp_path / "fit" / "fit.json").read_text())[KEY] == got[KEY]
    # the same command again resumes: every run is complete, none is run again
    t0 = time.monotonic()
    assert main(argv) == 0
    again = json.loads(capsys.readouterr().out)
    assert again[KEY] == got[KEY] and again["runs"] == got["runs"]
    resumed = time.monotonic() - t0
    with capsys.disabled():
        print(f"resumed: {resumed:.0f} s")
    assert resumed < wall / 3


@pytest.mark.parametrize("name, layout", [("settlement.csv", "settlement"),
                                          ("gauges.csv", "gauges")])
def test_measured_history_read_back_from_its_run(small_pile_run, name, layout, tmp_path):
    """A run's own history is the model's history at its rows; times beyond it are refused."""
    m = read_measured(small_pile_run / name)
    assert m.layout == layout and m.values.size >= 3
    assert np.array_equal(m.model_values(small_pile_run), m.values)
    fit = ScenarioFit("single_pile", {}, [VaryKey(KEY, 1.0, 6.0)], m, tmp_path / "fit")
    fit.cases[case_name([3.0])] = (3.0,)
    fit.model[case_name([3.0])] = m.model_values(small_pile_run)
    res = FitResult("scenario", name, (KEY,), (3.0,), (0.0,), ((1.0,),), 0.0, fit.unit,
                    m.values.size, 1)
    assert write_scenario_fit_figure(tmp_path / "fit.png", fit, res).stat().st_size > 10_000
    late = tmp_path / name
    rows = (small_pile_run / name).read_text().splitlines()
    col = rows[0].split(",").index("t_day" if layout == "settlement" else "time_day")
    last = rows[-1].split(",")
    last[col] = "99"
    late.write_text("\n".join([*rows, ",".join(last)]) + "\n")
    with pytest.raises(ScenarioError, match="must lie within the model's output times"):
        read_measured(late).model_values(small_pile_run)
