"""Two run folders compared against the reduced model's bounds
(studies/campaigns/compare_runs.py)."""

import csv
import shutil

import pytest

from pilegroup.studies.campaigns import compare_runs


def _scale(path, column, factor, row=None):
    """Multiply ``column`` of the CSV ``path`` by ``factor`` (in one data row, or in all)."""
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    for i, r in enumerate(rows):
        if (row is None or i == row) and r[column] not in ("", "0"):
            r[column] = repr(float(r[column]) * factor)
    with path.open("w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)


def test_a_run_equals_itself(small_pile_run, capsys):
    diffs = compare_runs.compare_runs(small_pile_run, small_pile_run)
    assert [d.quantity for d in diffs] == list(compare_runs.BOUNDS)
    assert all(d.value == 0.0 and d.within for d in diffs)
    assert compare_runs.main([str(small_pile_run), str(small_pile_run)]) == 0
    assert "| cap settlement | 0 % |" in capsys.readouterr().out


@pytest.mark.parametrize("small_pile_run", ["viscoplastic"], indirect=True)
def test_differences_beyond_the_bounds_are_found(small_pile_run, tmp_path):
    other = tmp_path / "other"
    shutil.copytree(small_pile_run, other)
    _scale(other / "settlement.csv", "settlement_m", 1.003)  # 0.3 % > 0.2 %
    _scale(other / "pile_loads.csv", "head_force_kN", 1.004)  # 0.4 % < 0.5 %
    _scale(other / "pile_profiles.csv", "axial_force_kN", 1.02)  # 2 % of each value
    diffs = {d.quantity: d for d in compare_runs.compare_runs(small_pile_run, other)}
    assert diffs["cap settlement"].value == pytest.approx(3e-3, rel=1e-6)
    assert not diffs["cap settlement"].within
    assert diffs["pile head force"].value == pytest.approx(4e-3, rel=1e-6)
    assert diffs["pile head force"].within
    assert diffs["centre pile axial force profile"].value == pytest.approx(2e-2, rel=1e-6)
    assert diffs["centre pile friction profile"].value == 0.0
    assert compare_runs.main([str(small_pile_run), str(other)]) == 1


def test_a_missing_folder_is_a_clear_error(tmp_path, capsys):
    assert compare_runs.main([str(tmp_path / "none"), str(tmp_path / "none")]) == 2
    assert "OUT_DIR" in capsys.readouterr().err
