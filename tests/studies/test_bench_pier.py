"""``pilegroup bench pier`` with several scenarios: one row each, the wall-time ratio to the first.

The runs are replaced by a stub (a finished process with a given wall time and no summary), so
the test checks the table's bookkeeping, not the runs (docs/benchmarks.md has those).
"""

from __future__ import annotations

import json

import pytest

from pilegroup.studies.bench import pier_bench
from pilegroup.studies.bench.benchrun import Finished
from pilegroup.studies.cli.commands import EXIT_INPUT, main


def test_several_scenarios_are_compared_within_one_run(tmp_path, monkeypatch):
    walls = {"pier667": 40.0, "pier667_soft_soil": 60.0}
    commands = []

    def fake_run(cmd, timeout):
        commands.append(cmd)
        return Finished(1, "", "stub", walls[cmd[cmd.index("run") + 1]])

    monkeypatch.setattr(pier_bench, "run_isolated", fake_run)
    rows = pier_bench.bench_pier(["pier667", "pier667_soft_soil"], out_dir=tmp_path)
    assert [r["scenario"] for r in rows] == ["pier667", "pier667_soft_soil"]
    assert [r["wall_ratio"] for r in rows] == [1.0, 1.5]
    assert len({c[c.index("--out") + 1] for c in commands}) == 2  # a folder each
    table = json.loads((tmp_path / "bench_pier.json").read_text())
    assert "pier667_soft_soil" in json.dumps(table)
    assert "wall_ratio" in (tmp_path / "bench_pier.md").read_text()


def test_other_benchmarks_take_one_scenario(capsys):
    assert main(["bench", "floors", "--scenario", "pier667", "single_pile"]) == EXIT_INPUT
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "--scenario" in err and "bench pier" in err


@pytest.mark.parametrize("what", ["presets"])
def test_one_scenario_still_a_string(what, monkeypatch):
    seen = {}

    def fake(presets, scenario, *a, **k):
        seen["scenario"] = scenario
        return [{"status": "complete"}]

    import pilegroup.studies.bench.preset_bench as pb
    monkeypatch.setattr(pb, "bench_presets", fake)
    assert main(["bench", what, "--scenario", "single_pile", "--presets", "direct"]) == 0
    assert seen["scenario"] == "single_pile"


def test_presets_default_and_floors_takes_one_preset(monkeypatch, capsys):
    """``bench presets`` compares its default presets unless told; ``bench floors`` measures one
    field-split preset: two are refused in one line, before anything is built."""
    seen = {}

    def fake(presets, scenario, *a, **k):
        seen["presets"] = presets
        return [{"status": "complete"}]

    import pilegroup.studies.bench.preset_bench as pb
    monkeypatch.setattr(pb, "bench_presets", fake)
    assert main(["bench", "presets", "--scenario", "single_pile"]) == 0
    assert seen["presets"] == ["direct_reuse", "fieldsplit_kept"]
    two = ["fieldsplit_pier", "fieldsplit_kept"]
    assert main(["bench", "floors", "--presets", *two]) == EXIT_INPUT
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1
    assert "bench floors --presets = 'fieldsplit_pier fieldsplit_kept'" in err
