"""A scenario with a Soft Soil Creep layer over a Modified Cam Clay layer runs through
``pilegroup run``, and its settlement keeps growing under a constant load after primary
consolidation (docs/model.md, "Soil models per layer").

The small single-pile scenario (``pilegroup.studies.bench.small_pile``) to 100 days, both
layers permeable enough (1 m/day) that primary consolidation is over within a few days. The
same run with the upper layer in Modified Cam Clay of the same compressibility, which does not
creep, shows that it is: its settlement stops.
"""

import csv
import math
import tomllib
from types import SimpleNamespace

import numpy as np
import pytest

from pilegroup.constitutive.cam_clay import ModifiedCamClay
from pilegroup.constitutive.critical_state import k0_stress
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep
from pilegroup.constitutive.soil import LinearElastic
from pilegroup.model.loader import apply_overrides, parse_override, scenario_from_dict
from pilegroup.solver import SoilMaterial
from pilegroup.solver.forms import representative_moduli
from pilegroup.studies.bench.small_pile import small_pile_text
from pilegroup.studies.cli.commands import main
from pilegroup.studies.run.pipeline import soil_law

#: Both layers: long enough to see creep, permeable, the lower one Modified Cam Clay.
COMMON = {"time.end_day": "100.0", "time.output_days": "[0.0, 0.5, 2.0, 10.0, 30.0, 100.0]",
          "layers[0].k_m_per_day": "1.0", "layers[1].k_m_per_day": "1.0",
          "layers[0].phi_deg": "25.0", "layers[0].OCR": "1.2",
          "layers[1].model": '"modified_cam_clay"', "layers[1].lam": "0.15",
          "layers[1].kappa": "0.03", "layers[1].phi_cs_deg": "28.0", "layers[1].OCR": "1.5"}
#: The upper layer (mud, 8 m) in Soft Soil Creep ...
SSC = {"layers[0].model": '"soft_soil_creep"', "layers[0].lambda_star": "0.1",
       "layers[0].kappa_star": "0.02", "layers[0].mu_star": "0.004"}
#: ... or in Modified Cam Clay of the same compressibility (lambda = lambda* (1 + e0), e0 1.2).
MCC = {"layers[0].model": '"modified_cam_clay"', "layers[0].lam": "0.22",
       "layers[0].kappa": "0.044", "layers[0].phi_cs_deg": "25.0"}


def _run(tmp_path, name, sets):
    path = tmp_path / "small.toml"
    path.write_text(small_pile_text())
    out = tmp_path / name
    argv = ["run", str(path), "--out", str(out)]
    argv += [a for k, v in {**COMMON, **sets}.items() for a in ("--set", f"{k}={v}")]
    assert main(argv) == 0
    with open(out / "settlement.csv") as f:
        return {float(r["t_day"]): float(r["settlement_m"]) for r in csv.DictReader(f)}


@pytest.fixture(autouse=True)
def _quiet(monkeypatch, tmp_path):
    monkeypatch.setenv("PILEGROUP_PROGRESS", "0")
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))


def test_soft_soil_creep_keeps_settling_after_primary_consolidation(tmp_path):
    ssc = _run(tmp_path, "ssc", SSC)
    mcc = _run(tmp_path, "mcc", MCC)
    # primary consolidation is over by day 10: without creep the settlement stops there
    assert abs(mcc[100.0] - mcc[10.0]) < 1e-6
    # with creep it keeps growing, at an increasing rate per day over log-spaced times
    # (measured 2026-11-28: 26.69, 27.08, 28.74 mm at 10, 30 and 100 days; serial = 2 ranks)
    assert ssc[30.0] - ssc[10.0] > 2e-4
    assert ssc[100.0] - ssc[30.0] > 1e-3
    assert ssc[100.0] - ssc[30.0] > 100.0 * abs(mcc[100.0] - mcc[30.0])


def _scenario(sets):
    doc = tomllib.loads(small_pile_text())
    return scenario_from_dict(apply_overrides(doc, dict(
        parse_override(f"{k}={v}") for k, v in {**COMMON, **sets}.items())))


def test_the_layers_become_their_laws():
    sc = _scenario(SSC)
    ssc, mcc = soil_law(sc, 0), soil_law(sc, 1)
    assert isinstance(ssc, SoftSoilCreep) and isinstance(mcc, ModifiedCamClay)
    assert (ssc.lambda_star, ssc.kappa_star, ssc.mu_star, ssc.phi_deg) == (0.1, 0.02, 0.004, 25.0)
    assert (ssc.OCR, ssc.POP, ssc.nu_ur, ssc.tau) == (1.2, 0.0, 0.15, 1.0)
    assert (mcc.lam, mcc.kappa, mcc.e0, mcc.phi_cs_deg, mcc.nu, mcc.OCR) == (
        0.15, 0.03, 0.8, 28.0, 0.35, 1.5)
    # the law's K0nc is the layer's K0 at rest without OCR: a normally consolidated point at
    # rest starts on its yield surface
    lay = sc.layers[1]
    assert math.isclose(mcc.k0nc(), 1 - math.sin(math.radians(28.0)), rel_tol=1e-12)
    nc = ModifiedCamClay(0.15, 0.03, 0.8, phi_cs_deg=28.0, nu=0.35, K0nc=mcc.K0nc)
    s0 = k0_stress(np.array([40.0, 90.0]), mcc.K0nc)
    state = nc.initial_state(2, s0)
    assert np.allclose(nc.yield_function(s0, state["pc"]), 0.0, atol=1e-9 * 90.0**2)
    assert math.isclose(lay.k0, mcc.K0nc * 1.5 ** math.sin(math.radians(28.0)), rel_tol=1e-12)


def test_representative_moduli_at_the_layer_mid_depth():
    law = SoftSoilCreep(0.1, 0.02, 0.004, 25.0)
    mat = SoilMaterial(law, k_m_per_day=1e-3, porosity=0.5, gamma_sat=17.0, K0=0.6)
    layer = SimpleNamespace(z_min=-10.0, z_max=-2.0, k0=0.6)
    column = SimpleNamespace(by_name={"l": layer}, z_top=0.0,
                             sigma_v=lambda z: -7.0 * -np.asarray(z))  # 7 kN/m^3 buoyant
    K, G = representative_moduli(mat, column, "l")
    p = (1 + 2 * 0.6) / 3 * 7.0 * 6.0  # at 6 m, the layer's mid-depth
    assert math.isclose(K, p / 0.02, rel_tol=1e-12)
    assert math.isclose(G, 1.5 * K * (1 - 0.3) / 1.15, rel_tol=1e-12)
    # a law of constant moduli: its own, whatever the stress
    el = SoilMaterial(LinearElastic(1e4, 0.25), k_m_per_day=1e-3, porosity=0.5)
    assert representative_moduli(el, column, "l") == el.elastic_moduli()
