"""``pilegroup lab`` and ``pilegroup fit oedometer`` with Modified Cam Clay and Soft Soil Creep.

Closed forms (docs/lab.md): Cam Clay's undrained path from an isotropic normally consolidated
state, ``p'/p'0 = (M^2/(M^2 + eta^2))^Lambda`` (Wood 1990), within 1 %; Soft Soil Creep's
creep stage against ``mu* ln(1 + t/tau_c)`` (Vermeer & Neher 1999; the closed form of
``studies/verification/soft_soil_cases.py``), within 2 % of the stage's creep (measured 1.3 %:
the backward-Euler lag at 20 steps per decade). Round trip: a lab oedometer of known
parameters with 2 % multiplicative noise (seeded) fitted back within 5 %.
"""

import csv
import json

import numpy as np
import pytest

from pilegroup.constitutive.cam_clay import ModifiedCamClay, mcc_undrained_path
from pilegroup.constitutive.soft_soil_creep import SoftSoilCreep, ssc_creep_strain
from pilegroup.studies.cli.commands import build_parser, main
from pilegroup.studies.lab.lab_tables import COLUMNS, read_lab_table

MCC = {"lam": 0.25, "kappa": 0.05, "M": 1.0, "nu": 0.25, "e0": 1.5}
SSC = {"lambda_star": 0.1, "kappa_star": 0.02, "mu_star": 0.004, "phi_deg": 25.0, "e0": 1.2}
#: A short oedometer: 25 -> 200 kPa, the creep stage, back to 25 kPa.
SHORT = ["--oedometer-start-kPa", "25", "--oedometer-max-kPa", "200", "--creep-days", "10"]


def _args(model, values):
    return ["--soil_model", model] + [a for k, v in values.items() for a in (f"--{k}", str(v))]


def _lab(test, model, values, out, *extra):
    assert main(["lab", test, *_args(model, values), "--out", str(out), *extra]) == 0
    return read_lab_table(out / f"{test}.csv", COLUMNS[test])


def _one_error_line(capsys, *words):
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    for w in words:
        assert w in err, (w, err)


def test_fit_oedometer_has_help(capsys):
    with pytest.raises(SystemExit) as info:
        build_parser().parse_args(["fit", "oedometer", "--help"])
    assert info.value.code == 0
    assert "--substeps-per-decade" in capsys.readouterr().out


@pytest.mark.parametrize("test", ["oedometer", "triaxial"])
@pytest.mark.parametrize("model, values", [("modified_cam_clay", MCC),
                                           ("soft_soil_creep", SSC)])
def test_lab_runs_the_soft_soil_models(test, model, values, tmp_path):
    extra = [*SHORT, "--substeps-per-decade", "5"] if test == "oedometer" else ["--steps", "20"]
    _lab(test, model, values, tmp_path, *extra)
    assert (tmp_path / f"{test}.png").stat().st_size > 10_000
    with open(tmp_path / f"{test}.csv", newline="") as fh:
        rows = list(csv.reader(fh))
    assert tuple(rows[0]) == COLUMNS[test] and len(rows) > 10


def _creep_stage(t):
    """Rows of the creep stage (a step at the stress of the one before) and the row before."""
    k = next(s for s in np.unique(t["step"])[1:] if np.isclose(
        t["vertical_stress_kPa"][t["step"] == s][0],
        t["vertical_stress_kPa"][t["step"] == s - 1][-1], rtol=1e-6))
    return t["step"] == k, int(np.nonzero(t["step"] == k - 1)[0][-1])


def test_the_layer_model_chooses_the_law(tmp_path):
    """layers[0].model = soft_soil_creep creeps; [soil] model = modified_cam_clay does not."""
    ssc = ["--set", 'layers[0].model="soft_soil_creep"', "--set", "layers[0].phi_deg=25",
           "--set", "layers[0].lambda_star=0.1", "--set", "layers[0].kappa_star=0.02",
           "--set", "layers[0].mu_star=0.004"]
    mcc = ["--set", 'soil.model="modified_cam_clay"'] + [
        a for i in (0, 1) for k, v in (("lam", 0.25), ("kappa", 0.05), ("M", 1.0))
        for a in ("--set", f"layers[{i}].{k}={v}")]
    creep = {}
    for name, layer, sets in (("ssc", "mud", ssc), ("mcc", "silty_clay", mcc)):
        out = tmp_path / name
        assert main(["lab", "oedometer", "--scenario", "single_pile", "--layer", layer, *sets,
                     *SHORT, "--substeps-per-decade", "5", "--out", str(out)]) == 0
        t = read_lab_table(out / "oedometer.csv", COLUMNS["oedometer"])
        m, i0 = _creep_stage(t)
        creep[name] = t["vertical_strain"][m][-1] - t["vertical_strain"][i0]
    assert creep["ssc"] > 0.004 * np.log(2.0)  # mu* ln(1 + 10/tau_c), tau_c ~ 1 day
    assert abs(creep["mcc"]) < 1e-12


def test_mcc_undrained_path_from_isotropic_nc(tmp_path):
    t = _lab("triaxial", "modified_cam_clay", MCC, tmp_path)
    law = ModifiedCamClay(MCC["lam"], MCC["kappa"], MCC["e0"], M=MCC["M"], nu=MCC["nu"])
    worst = 0.0
    for p0 in (50.0, 100.0, 200.0):
        m = (t["drainage"] == "undrained") & (t["confining_stress_kPa"] == p0)
        p, q = t["p_kPa"][m], t["q_kPa"][m]
        ref = mcc_undrained_path(p0, q / p, law)
        worst = max(worst, float(np.max(np.abs(p / ref - 1.0))))
        assert q[-1] > 0.95 * law.m * p[-1]  # near the critical state at 15 % strain
    print(f"undrained path: largest error {worst:.3g}")
    assert worst < 0.01, worst  # measured 4e-10: the return is exact on this path


def test_ssc_creep_stage_follows_the_closed_form(tmp_path):
    t = _lab("oedometer", "soft_soil_creep", SSC, tmp_path, *SHORT, "--creep-days", "30")
    law = SoftSoilCreep(SSC["lambda_star"], SSC["kappa_star"], SSC["mu_star"], SSC["phi_deg"])
    m, i0 = _creep_stage(t)
    sv, sh, ez = t["vertical_stress_kPa"], t["horizontal_stress_kPa"], t["vertical_strain"]

    def stress(i):
        return np.array([[-sh[i], -sh[i], -sv[i], 0.0, 0.0, 0.0]])

    # the law's state at the start of the stage from the readings: elastic strain
    # kappa* ln(p/p0) (exact), hardening p_p = p_p0 exp(eps_c/(lambda* - kappa*))
    p = (sv + 2.0 * sh) / 3.0
    eps_c = ez[i0] - law.kappa_star * np.log(p[i0] / p[0])
    pp = law.equivalent_pressure(stress(0))[0] * np.exp(eps_c / (law.lambda_star
                                                                 - law.kappa_star))
    tau_c = float(law.creep_time(stress(i0), np.array([pp]))[0])
    growth = ez[m] - ez[i0]
    ref = ssc_creep_strain(t["time_day"][m] - t["time_day"][i0], tau_c, law.mu_star)
    err = float(np.max(np.abs(growth - ref)) / ref[-1])
    print(f"creep stage: tau_c = {tau_c:.4g} day, error {err:.3g} of {ref[-1]:.4g}")
    assert 0.5 < tau_c < 2.0 and growth[-1] > 3.0 * law.mu_star
    assert err < 0.02, err  # measured 1.3e-2


def test_time_matters_for_ssc_not_for_mcc(tmp_path):
    ends = {}
    for model, values in (("modified_cam_clay", MCC), ("soft_soil_creep", SSC)):
        for days in ("1", "10"):
            out = tmp_path / f"{model}{days}"
            t = _lab("oedometer", model, values, out, *SHORT, "--creep-days", "0",
                     "--step-days", days, "--substeps-per-decade", "5")
            last = [np.nonzero(t["step"] == k)[0][-1] for k in np.unique(t["step"])]
            ends[model, days] = t["vertical_strain"][last]
    assert np.allclose(ends["modified_cam_clay", "1"], ends["modified_cam_clay", "10"],
                       rtol=0, atol=1e-9)
    # ten times longer steps: mu* ln 10 more creep on the normal compression line
    more = ends["soft_soil_creep", "10"] - ends["soft_soil_creep", "1"]
    assert more[3] == pytest.approx(SSC["mu_star"] * np.log(10.0), rel=0.1)


@pytest.mark.parametrize("ocr", [1.0, 2.0])
def test_fit_oedometer_round_trip(noisy, ocr, tmp_path, capsys):
    values = {**SSC, "OCR": ocr}
    _lab("oedometer", "soft_soil_creep", values, tmp_path, *SHORT, "--substeps-per-decade", "5")
    data = noisy(tmp_path / "oedometer.csv", "vertical_strain", 0, tmp_path / "noisy.csv")
    capsys.readouterr()
    assert main(["fit", "oedometer", str(data), "--phi_deg", "25", "--substeps-per-decade",
                 "5", "--json"]) == 0
    got = json.loads(capsys.readouterr().out)
    for k in ("lambda_star", "kappa_star", "mu_star"):
        assert got[k] == pytest.approx(values[k], rel=0.05), (k, got)
        assert 0.0 < got["standard_errors"][k] < 0.05 * got[k]
    if ocr > 1.0:
        assert got["OCR"] == pytest.approx(ocr, rel=0.05)
        assert set(got["correlations"]) == {"lambda_star", "kappa_star", "mu_star", "OCR"}
    else:
        assert "OCR" not in got and got["OCR_held"] == 1.0
    assert (tmp_path / "noisy_fit.png").stat().st_size > 10_000


@pytest.mark.parametrize("argv, words", [
    (["--soil_model", "soft_soil_creep", "--lambda_star", "0.1", "--kappa_star", "0.02",
      "--phi_deg", "25", "--e0", "1"], ("--mu_star", "missing", "(0, 0.1]")),
    (["--soil_model", "modified_cam_clay", "--lam", "0.2", "--kappa", "0.05", "--nu", "0.3",
      "--e0", "1"], ("--M", "missing", "phi_cs_deg")),
    (["--soil_model", "soft_soil_creep", *_args("", SSC)[2:], "--kappa_star", "0.1"],
     ("--kappa_star = 0.1", "must be < lambda_star = 0.1")),
    (["--soil_model", "modified_cam_clay", *_args("", MCC)[2:], "--kappa", "0.3"],
     ("--kappa = 0.3", "must be < lam = 0.25")),
    (["--soil_model", "soft_soil_creep", *_args("", SSC)[2:], "--OCR", "0.8"],
     ("--OCR = 0.8", "[1, 100]")),
    (["--soil_model", "soft_soil_creep", *_args("", SSC)[2:], "--mu_star", "-0.001"],
     ("--mu_star = -0.001", "(0, 0.1]")),
])
def test_lab_bad_soft_soil_input(argv, words, tmp_path, capsys):
    assert main(["lab", "oedometer", *argv, "--out", str(tmp_path)]) == 2
    _one_error_line(capsys, *words)
    assert not (tmp_path / "oedometer.csv").exists()


def _write(path, header, rows):
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    return path


@pytest.mark.parametrize("header, rows, extra, words", [
    ("step,vertical_stress_kPa,vertical_strain", ["0,25,0", "1,50,0.01"], [],
     ("d.csv", "time_day")),
    ("step,time_day,vertical_stress_kPa,vertical_strain", ["0,0,25,0", "1,0,50,0.01",
                                                           "1,1,80,0.02"], [],
     ("d.csv row 4", "changes within step 1")),
    ("step,time_day,vertical_stress_kPa,vertical_strain", ["0,0,25,0", "1,0,50,0.01"], [],
     ("--phi_deg", "missing")),
    ("step,time_day,vertical_stress_kPa,vertical_strain", ["0,0,25,0", "1,0,50,0.01"],
     ["--phi_deg", "25", "--OCR", "0.5"], ("--OCR = 0.5", "[1, 100]")),
])
def test_fit_oedometer_bad_input(header, rows, extra, words, tmp_path, capsys):
    f = _write(tmp_path / "d.csv", header, rows)
    assert main(["fit", "oedometer", str(f), *extra]) == 2
    _one_error_line(capsys, *words)
