"""The envelope of load combinations, on run folders written here (the CSV contract)."""

import csv

import pytest

from pilegroup.studies.results.envelope import (
    ENVELOPE_COLUMNS,
    RESULT_COLUMNS,
    CombinationRun,
    combination_readings,
    envelope,
)
from pilegroup.studies.results.envelope_report import write_envelope
from pilegroup.studies.results.tables import COLUMNS

#: Two piles at x = -1, 1; output times 0, 1, 2 days.
TIMES = (0.0, 1.0, 2.0)


def _write(run, name, rows):
    run.mkdir(parents=True, exist_ok=True)
    lines = [",".join(COLUMNS[name]), *(",".join(f"{v:g}" for v in r) for r in rows)]
    (run / name).write_text("\n".join(lines) + "\n")


def _run(tmp_path, name, scale, moments=True, tension=0.0):
    """A run folder: actions growing with time (x ``scale``), pile 2 pulled by ``tension``."""
    run = tmp_path / name
    run.mkdir(parents=True)
    (run / "settlement.csv").write_text("t_day,stage,settlement_m\n" + "".join(
        f"{t:g},loading,{0.01 * scale * t:g}\n" for t in TIMES))
    _write(run, "cap_motion.csv", [(t, 0.001 * scale * t * (-1) ** int(t), 0, -0.01 * scale * t,
                                    0, 1e-4 * scale * t, 0) for t in TIMES])
    heads = []
    for t in TIMES:
        heads.append((t, 1, -1, 0, 300 * scale * t, 3 * t, 4 * t, 0, 0, 0, 0))
        heads.append((t, 2, 1, 0, 100 * scale * t - tension * t, 6 * scale * t, 8 * t, 0, 0, 0,
                      0))
    _write(run, "pile_heads.csv", heads)
    if moments:
        _write(run, "pile_max_moment.csv", [r for t in TIMES for r in (
            (t, 1, 10 * scale * t, 2.5), (t, 2, 20 * scale * t, 4.0 + t))])
    return run


def _rows(path):
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


@pytest.fixture
def folders(tmp_path):
    """SLS, ULS (larger), ULS_lift (pile 2 in tension, no moments) and a failed one."""
    _run(tmp_path, "SLS", 1.0)
    _run(tmp_path, "ULS", 1.5)
    _run(tmp_path, "ULS_lift", 1.2, moments=False, tension=160.0)
    return [CombinationRun("SLS", tmp_path / "SLS", factors={"permanent": 1.0}),
            CombinationRun("ULS", tmp_path / "ULS", factors={"permanent": 1.35},
                           actions={"Fx_kN": 75.0, "Fz_kN": -540.0}),
            CombinationRun("ULS_lift", tmp_path / "ULS_lift"),
            CombinationRun("ULS_wind", tmp_path / "ULS_wind", "failed",
                           "ConvergenceError: no equilibrium at t = 0.3 day")]


def test_governing_combination_pile_depth_and_time(tmp_path, folders):
    write_envelope(tmp_path, folders, "test")
    rows = {(r["quantity"], r["pile"], r["time"]): r for r in _rows(tmp_path / "envelope.csv")}
    assert tuple(_rows(tmp_path / "envelope.csv")[0]) == ENVELOPE_COLUMNS
    n = rows[("N_kN", "", "last")]  # largest compression and the tension, with their piles
    assert (n["max"], n["max_combination"], n["max_pile"], n["max_t_day"]) == (
        "900", "ULS", "1", "2")
    assert (n["min"], n["min_combination"], n["min_pile"]) == ("-80", "ULS_lift", "2")
    v = rows[("V_kN", "", "last")]  # resultant: hypot(6 * 1.5 * 2, 16)
    assert float(v["max"]) == pytest.approx(24.08318, rel=1e-6)
    assert (v["max_combination"], v["max_pile"]) == ("ULS", "2")
    m = rows[("M_max_kNm", "", "last")]
    assert (m["max"], m["max_combination"], m["max_pile"], m["max_depth_m"]) == (
        "60", "ULS", "2", "6")
    # the combination without pile_max_moment.csv and the failed one are listed, not dropped
    assert m["combinations"] == "2"
    assert m["excluded"] == "ULS_lift (no pile_max_moment.csv); ULS_wind (failed)"
    assert rows[("N_kN", "", "last")]["excluded"] == "ULS_wind (failed)"
    # per pile; a run folder without the file says so on every pile's row
    assert rows[("M_max_kNm", "1", "last")]["max_depth_m"] == "2.5"
    assert rows[("M_max_kNm", "2", "all")]["excluded"].startswith(
        "ULS_lift (no pile_max_moment.csv)")
    assert rows[("N_kN", "2", "last")]["max"] == "300"


def test_last_time_against_every_time(tmp_path, folders):
    rows = {(e.quantity.name, e.pile, e.time): e
            for e in envelope(folders, {r.name: combination_readings(r) for r in folders[:3]})}
    last, every = rows[("ux_m", None, "last")], rows[("ux_m", None, "all")]
    # ux alternates in sign: largest +0.003 at t = 2 (ULS), smallest -0.0015 at t = 1 (ULS)
    assert (last.max.value, last.max_combination) == (pytest.approx(0.003), "ULS")
    assert (last.min.value, last.min_combination) == (pytest.approx(0.002), "SLS")
    assert (every.min.value, every.min.t_day, every.min_combination) == (
        pytest.approx(-0.0015), 1.0, "ULS")
    assert every.max.t_day == 2.0
    n2 = rows[("N_kN", 2, "all")]
    assert (n2.min.value, n2.min.t_day) == (pytest.approx(-80.0), 2.0)


def test_a_tie_goes_to_the_first_combination(tmp_path):
    runs = [CombinationRun(n, _run(tmp_path, n, 1.0)) for n in ("A", "B")]
    rows = envelope(runs, {r.name: combination_readings(r) for r in runs})
    assert {(e.max_combination, e.min_combination) for e in rows if e.max is not None} == {
        ("A", "A")}


def test_missing_files_give_empty_quantities(tmp_path):
    run = tmp_path / "vertical"
    run.mkdir()
    (run / "settlement.csv").write_text("t_day,stage,settlement_m\n0,geostatic,0\n"
                                        "0.5,loading,0.013\n")
    (run / "pile_loads.csv").write_text("t_day,pile,x_m,y_m,head_force_kN\n0,1,0,0,0\n"
                                        "0.5,1,0,0,498\n")
    runs = [CombinationRun("vertical", run), CombinationRun("never", tmp_path / "never",
                                                            "pending")]
    rows = write_envelope(tmp_path, runs, "test")
    by = {(e.quantity.name, e.pile, e.time): e for e in rows}
    assert by[("N_kN", None, "last")].max.value == 498.0  # from pile_loads.csv
    for q, file in (("ux_m", "cap_motion.csv"), ("V_kN", "pile_heads.csv"),
                    ("M_max_kNm", "pile_max_moment.csv")):
        e = by[(q, None, "all")]
        assert e.max is None and e.count == 0
        assert e.excluded == (("vertical", f"no {file}"), ("never", "pending"))
    text = (tmp_path / "envelope.csv").read_text().splitlines()
    assert any(line.startswith("M_max_kNm,kNm,,last,,,,,,,,,,,0,") for line in text)
    md = (tmp_path / "envelope.md").read_text()
    assert "`never` (pending)" in md and "`M_max_kNm` (" in md


def test_results_list_every_combination(tmp_path, folders):
    write_envelope(tmp_path, folders, "test")
    rows = _rows(tmp_path / "combination_results.csv")
    assert tuple(rows[0]) == RESULT_COLUMNS
    failed = [r for r in rows if r["combination"] == "ULS_wind"]
    assert len(failed) == 1 and failed[0]["status"] == "failed"
    assert failed[0]["note"].startswith("ConvergenceError") and failed[0]["quantity"] == ""
    lift = {(r["quantity"], r["pile"], r["time"]): r for r in rows
            if r["combination"] == "ULS_lift"}
    assert lift[("M_max_kNm", "", "last")]["note"] == "no pile_max_moment.csv"
    assert lift[("N_kN", "", "last")]["min"] == "-80"
    md = (tmp_path / "envelope.md").read_text()
    assert "`ULS_wind` (failed: ConvergenceError: no equilibrium at t = 0.3 day)" in md
    assert "| `ULS` | complete | 1.35 x permanent |" in md
    assert "## Envelope per pile" in md


def test_an_unreadable_file_is_a_note_not_a_crash(tmp_path):
    run = _run(tmp_path, "A", 1.0)
    (run / "pile_heads.csv").write_text("t_day,pile\n0,1\n")
    readings = combination_readings(CombinationRun("A", run))
    notes = {r.note for r in readings if r.quantity.name == "V_kN"}
    assert notes == {"pile_heads.csv unreadable"}
