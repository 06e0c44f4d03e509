"""Load combinations: the file's schema and errors, the arithmetic, and the command end to end."""

import csv
import os
import subprocess
import sys
from pathlib import Path

import pytest

from pilegroup.errors import ScenarioError
from pilegroup.studies.batch.batch_plan import resolve_cases
from pilegroup.studies.batch.combination_plan import (
    Combination,
    CombinationPlan,
    combination_plan_from_dict,
    load_combination_plan,
)
from pilegroup.studies.cli.commands import main

ROOT = Path(__file__).resolve().parents[2]
BIN = Path(sys.executable).parent
HEAD = '[combinations]\nscenario = "single_pile"\nstage = "loading"\n'
CASES = ('[load_cases.permanent]\ncap_load_kN = 400.0\n'
         '[load_cases.traffic]\nFz_kN = -100.0\n')
SLS = '[[combination]]\nname = "SLS"\nfactors = { permanent = 1.0, traffic = 1.0 }\n'
ULS = '[[combination]]\nname = "ULS"\nfactors = { permanent = 1.35, traffic = 1.5 }\n'


def _file(tmp_path, text, name="combos.toml"):
    f = tmp_path / name
    f.write_text(text)
    return f


def test_combinations_are_batch_cases_with_the_stage_load_set(tmp_path):
    f = _file(tmp_path, HEAD + 'set = { "outputs.xdmf" = false }\n' + CASES + SLS + ULS)
    plan = load_combination_plan(f)
    assert plan.name == "combos" and plan.stage_index == 1 and plan.vertical_key == "cap_load_kN"
    batch = plan.batch_plan()
    assert [c.name for c in batch.cases] == ["SLS", "ULS"]
    assert batch.cases[0].overrides == (("outputs.xdmf", False),
                                        ("stages[1].cap_load_kN", 500.0))
    assert batch.cases[1].override_dict()["stages[1].cap_load_kN"] == 690.0  # tidied
    scenarios = [rc.scenario for rc in resolve_cases(batch)]
    assert [sc.stages[1].cap_load_kN for sc in scenarios] == [500.0, 690.0]
    assert plan.actions(plan.combinations[1]) == {
        "Fx_kN": 0.0, "Fy_kN": 0.0, "Fz_kN": -690.0, "Mx_kNm": 0.0, "My_kNm": 0.0, "Mz_kNm": 0.0}


def test_horizontal_actions_pass_through_as_stage_keys(tmp_path):
    data = {"combinations": {"scenario": "single_pile", "stage": "loading"},
            "load_cases": {"permanent": {"cap_load_kN": 400.0},
                           "braking": {"Fx_kN": 50.0, "My_kNm": 20.0},
                           "wind": {"Fy_kN": -30.0, "Mz_kNm": 5.0}},
            "combination": [{"name": "ULS_braking", "factors": {"permanent": 1.35,
                                                                 "braking": 1.5}}]}
    plan = combination_plan_from_dict(data)
    c = plan.combinations[0]
    # every component a case gives is set, 0 where this combination's cases do not give it
    assert plan.stage_values(c) == {"Fx_kN": 75.0, "Fy_kN": 0.0, "cap_load_kN": 540.0,
                                    "My_kNm": 30.0, "Mz_kNm": 0.0}
    assert ("stages[1].Fx_kN", 75.0) in plan.overrides(c)


def test_the_vertical_goes_back_the_way_the_base_stage_gives_it():
    cases = {"permanent": {"Fz_kN": -400.0}, "uplift": {"Fz_kN": 150.0}}
    both = Combination("both", (("permanent", 1.0), ("uplift", 1.0)))
    plan = CombinationPlan("single_pile", "loading", 1, "Fz_kN", ("Mx_kNm",), (), cases, (both,))
    # a component the base stage gives and no case does is 0: the combination replaces it
    assert plan.stage_values(both) == {"Fz_kN": -250.0, "Mx_kNm": 0.0}


def test_an_upward_combination_names_the_combination(tmp_path):
    f = _file(tmp_path, HEAD + CASES + '[load_cases.uplift]\nFz_kN = 600.0\n'
              '[[combination]]\nname = "lift"\nfactors = { permanent = 1.0, uplift = 1.0 }\n')
    with pytest.raises(ScenarioError) as info:
        load_combination_plan(f)
    assert str(info.value).startswith("combos.toml: combination 'lift': cap_load_kN = -200.0 (kN)")
    assert "upward (Fz_kN = 200)" in str(info.value)


@pytest.mark.parametrize("text, key", [
    (HEAD + CASES + SLS + "[extra]\n", "file.extra"),
    (HEAD + "seed = 1\n" + CASES + SLS, "combinations.seed"),
    (HEAD.replace("single_pile", "nope.toml") + CASES + SLS, "combinations.scenario"),
    (HEAD.replace("loading", "consolidation") + CASES + SLS, "combinations.stage"),
    (HEAD.replace("loading", "unloading") + CASES + SLS, "combinations.stage"),
    (HEAD + SLS, "load_cases"),
    (HEAD + '[load_cases.a]\nFx = 1.0\n' + SLS, "load_cases.a.Fx"),
    (HEAD + '[load_cases.a]\ncap_load_kN = 1.0\nFz_kN = -1.0\n', "load_cases.a.cap_load_kN"),
    (HEAD + '[load_cases.a]\nFx_kN = "big"\n', "load_cases.a.Fx_kN"),
    (HEAD + '[load_cases.a]\nMx_kNm = true\n', "load_cases.a.Mx_kNm"),
    (HEAD + '[load_cases.a]\n', "load_cases.a"),
    (HEAD + CASES, "combination"),
    (HEAD + CASES + SLS.replace("traffic =", "wind ="), "combination[0].factors.wind"),
    (HEAD + CASES + SLS.replace("1.0, traffic = 1.0", "'x'"), "combination[0].factors.permanent"),
    (HEAD + CASES + '[[combination]]\nname = "a"\nfactors = {}\n', "combination[0].factors"),
    (HEAD + CASES + SLS.replace('"SLS"', '"envelope.csv"'), "combination[0].name"),
    (HEAD + CASES + SLS.replace('"SLS"', '"a/b"'), "combination[0].name"),
    (HEAD + CASES + SLS + SLS, "combination name = 'SLS'"),
    (HEAD + 'set = { "layers[0].E_MPa" = -1.0 }\n' + CASES + SLS,
     "base scenario: layers[0].E_MPa"),
    (HEAD + CASES + SLS.replace("1.0, traffic", "1e7, traffic"),
     "combination 'SLS': stages[1].cap_load_kN"),
])
def test_a_bad_file_names_the_file_and_the_key(tmp_path, text, key):
    with pytest.raises(ScenarioError) as info:
        load_combination_plan(_file(tmp_path, text))
    assert str(info.value).startswith(f"combos.toml: {key}"), str(info.value)
    assert "\n" not in str(info.value)


def test_the_command_exits_2_with_one_line(tmp_path, capsys):
    f = _file(tmp_path, HEAD + CASES + SLS.replace("traffic =", "wind ="))
    assert main(["combinations", str(f), "--out", str(tmp_path / "out"), "--no-progress"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("pilegroup: invalid input: combos.toml: combination[0].factors.wind")
    assert len(err.splitlines()) == 1 and not (tmp_path / "out").exists()


def test_example_file_in_docs_is_valid():
    plan = load_combination_plan(ROOT / "docs" / "examples" / "single_pile_combinations.toml")
    assert len(resolve_cases(plan.batch_plan())) == 3


def _rows(path):
    with path.open(newline="") as fh:
        return list(csv.DictReader(fh))


#: A combination the small pile cannot carry: the run fails (settles more than its diameter).
COLLAPSE = '[[combination]]\nname = "collapse"\nfactors = { permanent = 50.0 }\n'
#: a horizontal case at the pile head, and the ULS combination with it
BRAKING = '[load_cases.braking]\nFx_kN = 20.0\nMy_kNm = 10.0\n'
ULS_LATERAL = ('[[combination]]\nname = "ULS"\n'
               'factors = { permanent = 1.35, traffic = 1.5, braking = 1.5 }\n')


@pytest.mark.mpi
def test_combinations_run_on_two_ranks_and_give_the_envelope(tmp_path, small_pile):
    f = _file(Path(small_pile).parent, HEAD.replace('"single_pile"', '"small_pile.toml"')
              + 'set = { "outputs.xdmf" = false, "outputs.plots" = false }\n' + CASES + BRAKING
              + SLS + ULS_LATERAL + COLLAPSE)
    out = tmp_path / "out"
    cmd = [str(BIN / "mpirun"), "-n", "2", str(BIN / "pilegroup"), "combinations", str(f),
           "--out", str(out), "--no-progress"]
    env = {**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 1, r.stderr[-3000:]  # a combination failed, the others complete
    assert "collapse: failed" in r.stdout and "combinations: " in r.stdout
    rows = {(e["quantity"], e["pile"], e["time"]): e for e in _rows(out / "envelope.csv")}
    n = rows[("N_kN", "", "last")]
    assert n["max_combination"] == "ULS" and n["min_combination"] == "SLS"
    assert n["max_pile"] == "1" and float(n["max_t_day"]) == 2.0
    assert float(n["max"]) == pytest.approx(690.0, rel=0.02)  # the one pile carries the cap
    assert float(n["min"]) == pytest.approx(500.0, rel=0.02)
    w = rows[("settlement_m", "", "last")]
    assert w["max_combination"] == "ULS" and float(w["max"]) > float(w["min"]) > 0.0
    assert w["combinations"] == "2" and w["excluded"] == "collapse (failed)"
    # quantities of files these runs do not write are empty, and say why
    # the braking case: the head shear of the one pile is 1.5 x 20 kN, and ULS bends it most
    v = rows[("V_kN", "", "last")]
    assert v["max_combination"] == "ULS" and float(v["max"]) == pytest.approx(30.0, rel=1e-3)
    m = rows[("M_max_kNm", "", "all")]
    # at least the head's 15 kNm, to the solver's precision (the head's is the largest here:
    # 14.9999999 and 15.0000000 have both been computed)
    assert m["max_combination"] == "ULS" and float(m["max"]) >= 15.0 * (1.0 - 1e-6)
    assert m["excluded"] == "collapse (failed)"
    for q in ("ux_m", "ry_rad"):
        assert rows[(q, "", "last")]["max_combination"] == "ULS"
        assert float(rows[(q, "", "last")]["max"]) > 0.0
    md = (out / "envelope.md").read_text()
    assert f"| `N_kN` | kN | last | {float(n['max']):.4g} | `ULS` | 1 |" in md
    assert "Not in the envelope (did not complete): `collapse` (failed: " in md
    results = _rows(out / "combination_results.csv")
    assert {r["combination"] for r in results} == {"SLS", "ULS", "collapse"}
    collapse = [r for r in results if r["combination"] == "collapse"]
    assert len(collapse) == 1 and "exceeds the pile diameter" in collapse[0]["note"]
    # again: both complete, skipped, the envelope written again
    (out / "envelope.csv").unlink()
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300, env=env)
    assert r.returncode == 1 and r.stdout.count("complete before, skipped") == 2
    assert (out / "envelope.csv").is_file()
