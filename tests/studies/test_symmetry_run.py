"""A symmetric 3 x 3 group without a cap: the quarter model gives the full model's answers.

The centre pile is cut into a quarter, the four edge piles into halves; every pile of the
foundation is reported. The full mesh is the quarter mesh and its mirror images (the same
nodes and cells on the quarter's side, tests/geometry/test_symmetry.py), so the two models
differ only by the symmetry conditions and agree to the solver's accuracy, not to a
discretisation error: the settlement, every pile's head force and the centre pile's axial
force profile within 1e-6 relative (Newton stops at 1e-9 of the residual, the CSV files keep
9 significant digits; measured: equal to the last printed digit), far below the 0.2 % a
reduced model is allowed. The centre pile's friction profile too, except at the toe: the nodes
of the toe ring also carry the base's material point, whose first shear component is along x
(the base frame of solver/interface.py), and a quarter ring's mean of it is not the full
ring's; that station keeps a 1 % bound (measured 0.13 % at day 2). The quarter runs serially
and under ``mpirun -n 2``.
"""

import csv
import json
from pathlib import Path

import numpy as np
import pytest

#: Seconds a run (serial or `mpirun -n 2`) may take before the test fails: a rank that
#: dies or hangs must not hang the suite.
RUN_TIMEOUT_S = 900


def group_text(single_pile: str) -> str:
    """The fast-tier single pile made a 3 x 3 group at 2.4 m spacing (no cap)."""
    assert "grid = [1, 1]\n" in single_pile and "far_field_size_m = 8.0" in single_pile
    return single_pile.replace("grid = [1, 1]\n", "grid = [3, 3]\nspacing_m = [2.4, 2.4]\n") \
        .replace("far_field_size_m = 8.0", "far_field_size_m = 2.0")


def _rows(path: Path) -> list[dict[str, str]]:
    with path.open() as fh:
        return list(csv.DictReader(fh))


def _compare(full: Path, reduced: Path) -> None:
    s = json.loads((reduced / "summary.json").read_text())["solver"]
    assert s["symmetry"]["model"] == "quarter"
    w_full = [float(r["settlement_m"]) for r in _rows(full / "settlement.csv")]
    w_red = [float(r["settlement_m"]) for r in _rows(reduced / "settlement.csv")]
    assert len(w_full) == len(w_red) == 3
    np.testing.assert_allclose(w_red[1:], w_full[1:], rtol=1e-6)
    loads = {(r["t_day"], r["pile"]): float(r["head_force_kN"])
             for r in _rows(full / "pile_loads.csv")}
    red = {(r["t_day"], r["pile"]): float(r["head_force_kN"])
           for r in _rows(reduced / "pile_loads.csv")}
    assert red.keys() == loads.keys() and {k[1] for k in loads} == {str(i) for i in range(1, 10)}
    for k, v in loads.items():
        if float(k[0]) > 0:
            assert red[k] == pytest.approx(v, rel=1e-6), k
    for col in ("shaft_friction_kPa", "axial_force_kN"):
        prof = {}
        for name, folder in (("full", full), ("quarter", reduced)):
            rows = [r for r in _rows(folder / "pile_profiles.csv")
                    if r["pile"] == "5" and r["t_day"] == "2"]
            prof[name] = (np.array([float(r["depth_m"]) for r in rows]),
                          np.array([float(r[col]) for r in rows]))
        (z0, v0), (z1, v1) = prof["full"], prof["quarter"]
        np.testing.assert_allclose(z1, z0, atol=1e-9)
        toe = z0 == z0.max() if col == "shaft_friction_kPa" else np.zeros(z0.size, dtype=bool)
        scale = np.max(np.abs(v0))
        assert np.max(np.abs(v1 - v0)[~toe]) <= 1e-6 * scale, col
        assert np.all(np.abs(v1 - v0)[toe] <= 1e-2 * np.abs(v0[toe])), col


@pytest.fixture(scope="module")
def group(small_pile_source):
    return group_text(small_pile_source)


@pytest.fixture(scope="module")
def full_run(run_symmetry, tmp_path_factory, group):
    return run_symmetry(tmp_path_factory.mktemp("group_full"), group, "full", "none",
                        timeout=RUN_TIMEOUT_S)


def test_quarter_matches_full(run_symmetry, full_run, group, tmp_path):
    _compare(full_run, run_symmetry(tmp_path, group, "quarter", "quarter",
                                    timeout=RUN_TIMEOUT_S))


@pytest.mark.mpi
def test_quarter_under_mpirun_matches_full(run_symmetry, full_run, group, tmp_path):
    _compare(full_run, run_symmetry(tmp_path, group, "quarter", "quarter", ranks=2,
                                    timeout=RUN_TIMEOUT_S))
