"""Interface verification cases (studies/verification/interface_cases.py): serial and mpirun -n 2.

Every case runs with both interface quadratures (law at the nodes, or at facet Gauss points).
"""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pilegroup.geometry.plan import perimeter_factor
from pilegroup.studies import verification as ver

ROOT = Path(__file__).resolve().parents[2]
CASES = ["shaft-capacity", "interface-patch", "tied-limit"]
QUADRATURES = ["nodal", "gauss"]


def test_cases_are_registered():
    assert all(c in ver.CASES for c in CASES)


@pytest.mark.parametrize("quadrature", QUADRATURES)
def test_shaft_capacity(quadrature):
    r = ver.CASES["shaft-capacity"](quadrature=quadrature)
    d = r.details
    assert r.error <= r.tolerance == 0.02 and r.passed and d["quadrature"] == quadrature
    # every shaft point (node or Gauss point) at the Drucker-Prager limit; plateau of the load
    assert d["shaft_points_at_yield"] == d["shaft_points"] > 0
    loads = [row["head_load_kN"] for row in d["rows"]]
    assert np.allclose(loads[-3:], d["capacity_actual_sigma_n_kN"], rtol=2e-4)
    # in-situ tractions lump exactly onto the closed form pi d (k L + 3 alpha K0 gamma' L^2/2)
    assert d["err_insitu"] < 1e-12
    # the shaft's points stand for the circle's surface: the 8-gon of the circle's area (R^2 =
    # pi / 4 / (4 sin(pi / 4)) for d = 1 m, perimeter 16 R sin(pi / 8)) times the shaft factor
    big = np.sqrt(np.pi / 4 / (4 * np.sin(np.pi / 4)))
    assert 16 * big * np.sin(np.pi / 8) * perimeter_factor(8) == pytest.approx(np.pi, rel=1e-14)
    assert d["perimeter_m"] == pytest.approx(np.pi, rel=1e-12)


@pytest.mark.parametrize("quadrature", QUADRATURES)
def test_interface_patch_matches_pointwise_law(quadrature):
    r = ver.CASES["interface-patch"](quadrature=quadrature)
    d = r.details
    assert r.error <= r.tolerance == 1e-6 and r.passed and d["quadrature"] == quadrature
    assert d["node_spread_max"] < 1e-12  # homogeneous: every interface point alike
    assert d["creep_slip_vp_m"] > 0.01  # creep at constant shear load is exercised
    tau1 = [row["tau1"] for row in d["rows"] if row["t"] > 1.0]
    assert np.allclose(tau1, 32.0, rtol=1e-8)


@pytest.mark.parametrize("quadrature", QUADRATURES)
def test_tied_limit(quadrature):
    r = ver.CASES["tied-limit"](quadrature=quadrature)
    assert r.error <= r.tolerance == 0.01 and r.passed and r.details["quadrature"] == quadrature
    assert r.error < 1e-3  # measured 5.2e-5 (nodal), 4.6e-4 (gauss)


def _json_lines(out):
    return {d["case"]: d for d in (json.loads(x) for x in out.splitlines() if x.startswith("{"))}


@pytest.mark.mpi
@pytest.mark.parametrize("quadrature", QUADRATURES)
def test_interface_cases_under_mpirun_match_serial(quadrature):
    exe = str(Path(sys.executable).parent / "pilegroup")
    mpirun = str(Path(sys.executable).parent / "mpirun")
    cmd = [exe, "verify", *CASES, "--json", "--interface-quadrature", quadrature]
    serial = subprocess.run(cmd, capture_output=True, text=True, cwd=ROOT, timeout=600)
    par = subprocess.run([mpirun, "-n", "2", *cmd], capture_output=True, text=True, cwd=ROOT,
                         timeout=600)
    assert serial.returncode == 0, serial.stderr[-2000:]
    assert par.returncode == 0, par.stderr[-2000:]
    s, p = _json_lines(serial.stdout), _json_lines(par.stdout)
    for c in CASES:
        assert s[c]["passed"] and p[c]["passed"] and p[c]["details"]["ranks"] == 2
        assert p[c]["details"]["quadrature"] == s[c]["details"]["quadrature"] == quadrature
        assert p[c]["dofs"] == s[c]["dofs"] and p[c]["steps"] == s[c]["steps"]
        # the errors are differences of nearly equal numbers (patch: ~1e-9, at the Newton
        # tolerance): compared in absolute terms
        assert p[c]["error"] == pytest.approx(s[c]["error"], rel=1e-8, abs=1e-10), c
        for rs, rp in zip(s[c]["details"]["rows"], p[c]["details"]["rows"], strict=True):
            for k, v in rs.items():
                assert rp[k] == pytest.approx(v, rel=1e-8, abs=1e-12), (c, k)
