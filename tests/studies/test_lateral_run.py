"""Cap actions on a 3 x 3 group: the half model gives the full model's answers, heads balance.

A horizontal force along x and a moment about y are mirror-symmetric about y = 0 only:
``symmetry = "auto"`` keeps the half y >= 0 and the summary says why. The half mesh is the full
mesh's y >= 0 side (tests/geometry/test_symmetry.py), so the two models differ only by the
symmetry conditions: cap motion and every pile's head actions agree far inside the 0.2 % and
0.5 % a reduced model is allowed (measured: to the printed digits). In both, the pile heads'
actions balance the applied ones (the cap is free of the soil with the interface).
"""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

from pilegroup.studies.verification.lateral_cases import head_resultant

#: Seconds a run (serial or `mpirun -n 2`) may take before the test fails: a rank that
#: dies or hangs must not hang the suite.
RUN_TIMEOUT_S = 900

FX, MY, Q = 100.0, 50.0, 500.0


def lateral_group_text(single_pile: str) -> str:
    """The fast-tier single pile made a 3 x 3 group under a cap, with Fx and My on the cap."""
    for old in ("grid = [1, 1]\n", "far_field_size_m = 8.0", "cap_load_kN = 500.0\n",
                "[structure]"):
        assert old in single_pile, old
    return (single_pile.replace("grid = [1, 1]\n", "grid = [3, 3]\nspacing_m = [2.4, 2.4]\n")
            .replace("far_field_size_m = 8.0", "far_field_size_m = 2.0")
            .replace("cap_load_kN = 500.0\n", f"cap_load_kN = {Q}\nFx_kN = {FX}\n"
                     f"My_kNm = {MY}\n")
            .replace("[structure]", "[cap]\nsize_x_m = 7.2\nsize_y_m = 7.2\nthickness_m = 1.0"
                     "\n\n[structure]"))


def _table(path: Path) -> dict[str, np.ndarray]:
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def _compare(full: Path, half: Path) -> None:
    s = json.loads((half / "summary.json").read_text())["solver"]["symmetry"]
    assert s["model"] == "half_y" and "Fx = 100" in s["reason"], s
    a, b = _table(full / "cap_motion.csv"), _table(half / "cap_motion.csv")
    for col in ("ux_m", "uz_m", "ry_rad"):
        np.testing.assert_allclose(b[col], a[col], rtol=2e-3, atol=1e-12 * np.abs(a[col]).max())
    for col in ("uy_m", "rx_rad", "rz_rad"):
        assert np.all(b[col] == 0.0)
    a, b = _table(full / "pile_heads.csv"), _table(half / "pile_heads.csv")
    assert np.array_equal(a["pile"], b["pile"]) and set(a["pile"]) == set(range(1, 10))
    for col in ("N_kN", "Vx_kN", "Vy_kN", "Mx_kNm", "My_kNm", "T_kNm"):
        scale = np.abs(a[col]).max()
        assert np.abs(b[col] - a[col]).max() <= 5e-3 * scale + 1e-9, col


def _balance(folder: Path) -> None:
    h = _table(folder / "pile_heads.csv")
    last = {k: v[h["t_day"] == h["t_day"].max()] for k, v in h.items()}
    got = head_resultant(last, (0.0, 0.0, 1.0))
    applied = np.array([FX, 0.0, -Q, 0.0, MY, 0.0])
    np.testing.assert_allclose(got, applied, rtol=1e-6, atol=1e-6 * Q)


@pytest.fixture(scope="module")
def group(small_pile_source):
    return lateral_group_text(small_pile_source)


@pytest.fixture(scope="module")
def full_run(run_symmetry, tmp_path_factory, group):
    return run_symmetry(tmp_path_factory.mktemp("lateral_full"), group, "full", "none",
                        timeout=RUN_TIMEOUT_S)


def test_half_matches_full_and_heads_balance(run_symmetry, full_run, group, tmp_path):
    half = run_symmetry(tmp_path, group, "half", "auto", timeout=RUN_TIMEOUT_S)
    _compare(full_run, half)
    _balance(full_run)
    _balance(half)
    bending = _table(half / "pile_bending.csv")
    assert {"N_kN", "Vx_kN", "My_kNm", "ux_m"} <= bending.keys()
    top = _table(half / "pile_max_moment.csv")
    assert np.all(top["M_max_kNm"] >= 0.0)


@pytest.mark.mpi
def test_half_under_mpirun_matches_full(run_symmetry, full_run, group, tmp_path):
    half = run_symmetry(tmp_path, group, "half", "auto", ranks=2, timeout=RUN_TIMEOUT_S)
    _compare(full_run, half)
    _balance(half)


def test_stiffness_matrix_of_a_pile_head(small_pile, tmp_path):
    """``pilegroup stiffness``: positive diagonal, symmetric (Betti) to 1 %, full model."""
    import subprocess
    import sys

    out = tmp_path / "k"
    cmd = [str(Path(sys.executable).parent / "pilegroup"), "stiffness", small_pile, "--out",
           str(out), "--set", "outputs.plots=false", "--set", "outputs.xdmf=false"]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stderr[-3000:]
    assert json.loads((out / "summary.json").read_text())["solver"]["symmetry"]["model"] == "none"
    with (out / "cap_stiffness.csv").open() as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["action", "ux_m", "uy_m", "uz_m", "rx_rad", "ry_rad", "rz_rad"]
    assert [r[0] for r in rows[1:]] == ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    K = np.array([[float(v) for v in r[1:]] for r in rows[1:]])
    d = np.sqrt(np.abs(np.outer(np.diag(K), np.diag(K))))
    assert np.all(np.diag(K) > 0.0)
    assert np.max(np.abs(K - K.T) / d) < 0.01
    # a head pushed along +x with its rotation held back needs a moment of the opposite sense
    assert K[0, 4] < 0.0 and K[1, 3] > 0.0
    assert abs(K[0, 0] - K[1, 1]) < 1e-3 * K[0, 0]  # a round pile: the same both ways
