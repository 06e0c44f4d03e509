"""Scenario keys of ground that moves: surcharge and groundwater stages, consolidating layers."""

import copy
import tomllib

import pytest

from pilegroup.model import ScenarioError, bundled_text, scenario_from_dict
from pilegroup.studies.cli.commands import EXIT_INPUT, main
from pilegroup.studies.run.pipeline import ground_drainage, solver_stages, surcharge_loads

BASE = tomllib.loads(bundled_text("pier667"))
FILL = {"name": "fill", "kind": "surcharge", "surcharge_kPa": 40.0, "duration_day": 10.0}
PUMP = {"name": "pumping", "kind": "groundwater", "drawdown_m": 2.0, "duration_day": 5.0}


def _with(stages=(), **layer1):
    data = copy.deepcopy(BASE)
    data["stages"][1:1] = [dict(s) for s in stages]
    data["layers"][1].update(layer1)
    return data


def test_ground_stages_map_onto_ground_actions():
    embankment = dict(FILL, name="embankment", area_m=[10.0, 30.0, -20.0, 20.0])
    sc = scenario_from_dict(_with([FILL, PUMP, embankment], excess_pore_pressure_ratio=0.3))
    times = {st.name: (a, b) for st, a, b in sc.stage_times()}
    assert times["fill"] == (0.0, 10.0) and times["pumping"] == (10.0, 15.0)
    assert times["embankment"] == (15.0, 25.0)
    stages = {s.name: s for s in solver_stages(sc)}
    assert stages["fill"].kind == "ground" and stages["fill"].ground == (1.0, 0.0, 0.0)
    assert stages["pumping"].ground == (1.0, 0.0, 2.0)  # drawdown so far (m), last action
    assert stages["embankment"].ground == (1.0, 1.0, 2.0)
    loads = surcharge_loads(sc)
    assert loads[0].area is None and loads[1].area == (10.0, 30.0, -20.0, 20.0)
    assert [ld.action for ld in loads] == [0, 1]
    assert ground_drainage(sc).action == 2 and ground_drainage(sc).value == pytest.approx(-9.81)
    assert sc.layers[1].excess_pore_pressure_ratio == 0.3


@pytest.mark.parametrize(("stage", "layer", "key", "words"), [
    (dict(FILL, duration_day=None), {}, "duration_day", "required for a surcharge stage"),
    ({"name": "f", "kind": "surcharge", "duration_day": 1.0}, {}, "surcharge_kPa", "required"),
    (dict(FILL, surcharge_kPa=0.0), {}, "surcharge_kPa", "non-zero"),
    (dict(FILL, surcharge_kPa=5000.0), {}, "surcharge_kPa", "1000"),
    (dict(FILL, drawdown_m=1.0), {}, "drawdown_m", "only for groundwater"),
    (dict(PUMP, surcharge_kPa=1.0), {}, "surcharge_kPa", "only for surcharge"),
    (dict(FILL, area_m=[5.0, 1.0, 0.0, 1.0]), {}, "area_m", "x_min < x_max"),
    (dict(FILL, area_m=[0.0, 500.0, 0.0, 1.0]), {}, "area_m", "ground surface"),
    (dict(FILL, duration_day=400.0), {}, "time.end_day", "surcharge stage 'fill'"),
    (FILL, {"excess_pore_pressure_ratio": 1.0}, "excess_pore_pressure_ratio", "1"),
    (FILL, {"excess_pore_pressure_ratio": 0.2, "excess_pore_pressure_kPa": 5.0},
     "excess_pore_pressure_kPa", "not both"),
    (FILL, {"excess_pore_pressure_kPa": 500.0}, "excess_pore_pressure_kPa",
     "vertical effective stress at the layer's top"),
])
def test_bad_ground_keys_name_key_value_and_rule(stage, layer, key, words):
    data = _with([{k: v for k, v in stage.items() if v is not None}], **layer)
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(data)
    assert key in err.value.key and words in str(err.value)


def test_cli_rejects_a_bad_ground_key_with_one_line(tmp_path, capsys):
    text = bundled_text("pier667").replace(
        '[[stages]]\nname = "loading"',
        '[[stages]]\nname = "fill"\nkind = "surcharge"\nsurcharge_kPa = "lots"\n'
        'duration_day = 1.0\n\n[[stages]]\nname = "loading"', 1)
    assert "lots" in text
    f = tmp_path / "s.toml"
    f.write_text(text)
    assert main(["scenario", "validate", str(f)]) == EXIT_INPUT
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "surcharge_kPa" in err and "lots" in err


def test_symmetry_follows_the_surcharge_area():
    from pilegroup.geometry.adapter import resolve_geometry

    site_wide = scenario_from_dict(_with([FILL]))
    assert resolve_geometry(site_wide).symmetry == "quarter"
    beside = dict(FILL, area_m=[10.0, 30.0, -20.0, 20.0])  # an embankment east of the pier
    geo = resolve_geometry(scenario_from_dict(_with([beside])))
    assert geo.symmetry == "half_y"
    assert "surcharge stage 'fill' spans x = 10 .. 30 m" in geo.reason
    data = _with([beside])
    data.setdefault("numerics", {})["symmetry"] = "quarter"
    with pytest.raises(ScenarioError, match="cuts at x = 0, but the load is not mirror"):
        resolve_geometry(scenario_from_dict(data))


INSTALL = {"name": "piles", "kind": "installation"}


def _later(**time):
    """Pier 667 with a fill from day -100 and the piles installed at day 0, then its load."""
    data = copy.deepcopy(BASE)
    data["stages"] = [data["stages"][0], dict(FILL), {"name": "settling",
                                                      "kind": "consolidation", "until_day": 0.0},
                      INSTALL, *data["stages"][1:]]
    data["time"].update({"start_day": -100.0, **time})
    return data


def test_piles_installed_into_moving_ground_map_onto_solver_stages():
    sc = scenario_from_dict(_later())
    times = {st.name: (a, b) for st, a, b in sc.stage_times()}
    assert times["geostatic"] == (-100.0, -100.0) and times["fill"] == (-100.0, -90.0)
    assert times["settling"] == (-90.0, 0.0) and times["piles"] == (0.0, 0.0)
    kinds = [s.kind for s in solver_stages(sc)]
    assert kinds[:4] == ["geostatic", "ground", "consolidation", "install"]
    assert [s.duration for s in solver_stages(sc)][:4] == [0.0, 10.0, 90.0, 0.0]


@pytest.mark.parametrize(("change", "key", "words"), [
    (lambda d: d["time"].update(start_day=5.0), "time.start_day", "[-100000, 0]"),
    (lambda d: d["time"].update(output_days=[-200.0, 0.0]), "output_days[0]",
     "start_day = -100"),
    (lambda d: d["stages"].insert(1, {"name": "early", "kind": "load", "cap_load_kN": 1.0,
                                      "duration_day": 1.0}),
     "stages[1].kind", "before the piles exist"),
    (lambda d: d["stages"].append(dict(INSTALL, name="again")), "kind",
     "installed once"),
    (lambda d: d["interface"].update(mode="tied"), "interface.mode", "installation stage"),
])
def test_bad_order_of_events_names_key_value_and_rule(change, key, words):
    data = _later()
    change(data)
    with pytest.raises(ScenarioError) as err:
        scenario_from_dict(data)
    assert key in err.value.key and words in str(err.value)
