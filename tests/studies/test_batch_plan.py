"""Batch plan files: schema, case names, validation up front, queue order, resume digest."""

import json
from pathlib import Path

import pytest

from pilegroup.errors import ScenarioError
from pilegroup.model import load_scenario
from pilegroup.studies.batch.batch_plan import (
    load_plan,
    queue_order,
    resolve_cases,
    scenario_digest,
)
from pilegroup.studies.batch.rows import csv_text, is_complete

ROOT = Path(__file__).resolve().parents[2]


def _plan(tmp_path, text, name="plan.toml"):
    f = tmp_path / name
    f.write_text(text)
    return f


def test_sweep_is_a_cartesian_product_named_by_value(tmp_path, small_pile):
    f = _plan(tmp_path, '[batch]\nscenario = "small_pile.toml"\nset = {"outputs.xdmf" = false}\n'
              '[sweep]\n"numerics.mesh.size_m" = [1.0, 0.8]\n'
              '"interface.mode" = ["tied", "elastic"]\n'
              '[[case]]\nname = "stiff"\nset = {"layers[0].E_MPa" = 6.0}\n')
    plan = load_plan(f)
    assert plan.name == "plan" and Path(plan.scenario) == Path(small_pile).resolve()
    assert [c.name for c in plan.cases] == [
        "stiff", "size_m=1.0,mode=tied", "size_m=1.0,mode=elastic", "size_m=0.8,mode=tied",
        "size_m=0.8,mode=elastic"]
    assert plan.cases[0].overrides == (("outputs.xdmf", False), ("layers[0].E_MPa", 6.0))
    cases = resolve_cases(plan)
    assert cases[3].scenario.numerics.mesh.size_m == 0.8
    assert cases[3].scenario.interface.mode == "tied"
    assert cases[0].scenario.layers[0].E == pytest.approx(6000.0)  # kPa


def test_sweep_keys_ending_alike_use_the_whole_key(tmp_path):
    f = _plan(tmp_path, '[batch]\nscenario = "single_pile"\n[sweep]\n'
              '"layers[0].E_MPa" = [3.0]\n"layers[1].E_MPa" = [7.7, 9]\n')
    assert [c.name for c in load_plan(f).cases] == [
        "layers_0_.E_MPa=3.0,layers_1_.E_MPa=7.7", "layers_0_.E_MPa=3.0,layers_1_.E_MPa=9"]


@pytest.mark.parametrize("text, key", [
    ('[batch]\nscenario = "single_pile"\n[swep]\n"a" = [1]\n', "plan.swep"),
    ('[batch]\nscenario = "single_pile"\n', "plan = 'no cases'"),
    ('[batch]\nscenario = "nope.toml"\n[[case]]\nname = "a"\n', "batch.scenario"),
    ('[batch]\nscenario = "single_pile"\n[[case]]\nname = "a/b"\n', "case[0].name"),
    ('[batch]\nscenario = "single_pile"\n[[case]]\nname = "batch.csv"\n', "case[0].name"),
    ('[batch]\nscenario = "single_pile"\n[[case]]\nname = "a"\n[[case]]\nname = "a"\n',
     "case name = 'a'"),
    ('[batch]\nscenario = "single_pile"\n[sweep]\n"numerics.mesh.size_m" = 1.0\n',
     "sweep.numerics.mesh.size_m"),
    ('[batch]\nscenario = "single_pile"\nseed = 3\n[[case]]\nname = "a"\n', "batch.seed"),
])
def test_bad_plan_names_the_key(tmp_path, text, key):
    with pytest.raises(ScenarioError) as info:
        load_plan(_plan(tmp_path, text, "bad.toml"))
    assert str(info.value).startswith(f"bad.toml: {key}")
    assert "\n" not in str(info.value)


def test_every_case_is_validated_before_anything_runs(tmp_path):
    f = _plan(tmp_path, '[batch]\nscenario = "single_pile"\n[[case]]\nname = "fine"\n'
              '[[case]]\nname = "wrong"\nset = {"numerics.mesh.size_m" = -1.0}\n')
    with pytest.raises(ScenarioError) as info:
        resolve_cases(load_plan(f))
    assert str(info.value).startswith("case 'wrong': numerics.mesh.size_m = -1.0 (m):")


def test_queue_takes_the_largest_mesh_first(tmp_path):
    f = _plan(tmp_path, '[batch]\nscenario = "single_pile"\n[sweep]\n'
              '"numerics.mesh.n_circ_min" = [16, 64, 32]\n')
    cases = resolve_cases(load_plan(f))
    costs = [c.cost for c in cases]
    assert costs[1] > costs[2] > costs[0]
    assert queue_order(cases) == [1, 2, 0]


def test_resume_needs_the_same_resolved_scenario(tmp_path):
    sc = load_scenario("single_pile")
    other = load_scenario("single_pile", {"numerics.mesh.size_m": 0.6})
    run = tmp_path / "run"
    run.mkdir()
    (run / "scenario.json").write_text(json.dumps(json.loads(json.dumps(
        sc, default=lambda o: o.__dict__)), indent=3))
    assert not is_complete(run, scenario_digest(sc))  # no summary.json
    (run / "summary.json").write_text('{"status": "failed"}')
    assert not is_complete(run, scenario_digest(sc))
    (run / "summary.json").write_text('{"status": "complete", "solver": {"complete": true}}')
    assert is_complete(run, scenario_digest(sc))
    assert not is_complete(run, scenario_digest(other))
    assert scenario_digest(sc) != scenario_digest(other)


def test_csv_has_one_column_per_override_quantity_and_time():
    rows = [{"name": "a", "status": "complete", "overrides": {"x.y": 1.0},
             "output_days": [0.0, 2.0], "settlement_m": [0.0, 0.01],
             "head_force_kN": {"1": [0.0, 50.0]}, "layer_friction_kPa": {"1 mud": [0.0, 3.0]}},
            {"name": "b", "status": "failed", "message": "StepFailure: x", "overrides": {
                "z": [1, 2]}}]
    lines = csv_text(rows).splitlines()
    head = lines[0].split(",")
    assert {"x.y", "z", "settlement_m@2d", "head_force_kN[pile 1]@2d",
            "shaft_friction_kPa[1 mud]@2d"} <= set(head)
    a = dict(zip(head, lines[1].split(","), strict=True))
    assert a["settlement_m@2d"] == "0.01" and a["head_force_kN[pile 1]@2d"] == "50.0"
    assert lines[2].startswith("b,failed,,StepFailure: x")


def test_example_plan_in_docs_is_valid():
    plan = load_plan(ROOT / "docs" / "examples" / "single_pile_sizes.toml")
    assert len(resolve_cases(plan)) == 7
