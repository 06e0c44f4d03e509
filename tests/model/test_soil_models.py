"""A layer's soil model and its critical-state keys (model/soil_models.py, docs/model.md,
"Soil models per layer"): the default, K0 at rest, the keys' reference, the refusals.

The one-line refusals of ``pilegroup scenario validate`` (lambda* <= kappa*, OCR < 1, a
negative mu*, ...) are cases of tests/model/test_refusals_at_validation.py.
"""

import math

import pytest

from pilegroup.errors import ScenarioError
from pilegroup.model import keys, load_scenario
from pilegroup.model.soil_models import friction_for_k0, k0nc, layer_model

SSC = {"layers[0].model": "soft_soil_creep", "layers[0].lambda_star": 0.1,
       "layers[0].kappa_star": 0.02, "layers[0].mu_star": 0.004, "layers[0].phi_deg": 25.0}
MCC = {"layers[1].model": "modified_cam_clay", "layers[1].lam": 0.15, "layers[1].kappa": 0.03,
       "layers[1].M": 1.2}


def test_a_layer_takes_its_own_model_else_the_scenario_s():
    sc = load_scenario("single_pile", {**SSC, **MCC})
    assert [layer_model(lay, sc.soil) for lay in sc.layers] == ["soft_soil_creep",
                                                                "modified_cam_clay"]
    plain = load_scenario("single_pile")
    assert [layer_model(lay, plain.soil) for lay in plain.layers] == ["mohr_coulomb"] * 2
    assert plain.layers[0].nu_ur == 0.15 and plain.layers[0].tau_ref_day == 1.0


def test_k0_at_rest_of_cam_clay_is_jaky_of_phi_cs_with_ocr():
    sc = load_scenario("single_pile", {**MCC, "layers[1].OCR": 2.0})
    lay = sc.layers[1]
    s = 3 * 1.2 / (6 + 1.2)  # sin phi_cs of M = 1.2 (triaxial compression)
    assert math.isclose(math.sin(math.radians(friction_for_k0(lay))), s, rel_tol=1e-12)
    assert math.isclose(k0nc(lay), 1 - s, rel_tol=1e-12)
    assert math.isclose(lay.k0, (1 - s) * 2.0**s, rel_tol=1e-12)  # Mayne & Kulhawy
    # Soft Soil Creep: phi_deg, as for the other models
    ssc = load_scenario("single_pile", SSC).layers[0]
    assert math.isclose(ssc.k0, 1 - math.sin(math.radians(25.0)), rel_tol=1e-12)


def test_ocr_without_phi_deg_is_fine_with_a_critical_state_angle():
    doc = {**MCC, "layers[1].OCR": 1.5, "layers[1].phi_cs_deg": 30.0}
    del doc["layers[1].M"]
    sc = load_scenario("single_pile", doc)
    assert math.isclose(sc.layers[1].k0, (1 - 0.5) * 1.5**0.5, rel_tol=1e-12)


@pytest.mark.parametrize(("sets", "fragment"), [
    ({**SSC, "layers[0].kappa_star": 0.1}, "layers[0].kappa_star (layer 1) = 0.1 (-): must be <"
                                            " lambda_star = 0.1"),
    ({**SSC, "layers[0].mu_star": 0.0}, "layers[0].mu_star (layer 1) = 0.0 (-): must be in (0,"),
    ({**SSC, "layers[0].tau_ref_day": 0.0}, "layers[0].tau_ref_day (layer 1) = 0.0 (day)"),
    ({**SSC, "layers[0].nu_ur": 0.5}, "layers[0].nu_ur (layer 1) = 0.5 (-): must be in (0, 0.5)"),
    ({**MCC, "layers[1].phi_cs_deg": 30.0}, "give either M or phi_cs_deg, not both"),
    ({**MCC, "layers[1].lam": None}, "layers[1].lam (layer 2) = None: missing key"),
    ({"soil.model": "soft_soil_creep"}, "layers[0].lambda_star (layer 1) = None: missing key"),
])
def test_refusals_name_the_key(sets, fragment):
    sets = {k: v for k, v in sets.items() if v is not None}
    with pytest.raises(ScenarioError) as exc:
        load_scenario("single_pile", sets)
    assert fragment in str(exc.value) and "\n" not in str(exc.value)


def test_the_keys_reference_gives_units_and_users():
    by_path = {k.path: k for k in keys.keys()}
    assert by_path["layers.POP_kPa"].unit == "kPa"
    assert by_path["layers.tau_ref_day"].unit == "day"
    assert by_path["layers.phi_cs_deg"].unit == "degree"
    assert by_path["layers.lambda_star"].unit == "-"
    assert "soft_soil_creep" in by_path["layers.mu_star"].used_by
    assert "modified_cam_clay" in by_path["layers.lam"].used_by
    assert "soft_soil_creep" in by_path["layers.phi_deg"].used_by
    assert '"soft_soil_creep"' in by_path["layers.model"].allowed
    for name in ("lam", "kappa", "M", "phi_cs_deg", "POP_kPa", "lambda_star", "kappa_star",
                 "mu_star", "nu_ur", "tau_ref_day", "model"):
        assert by_path[f"layers.{name}"].meaning
