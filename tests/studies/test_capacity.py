"""A load far beyond capacity stops cleanly: no equilibrium beyond the load reached, the
load-settlement curve written and plotted, a failed summary, exit code 1, on 1 and 2 ranks.

Slow tier: the run goes on until the settlement runs away (about 3 min on 2 cores).
"""

import csv
import json
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent


@pytest.mark.slow
@pytest.mark.parametrize("ranks", [1, pytest.param(2, marks=pytest.mark.mpi)])
def test_load_beyond_capacity_stops_cleanly(tmp_path, small_pile_source, ranks):
    text = small_pile_source.replace("cap_load_kN = 500.0", "cap_load_kN = 200000.0")
    assert "200000.0" in text
    f = tmp_path / "overload.toml"
    f.write_text(text)
    out = tmp_path / "run"
    cmd = [str(BIN / "pilegroup"), "run", str(f), "--out", str(out)]
    if ranks > 1:
        cmd = [str(BIN / "mpirun"), "-n", str(ranks), *cmd]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600,
                       env={**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")})
    assert r.returncode == 1, r.stderr[-3000:]
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert len(lines) == 1 and "no equilibrium beyond load factor" in lines[0], r.stderr[-3000:]
    assert "Traceback" not in r.stderr
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "failed" and "no equilibrium beyond load factor" in s["reason"]
    with (out / "load_settlement.csv").open() as fh:
        rows = list(csv.DictReader(fh))
    loads = [float(row["load_kN"]) for row in rows]
    assert len(rows) >= 2 and loads[0] == 0.0 and loads == sorted(loads)
    reached = float(re.search(r"\(([0-9.e+]+) kN\)", s["reason"]).group(1))
    assert loads[-1] == pytest.approx(reached, rel=1e-5)  # the curve ends where it stopped
    assert (out / "plots" / "load_settlement.png").stat().st_size > 0
