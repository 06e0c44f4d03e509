"""Cross-code verification against OpenGeoSys 6 (studies/verification/ogs_compare.py): slow tier.

The session fixture installs OGS (PyPI ``ogs``) into the running Python's environment with
``tools/install-ogs.sh`` (never part of ``make test``'s fast tier) and skips, with the reason,
when it cannot. The tolerances are the module's (1 % settlement, 3 % + 0.5 kPa pressure); no
expected number is written here.
"""

import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[2]


@pytest.fixture(scope="session")
def ogs_installed():
    """OGS in this Python's environment (installed on first use), else the test is skipped."""
    venv = Path(sys.executable).parent.parent
    try:
        r = subprocess.run(["bash", str(ROOT / "tools" / "install-ogs.sh"), str(venv)],
                           capture_output=True, text=True, timeout=900, check=False,
                           env=os.environ | {"PIP_DISABLE_PIP_VERSION_CHECK": "1"})
    except (OSError, subprocess.TimeoutExpired) as exc:
        pytest.skip(f"OpenGeoSys could not be installed: {exc}")
    if r.returncode != 0:
        pytest.skip("OpenGeoSys could not be installed (tools/install-ogs.sh exit "
                    f"{r.returncode}): {(r.stderr or r.stdout)[-500:]}")
    from pilegroup.studies.verification import ogs_compare

    ogs_compare.ogs_executable()  # installed: a missing executable is a failure, not a skip
    return ogs_compare


def test_quadratic_mesh_conversion():
    """The 20-node mesh: positive volumes, pilegroup's nodes first, the same face areas."""
    from pilegroup.geometry import groups
    from pilegroup.studies.verification import ogs_compare as oc

    md = oc.build_case_mesh()
    om = oc.ogs_mesh(md, {"ground": (groups.GROUND,), "head": (groups.head(1),)})
    assert np.array_equal(om.points[:om.n_vertices], md.mesh.geometry.x)
    c = om.points[om.cells[:, :8]]
    d3 = c[:, 4:].sum(axis=1) - c[:, :4].sum(axis=1)
    d1 = c[:, 1] - c[:, 0] + c[:, 2] - c[:, 3] + c[:, 5] - c[:, 4] + c[:, 6] - c[:, 7]
    d2 = c[:, 3] - c[:, 0] + c[:, 2] - c[:, 1] + c[:, 7] - c[:, 4] + c[:, 6] - c[:, 5]
    assert np.all(np.einsum("ij,ij->i", np.cross(d1, d2), d3) > 0)
    mids = om.points[om.cells[:, 8:]]
    ends = om.points[om.cells[:, :8]][:, oc._HEX_EDGES]
    assert np.allclose(mids, ends.mean(axis=2))
    for name, group in (("ground", groups.GROUND), ("head", groups.head(1))):
        area, mean = oc._quad8_mean(om.points, om.faces[name], np.ones(len(om.points)))
        assert area == pytest.approx(oc._facet_integral(md, group, 1.0), rel=1e-12)
        assert mean == pytest.approx(1.0, rel=1e-12)


@pytest.mark.parametrize(("case", "pair"), [
    ("fill", "Q2Q1"),
    ("pile", "Q2Q1"),
    ("fill", "Q1Q1"),
    # Q1Q1 settles several % less than OGS's Taylor-Hood next to the loaded pile on this mesh:
    # trilinear hexahedra are too stiff in the shear zone along the shaft (docs/results.md)
    pytest.param("pile", "Q1Q1", marks=pytest.mark.xfail(
        strict=True, reason="Q1Q1 stiffer than OGS's Taylor-Hood next to the pile"))])
def test_against_opengeosys(ogs_installed, case, pair):
    """Settlement within 1 % and pore pressure within 3 % + 0.5 kPa of OGS at every output.

    Q2Q1 is pilegroup's default (the comparison that must hold); Q1Q1, the trilinear pair,
    shows what the element costs next to a pile.
    """
    oc = ogs_installed
    res = oc.compare(case, pair)
    table = oc.format_table(res)
    print(table)
    assert len(res["settlement"]) == len(oc.STEPS), table
    assert res["area_m2"][0] == pytest.approx(res["area_m2"][1], rel=1e-10), table
    assert res["max_pressure_ratio"] <= 1.0, table
    assert res["max_settlement_error"] <= oc.TOL_S, table
