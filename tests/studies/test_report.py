"""Post-processing (studies.report): synthetic run folders with analytically chosen values.

Figures and report speak of the scenario: its piles by place, its layers, its toes; published
values only from its ``[reference]`` (docs/results.md, "Figures and report of a run"); the last
test reads the small pile's real run.
"""

import csv
import dataclasses
import json
import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from matplotlib.text import Text

from pilegroup.model import ScenarioError, load_scenario
from pilegroup.studies.cli.commands import build_parser, main
from pilegroup.studies.report.plots import FIGURES
from pilegroup.studies.report.run_report import results_markdown, write_report
from pilegroup.studies.results.pile_roles import key_piles, name_piles
from pilegroup.studies.results.rundata import load_run
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
#: The piles' length in soil (m): the last layer reaches on to the block's bottom at 80 m.
PILE_LENGTH, BLOCK_DEPTH = 40.0, 80.0
#: The vertical load of the synthetic scenario's load stage (kN).
APPLIED_KN = 12000.0


def scenario_json(reference: bool) -> dict:
    """scenario.json of the synthetic run: 3 x 3 piles at 3 m, 40 m long, the layers of LAYERS
    (the last one down to the block's bottom), and pier667's ``[reference]`` if asked."""
    layers = [{"name": name, "thickness_m": bot - top} for _, name, top, bot in LAYERS]
    layers[-1]["thickness_m"] = None
    ref = dataclasses.asdict(load_scenario("pier667").reference) if reference else None
    return {"name": "synthetic", "site": {"depth_m": BLOCK_DEPTH}, "layers": layers,
            "piles": {"diameter_m": 1.0, "length_in_soil_m": PILE_LENGTH,
                      "positions_m": [[3.0 * c, 3.0 * r] for r in range(3) for c in range(3)]},
            "stages": [{"name": "geostatic", "kind": "geostatic"},
                       {"name": "loading", "kind": "load", "cap_load_kN": APPLIED_KN}],
            "reference": ref}


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
             files: tuple[str, ...] = tuple(COLUMNS), complete: bool = True,
             reference: bool = True) -> Path:
    """A run folder following the data contract (centre pile 5 and corner pile 1).

    Its scenario.json carries pier667's ``[reference]`` unless ``reference`` is false.
    """
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
    if "pile_heads.csv" in files:  # the head: 1 % above the uppermost section's force
        rows = [[t, 3 * r + c + 1, 3.0 * c, 3.0 * r, 1010.0 + 101.0 * (3 * r + c + 1)]
                + [0.0] * 5 + [0.0] for t in OUTPUT_DAYS for r in range(3) for c in range(3)]
        write_csv(out / "pile_heads.csv", list(COLUMNS["pile_heads.csv"]), rows)
    (out / "summary.json").write_text(json.dumps({"scenario": "synthetic", "complete": complete,
                                                  "centre_pile": CENTRE}))
    (out / "scenario.json").write_text(json.dumps(scenario_json(reference)))
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
    assert f"t = 317 day: **{1000 * w:.3f} mm** ({100 * w:.2f} cm)." in sec
    # pier667's [reference]: the paper's ABAQUS 30.3 cm
    assert "Reference settlement: **303 mm** (no time stated)" in sec
    assert "Table 2" in sec and "no measured settlement" in sec and "10 % of it" in sec
    assert "End of loading: t = 1 day" in md and "run status: complete" in md
    for f, *_ in FIGURES:
        assert f"](plots/{f})" in md


def test_gauge_error_table_at_the_last_output_time(tmp_path):
    md = results_markdown(make_run(tmp_path / "run"), "plots")
    sec = section(md, "Virtual strain gauges")
    assert sec.startswith(": the field method against the model, t = 317 day")
    assert "Pile 5 (row 2, column 2, centre)" in sec
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
    # the figures, report.md, report.html and the --markdown file
    assert len(capsys.readouterr().out.splitlines()) == len(FIGURES) + 3
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


#: Text of a publication that only a scenario with a [reference] may show.
PUBLISHED = ("ABAQUS", "Table 1", "Table 2", "30.3", "303", "10856", "soft layer", "first 89",
             "89 d (reference)", "paper", "Li, Feng", "reference", "Reference")


def texts(run_dir) -> dict[str, str]:
    """Every figure's text (titles, labels, legends, notes) and the Markdown summary, by name."""
    run = load_run(run_dir)
    out = {}
    for name, _, needs, plot in FIGURES:
        if run.has(needs):
            fig = plot(run)
            out[name] = "\n".join(t.get_text() for t in fig.findobj(Text))
    out["report.md"] = results_markdown(run_dir, "plots").replace(str(run_dir), "RUN")
    return out


def test_piles_are_named_by_their_place():
    grid = name_piles([(x, y) for y in (-2.5, 0.0, 2.5) for x in (-3.5, 0.0, 3.5)], [63.5] * 9)
    assert [p.role for p in grid] == ["corner", "edge", "corner", "edge", "centre", "edge",
                                      "corner", "edge", "corner"]
    assert grid[4].name == "pile 5 (row 2, column 2, centre)" and grid[4].length == 63.5
    assert grid[5].short == "pile 6, r2 c3"
    # a 2 x 3 group (3 columns along x, 2 rows along y) has no centre pile
    two = name_piles([(x, y) for y in (-1.8, 1.8) for x in (-3.6, 0.0, 3.6)])
    assert [p.role for p in two] == ["corner", "edge", "corner"] * 2
    assert name_piles([(0.0, 0.0)])[0].name == "the pile"
    assert [p.role for p in name_piles([(0, 0), (2, 0), (4, 0)])] == ["end", "centre", "end"]
    odd = name_piles([(0.0, 0.0), (1.0, 2.0), (5.0, 1.0)])
    assert odd[1].name == "pile 2 (x = 1 m, y = 2 m)" and odd[1].row is None


def test_key_piles_are_one_of_each_role_and_the_most_and_least_loaded():
    grid = name_piles([(x, y) for y in (-2.5, 0.0, 2.5) for x in (-3.5, 0.0, 3.5)])
    loads = {1: 1390.3, 2: 1108.6, 3: 1390.3, 4: 1128.5, 5: 820.7, 6: 1128.5, 7: 1390.3,
             8: 1108.6, 9: 1390.3}
    picked = [(p.number, why) for p, why in key_piles(grid, loads)]
    assert picked == [(1, "corner, most loaded"), (4, "edge"), (5, "centre, least loaded")]
    two = name_piles([(x, y) for y in (-1.8, 1.8) for x in (-3.6, 0.0, 3.6)])
    lateral = {1: 3000.0, 2: 4000.0, 3: 5000.0, 4: 3000.0, 5: 4000.0, 6: 5000.0}
    assert [(p.number, why) for p, why in key_piles(two, lateral)] == [
        (1, "least loaded"), (2, "edge"), (3, "corner, most loaded")]


def test_without_a_reference_nothing_published_is_drawn_or_written(tmp_path):
    run = make_run(tmp_path / "run", reference=False)
    for name, text in texts(run).items():
        found = [w for w in PUBLISHED if w in text]
        assert not found, (name, found)
    md = results_markdown(run, "plots")
    assert "### Shaft friction from the end of loading to the last output time" in md
    assert "grow fastest" not in md  # the early period is a reference's
    assert "vertical load of the last load stage: 12000.0 kN" in md


def test_pier667_s_reference_is_drawn_and_written(tmp_path):
    ref = load_scenario("pier667").reference
    assert ref is not None and ref.settlement_m == 0.303 and ref.soft_layers == (1, 2, 3)
    assert ref.total_load_kN == 10856.0 and ref.early_day == 89.0
    out = texts(make_run(tmp_path / "run"))
    assert "reference: 303 mm (no time stated)" in out["settlement_time.png"]
    assert "89 d (reference)" in out["friction_time.png"]
    assert "soft layers 1, 2, 3 of the reference" in out["friction_time.png"]
    md = out["report.md"]
    for words in ("ABAQUS", "Table 2", "reference total load on the foundation: 10856 kN",
                  "### Does shaft friction grow with time in the soft layers?",
                  "### Does relative displacement grow fastest in the first 89 days?",
                  "Soft layers 1, 2, 3 of the reference (clay, mud, mucky_clay)"):
        assert words in md, words


def test_figures_name_piles_by_place_and_end_below_the_deepest_toe(tmp_path):
    run = load_run(make_run(tmp_path / "run"))
    out = texts(run.out_dir)
    # the synthetic profiles hold piles 1 and 5 only; pile 9 carries the most
    assert "pile 1, r1 c1\n(least loaded)" in out["axial_force_profiles.png"]
    assert "pile 5, r2 c2\n(centre)" in out["axial_force_profiles.png"]
    assert "pile 5 (row 2, column 2, centre)" in out["friction_time.png"]
    assert "mucky_clay" in out["axial_force_profiles.png"]  # the layers by name
    for name, _, _, plot in FIGURES:
        if name in ("axial_force_profiles.png", "friction_profiles.png",
                    "gauge_friction_profiles.png", "unified_method.png", "pile_bending.png"):
            bottom, top = plot(run).axes[0].get_ylim()
            assert (bottom, top) == pytest.approx((1.1 * PILE_LENGTH, 0.0)), name


def test_a_group_without_a_centre_pile_has_none_in_its_report(tmp_path):
    run_dir = make_run(tmp_path / "run")
    sc = json.loads((run_dir / "scenario.json").read_text())
    sc["piles"]["positions_m"] = [[3.0 * c, 3.0 * r] for r in range(2) for c in range(3)]
    (run_dir / "scenario.json").write_text(json.dumps(sc))
    for name, text in texts(run_dir).items():
        assert "centre pile" not in text and ", centre)" not in text, name
    assert "pile 5 (row 2, column 2, edge)" in texts(run_dir)["report.md"]


def _rows(path):
    with path.open() as fh:
        return list(csv.DictReader(fh))


@pytest.mark.parametrize("small_pile_run", ["viscoplastic"], indirect=True)
def test_a_real_run_cut_at_the_toe_and_its_head_force(small_pile_run, tmp_path):
    run_dir = tmp_path / "run"
    shutil.copytree(small_pile_run, run_dir)
    toe = load_run(run_dir).deepest_toe
    assert toe == 12.0  # the block reaches 20 m
    for name in ("interface_layers.csv", "layer_history.csv"):
        rows = _rows(run_dir / name)
        assert max(float(r["depth_bottom_m"]) for r in rows) == pytest.approx(toe), name
    loads = [r for r in _rows(run_dir / "pile_loads.csv") if float(r["t_day"]) == 2.0]
    heads = [r for r in _rows(run_dir / "pile_heads.csv") if float(r["t_day"]) == 2.0]
    assert float(loads[0]["depth_m"]) == 0.0 == float(heads[0]["depth_m"])
    head = float(heads[0]["N_kN"])
    assert float(loads[0]["head_force_kN"]) == head  # one head force (docs/model.md)
    assert head == pytest.approx(500.0, rel=1e-6)  # the load on the head
    profile = [r for r in _rows(run_dir / "pile_profiles.csv") if float(r["t_day"]) == 2.0]
    assert float(profile[0]["axial_force_kN"]) < head  # below the head: friction above it
    write_report(run_dir)
    for name, text in texts(run_dir).items():
        found = [w for w in PUBLISHED if w in text]
        assert not found, (name, found)
    assert "the cap's action on the pile at its head" in texts(run_dir)["report.md"]
    ylim = FIGURES[5][3](load_run(run_dir)).axes[0].get_ylim()
    assert np.allclose(ylim, (1.1 * toe, 0.0))
