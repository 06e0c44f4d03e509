"""The readings table reads each run folder of a batch as the report does."""

import json
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
    # friction of the soft layers of the scenario's [reference]: the single pile has none
    assert cells[4] == "-"


def test_the_soft_layers_are_those_of_the_reference(small_pile_run, tmp_path):
    batch = tmp_path / "batch"
    shutil.copytree(small_pile_run, batch / "case_a")
    path = batch / "case_a" / "scenario.json"
    sc = json.loads(path.read_text())
    sc["reference"] = {"source": "a test", "soft_layers": [1, 2]}
    path.write_text(json.dumps(sc))
    row = next(r for r in readings_table(batch, times=(0.5, 2.0, 2.0)).splitlines()
               if r.startswith("| case_a"))
    cells = [c.strip() for c in row.strip("|").split("|")]
    assert len(cells[4].split("/")) == 2  # layers 1 and 2 at 0.5 d
