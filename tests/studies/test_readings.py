"""The readings table reads each run folder of a batch as the report does."""

import shutil

import numpy as np
import pytest

from pilegroup.studies.campaigns.readings import readings_table
from pilegroup.studies.results.tables import read_csv


def test_one_row_per_complete_run_with_its_settlements(small_pile_run, tmp_path):
    batch = tmp_path / "batch"
    shutil.copytree(small_pile_run, batch / "case_a")
    (batch / "not_a_run").mkdir()
    table = readings_table(batch, times=(0.5, 2.0, 2.0))
    rows = [r for r in table.splitlines() if r.startswith("| case_a")]
    assert len(rows) == 1 and len(table.splitlines()) == 3
    cells = [c.strip() for c in rows[0].strip("|").split("|")]
    s = read_csv(small_pile_run / "settlement.csv")
    for cell, t in zip(cells[1:4], (0.5, 2.0, 2.0), strict=True):
        want = 1000 * s["settlement_m"][np.isclose(s["t_day"], t)][0]
        assert float(cell) == pytest.approx(want, abs=0.006)
    # the single pile's layers 1-3 friction at 0.5 d: three numbers (or "-" where none)
    assert len(cells[4].split("/")) == 3
