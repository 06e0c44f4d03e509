"""Post-processing (studies.report): synthetic run folders with analytically chosen values."""

import json
import math
from pathlib import Path

import pytest

from pilegroup.model import ScenarioError
from pilegroup.studies.cli.commands import build_parser, main
from pilegroup.studies.report.plots import FIGURES
from pilegroup.studies.report.run_report import results_markdown, write_report
from pilegroup.studies.results.tables import COLUMNS

#: Four layers: the soft layers 1-3 of Table 1 and one stiff layer (number, name, top, bottom).
LAYERS = [(1, "clay", 0.0, 0.4), (2, "mud", 0.4, 19.7), (3, "mucky_clay", 19.7, 32.1),
          (4, "silty_clay_4", 32.1, 40.0)]
OUTPUT_DAYS = [0.0, 1.0, 30.0, 89.0, 180.0, 317.0]
T_LOAD = 1.0
F0 = {1: 5.0, 2: 8.0, 3: 12.0, 4: 30.0}  # kPa at the end of loading
W_END = {1: 0.012, 2: 0.010, 3: 0.006, 4: 0.002}  # m, scale of the relative displacement
CENTRE = 5
GAUGE_DEPTHS = [0.5, 10.0, 20.0, 30.0]


def gauge_row(t: float, pile: int, s: int, z: float) -> list[object]:
    """gauges.csv row: field minus model = +2 kN, +0.5 kPa and w/2 (model w = field w / 2)."""
    on = 1.0 if t > 0 else 0.0
    N, f, w = on * (1400.0 - 10.0 * z), on * (10.0 + z / 10.0), on * (12.0 - z / 10.0)
    last = s == len(GAUGE_DEPTHS)
    fm = float("nan") if last else f - 0.5 * on
    f = float("nan") if last else f
    return [t, pile, s, z, N / 1.5e7, N, f, w, N - 2.0 * on, fm, w / 2, w, 2.0 * on, f - fm,
            w / 2]


def settlement(t: float) -> float:
    """Cap settlement, m: zero before loading, then a consolidation-like curve."""
    return 0.0 if t < T_LOAD else 0.010 + 0.020 * (1.0 - math.exp(-(t - T_LOAD) / 50.0))


def friction(j: int, t: float, slopes: dict[int, float]) -> float:
    """Layer-mean friction, kPa: ramps to F0 during loading, then linear in time."""
    return F0[j] * t / T_LOAD if t < T_LOAD else F0[j] + slopes[j] * (t - T_LOAD)


def relative(j: int, t: float, shape: str) -> float:
    """Relative displacement, m: 1 - exp(-t/30) (early growth), (t/317)^3 (late) or zero."""
    if shape == "early":
        return W_END[j] * (1.0 - math.exp(-t / 30.0))
    if shape == "late":
        return W_END[j] * (t / 317.0) ** 3
    return 0.0


def write_csv(path: Path, header: list[str], rows: list[list[object]]) -> None:
    path.write_text("\n".join([",".join(header)] + [",".join(f"{v}" for v in r) for r in rows])
                    + "\n")


def _ground_tables(out: Path, files: tuple[str, ...]) -> None:
    """neutral_plane.csv, settlement_profiles.csv (piles 1, 5 and the free field), trough."""
    depths = [0.5 + k for k in range(40)]
    if "neutral_plane.csv" in files:
        rows = [[t, p, 12.0, 150.0, 0.01, 1200.0, 1350.0, 0.012] for t in OUTPUT_DAYS
                for p in (1, CENTRE)]
        write_csv(out / "neutral_plane.csv", list(COLUMNS["neutral_plane.csv"]), rows)
    if "settlement_profiles.csv" in files:
        rows = [[t, p, z, 1200.0 + 10 * z - 0.4 * z * z, 0.012 - 1e-5 * z, 0.02 * (1 - z / 40),
                 0.5] for t in OUTPUT_DAYS for p in (1, CENTRE) for z in depths]
        rows += [[t, 0, z, "", "", 0.02 * (1 - z / 40), 0.0] for t in OUTPUT_DAYS
                 for z in depths]
        write_csv(out / "settlement_profiles.csv", list(COLUMNS["settlement_profiles.csv"]), rows)
    if "surface_trough.csv" in files:
        rows = [[t, x, 0.01 * (1 - abs(x) / 40)] for t in OUTPUT_DAYS for x in range(-40, 41, 4)]
        write_csv(out / "surface_trough.csv", list(COLUMNS["surface_trough.csv"]), rows)


def _lateral_tables(out: Path, files: tuple[str, ...]) -> None:
    """pile_bending.csv (piles 1 and 5 bent along x), cap_motion.csv (a cap pushed along x)."""
    depths = [0.5 + k for k in range(40)]
    if "pile_bending.csv" in files:
        rows = [[t, p, z, 1200.0, 50.0 * math.exp(-z / 5), 0.0, 0.0,
                 100.0 * z * math.exp(-z / 4), 0.0, 0.01 * math.exp(-z / 6), 0.0]
                for t in OUTPUT_DAYS for p in (1, CENTRE) for z in depths]
        write_csv(out / "pile_bending.csv", list(COLUMNS["pile_bending.csv"]), rows)
    if "cap_motion.csv" in files:
        rows = [[t, 0.01 * (1 + t / 317), 0.0, -settlement(t), 0.0, 5e-4 * (1 + t / 317), 0.0]
                for t in OUTPUT_DAYS]
        write_csv(out / "cap_motion.csv", list(COLUMNS["cap_motion.csv"]), rows)


def make_run(out: Path, slopes: dict[int, float] | None = None, shape: str = "early",
             files: tuple[str, ...] = tuple(COLUMNS), complete: bool = True) -> Path:
    """A run folder following the data contract (centre pile 5 and corner pile 1)."""
    slopes = slopes if slopes is not None else {1: 0.01, 2: 0.02, 3: 0.015, 4: -0.01}
    out.mkdir(parents=True, exist_ok=True)
    stage = {0.0: "geostatic", 1.0: "loading"}
    if "settlement.csv" in files:
        write_csv(out / "settlement.csv", ["t_day", "stage", "settlement_m"],
                  [[t, stage.get(t, "consolidation"), f"{settlement(t):.9g}"]
                   for t in OUTPUT_DAYS])
    if "pile_profiles.csv" in files:
        rows = []
        for t in OUTPUT_DAYS:
            for pile in (1, CENTRE):
                for j, _, top, bot in LAYERS:
                    for z in (top + 0.25 * (bot - top), top + 0.75 * (bot - top)):
                        rows.append([t, pile, z, j, 1400.0 - 10.0 * z, friction(j, t, slopes),
                                     relative(j, t, shape)])
        write_csv(out / "pile_profiles.csv", list(COLUMNS["pile_profiles.csv"]), rows)
    if "layer_history.csv" in files:
        times = [0.0, 0.5, 1.0] + [float(d) for d in range(2, 318)]
        rows = [[t, CENTRE, j, name, top, bot, friction(j, t, slopes), relative(j, t, shape),
                 0.0, -50.0] for t in times for j, name, top, bot in LAYERS]
        write_csv(out / "layer_history.csv", list(COLUMNS["layer_history.csv"]), rows)
    if "pile_loads.csv" in files:
        rows = [[t, 3 * r + c + 1, 3.0 * c, 3.0 * r, 1000.0 + 100.0 * (3 * r + c + 1)]
                for t in OUTPUT_DAYS for r in range(3) for c in range(3)]
        write_csv(out / "pile_loads.csv", list(COLUMNS["pile_loads.csv"]), rows)
    if "load_settlement.csv" in files:
        rows = [[t, stage.get(t, "consolidation"), min(t, 1.0), 10856.0 * min(t, 1.0),
                 f"{settlement(t):.9g}"] for t in OUTPUT_DAYS]
        write_csv(out / "load_settlement.csv", list(COLUMNS["load_settlement.csv"]), rows)
    if "gauges.csv" in files:
        rows = [gauge_row(t, pile, s, z) for t in OUTPUT_DAYS for pile in (1, CENTRE)
                for s, z in enumerate(GAUGE_DEPTHS, start=1)]
        write_csv(out / "gauges.csv", list(COLUMNS["gauges.csv"]), rows)
    _ground_tables(out, files)
    _lateral_tables(out, files)
    if "capacity.csv" in files:  # a capacity stage's curve: stiff, then plunging at 20 MN
        w = [0.0, 0.01, 0.02, 0.04, 0.08, 0.2]
        q = [10856.0, 15000.0, 18000.0, 19500.0, 19900.0, 20000.0]
        rows = [[1.0 + k, p, k / 10, qi / (1 if p == 0 else 9), wi, ""]
                for p in (0, 1, CENTRE) for k, (qi, wi) in enumerate(zip(q, w, strict=True))]
        write_csv(out / "capacity.csv", list(COLUMNS["capacity.csv"]), rows)
    (out / "summary.json").write_text(json.dumps({"scenario": "synthetic", "complete": complete,
                                                  "centre_pile": CENTRE}))
    return out


def section(md: str, start: str) -> str:
    """The Markdown section whose heading starts with ``start`` (up to the next heading)."""
    part = md.split("### " + start, 1)[1]
    return part.split("\n### ", 1)[0]


def test_write_report_writes_every_figure(tmp_path):
    run = make_run(tmp_path / "run")
    paths = write_report(run)
    assert [p.name for p in paths] == [f[0] for f in FIGURES]
    for p in paths:
        assert p.parent == run / "plots"
        data = p.read_bytes()
        assert data[:8] == b"\x89PNG\r\n\x1a\n" and len(data) > 10_000, p
    assert sorted(x.name for x in (run / "plots").iterdir()) == sorted(p.name for p in paths)


def test_settlement_table_and_paper_value(tmp_path):
    md = results_markdown(make_run(tmp_path / "run"), "plots")
    sec = section(md, "Cap settlement")
    for t in OUTPUT_DAYS:
        stage = {0.0: "geostatic", 1.0: "loading"}.get(t, "consolidation")
        assert f"| {t:g} | {stage} | {1000 * settlement(t):.3f} |" in sec
    w = settlement(317.0)
    assert f"t = 317 day: **{1000 * w:.3f} mm** ({100 * w:.2f} cm), 10 % of the paper's" in sec
    assert "Table 2" in sec and "**30.3 cm**" in sec and "no measured settlement" in sec
    assert "End of loading: t = 1 day" in md and "run status: complete" in md
    for f, *_ in FIGURES:
        assert f"](plots/{f})" in md


def test_gauge_error_table_at_the_last_output_time(tmp_path):
    md = results_markdown(make_run(tmp_path / "run"), "plots")
    sec = section(md, "Virtual strain gauges")
    assert sec.startswith(": the field method against the model, t = 317 day")
    assert f"Centre pile {CENTRE}" in sec
    # z = 20 m: N = 1200 (model 1198), f = 12 (model 11.5), w = 10 mm (model 5 mm)
    assert ("| 3 | 20 | 1200.0 | 1198.0 | 12.000 | 11.500 | +0.500 | 10.000 | 10.000 | 5.000 "
            "| +5.000 |") in sec
    # no interval below the last section
    assert "| 4 | 30 | 1100.0 | 1098.0 | - | - | - | 9.000 | 9.000 | 4.500 | +4.500 |" in sec
    assert sec.count("\n| ") == 2 + len(GAUGE_DEPTHS)  # header, rule, one row per section


def test_answers_yes_for_growing_friction_and_early_relative_displacement(tmp_path):
    slopes = {1: 0.01, 2: 0.02, 3: 0.015, 4: -0.01}  # the stiff layer 4 does not count
    md = results_markdown(make_run(tmp_path / "run", slopes, "early"), "plots")
    fric = section(md, "Does shaft friction grow")
    assert "**Answer: yes.**" in fric
    f0, f1 = friction(2, 1.0, slopes), friction(2, 317.0, slopes)
    assert f"| 2 mud | {f0:.3f} | {f1:.3f} | {f1 - f0:+.3f} | yes |" in fric
    rel = section(md, "Does relative displacement grow fastest")
    assert "**Answer: yes.**" in rel
    w0, w89, w1 = (relative(1, t, "early") for t in (1.0, 89.0, 317.0))
    r1, r2 = (w89 - w0) / 88.0, (w1 - w89) / 228.0
    assert (f"| 1 clay | {1000 * w0:.3f} | {1000 * w89:.3f} | {1000 * w1:.3f} "
            f"| {1000 * r1:.5f} | {1000 * r2:.5f} | yes |") in rel


def test_answers_no_for_the_opposite_data(tmp_path):
    slopes = {1: -0.005, 2: -0.01, 3: -0.02, 4: 0.05}
    md = results_markdown(make_run(tmp_path / "run", slopes, "late"), "plots")
    assert "**Answer: no.**" in section(md, "Does shaft friction grow")
    assert "**Answer: no.**" in section(md, "Does relative displacement grow fastest")


def test_partial_growth_names_the_layers(tmp_path):
    # friction growing linearly in layer 2 only
    md = results_markdown(make_run(tmp_path / "run", {1: 0.0, 2: 0.02, 3: 0.0, 4: 0.0}),
                          "plots")
    assert "**Answer: no (only in layer(s) 2).**" in section(md, "Does shaft friction grow")


def test_profiles_replace_a_missing_layer_history(tmp_path):
    files = ("settlement.csv", "pile_profiles.csv")
    run = make_run(tmp_path / "run", shape="early", files=files)
    md = results_markdown(run, "plots")
    assert "**Answer: yes.**" in section(md, "Does shaft friction grow")
    assert "**Answer: yes.**" in section(md, "Does relative displacement grow fastest")
    names = [p.name for p in write_report(run)]
    assert "friction_time.png" in names and "pile_loads.png" not in names


def test_tied_run_and_interrupted_run(tmp_path):
    md = results_markdown(make_run(tmp_path / "run", shape="zero", complete=False), "figs")
    assert "**interrupted**" in md
    assert "**Answer: not applicable**" in section(md, "Does relative displacement grow fastest")


def test_missing_files_skip_figures(tmp_path, caplog):
    run = make_run(tmp_path / "run", files=("settlement.csv",))
    with caplog.at_level("INFO", logger="pilegroup.studies.report.run_report"):
        paths = write_report(run)
    assert [p.name for p in paths] == ["settlement_time.png"]
    assert "skipping friction_profiles.png" in caplog.text
    md = results_markdown(run, "plots")
    assert "**Answer: no data**" in section(md, "Does shaft friction grow")
    assert "**Answer: no data**" in section(md, "Does relative displacement grow fastest")
    assert "friction_profiles.png" not in md


def test_interrupted_before_89_days_says_data_missing(tmp_path):
    run = make_run(tmp_path / "run")
    for name in ("settlement.csv", "layer_history.csv", "pile_profiles.csv", "pile_loads.csv"):
        lines = (run / name).read_text().splitlines()
        keep = [ln for ln in lines[1:] if float(ln.split(",")[0]) <= 60.0]
        (run / name).write_text("\n".join([lines[0], *keep]) + "\n")
    md = results_markdown(run, "plots")
    assert "**Answer: yes.**" in section(md, "Does shaft friction grow")
    assert "**Answer: no data**" in section(md, "Does relative displacement grow fastest")
    assert len(write_report(run)) == len(FIGURES)


def test_wrong_header_is_a_clear_error(tmp_path):
    run = make_run(tmp_path / "run")
    text = (run / "pile_profiles.csv").read_text()
    (run / "pile_profiles.csv").write_text(text.replace("depth_m", "z_m", 1))
    with pytest.raises(ScenarioError) as info:
        write_report(run)
    msg = str(info.value)
    assert "pile_profiles.csv" in msg and "missing column 'depth_m'" in msg
    assert "required columns: t_day, pile, depth_m, layer" in msg


def test_non_numeric_value_is_a_clear_error(tmp_path):
    run = make_run(tmp_path / "run", files=("settlement.csv",))
    (run / "settlement.csv").write_text("t_day,stage,settlement_m\n0,geostatic,abc\n")
    with pytest.raises(ScenarioError, match=r"settlement.csv row 2 = 'abc': column "
                                            r"'settlement_m' must be a number"):
        results_markdown(run, "plots")


def test_cli_report_with_markdown(tmp_path, capsys):
    run = make_run(tmp_path / "run")
    md = tmp_path / "doc" / "results.md"
    assert main(["report", str(run), "--markdown", str(md)]) == 0
    assert len(capsys.readouterr().out.splitlines()) == len(FIGURES) + 1
    text = md.read_text()
    assert "](../run/plots/friction_profiles.png)" in text
    assert all((run / "plots" / f[0]).is_file() for f in FIGURES)


@pytest.mark.parametrize("problem", ["missing_folder", "empty_folder", "bad_header"])
def test_cli_report_bad_input_exits_2(tmp_path, capsys, problem):
    run = tmp_path / "run"
    if problem == "empty_folder":
        run.mkdir()
    elif problem == "bad_header":
        make_run(run, files=("pile_loads.csv",))
        (run / "pile_loads.csv").write_text("t_day,pile,x_m,y_m\n0,1,0,0\n")
    assert main(["report", str(run)]) == 2
    err = capsys.readouterr().err
    assert err.startswith("pilegroup: invalid input: ") and len(err.strip().splitlines()) == 1
    expected = {"missing_folder": "no such folder", "empty_folder": "not a run output folder",
                "bad_header": "missing column 'head_force_kN'"}[problem]
    assert expected in err and "Traceback" not in err


def test_report_has_help(capsys):
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args(["report", "--help"])
    assert info.value.code == 0
    assert "usage: pilegroup report" in capsys.readouterr().out
