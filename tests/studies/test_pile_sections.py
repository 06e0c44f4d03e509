"""Pile sections: the head and every element-layer boundary, one recovery for every file.

``pile_bending.csv`` holds the sections at the pile's mesh planes, the head (depth 0) first;
``pile_heads.csv`` is its head row, ``pile_max_moment.csv`` its largest resultant moment and
``pile_loads.csv`` its head's axial force (docs/model.md, "What a run reports").

Fast tier: the lateral verification pile of ``pilegroup verify lateral-single-pile``
(studies/verification/lateral_cases.py: d = 0.6 m, L = 15 m, E_p/G* = 6.4e3, l_c = 7.3 m,
tied to linear elastic soil, no cap, Q2Q1 on its default mesh) in a 40 m x 40 m x 30 m block
(:data:`SMALL_SITE`), about 10 s a run:

* under its H = 50 kN and M = 20 kN m at the ground surface (the verification's own case, half
  model): the head row is H and M (statics: the section through the loaded head carries the
  applied action; tolerance 1e-6, the Newton residual's order);
* under H alone, the whole model (no symmetry condition makes y components zero): the largest
  moment against Randolph (1981), ``M_max = 0.1 H l_c`` at about ``l_c / 3`` for a free-head
  flexible pile in homogeneous soil (15 %: his expressions fit his own finite element runs to
  about 10 %, this mesh and block are 7 % stiffer than his head deflection and the profile is
  sampled at the element layers, 1.4-3.4 m apart at that depth; measured 33.7 kN m, 8 % below,
  at 1.37 m); at
  the toe, L = 2 l_c deep, the shear and moment are below 1 % of H and of H l_c (a flexible
  pile: the response dies out within l_c; measured 0.2 % and 0.001 %); the y components, with
  no load in y on a mesh mirror-symmetric about y = 0, below 1e-6 of the x ones (measured
  4e-9: round-off).

Slow tier: ``group2x3_lateral`` on its defaults to day 2.5 (2 ranks, about 5 min).
"""

import csv
from pathlib import Path

import numpy as np
import pytest

from pilegroup.studies.verification.lateral_cases import (
    D_LAT,
    E_PILE,
    E_SOIL,
    H_LAT,
    M_LAT,
    NU_SOIL,
    head_resultant,
    lateral_scenario,
    randolph_head,
)

RUN_TIMEOUT_S = 1800
#: The verification's block stands for a half-space (160 m wide, 60 m deep); statics and a 15 %
#: comparison need no more than 40 m x 40 m x 30 m, which keeps a run about 10 s (that block
#: is 1.9 % stiffer in head deflection).
SMALL_SITE = {"size_x_m": 40.0, "size_y_m": 40.0, "depth_m": 30.0}


def _table(path: Path) -> dict[str, np.ndarray]:
    with path.open() as fh:
        rows = list(csv.DictReader(fh))
    return {k: np.array([float(r[k]) for r in rows]) for k in rows[0]}


def _at(table: dict[str, np.ndarray], t: float, pile: int) -> dict[str, np.ndarray]:
    m = (table["t_day"] == t) & (table["pile"] == pile)
    return {k: v[m] for k, v in table.items()}


def _run(tmp: Path, doc: dict) -> Path:
    from pilegroup.model import scenario_from_dict
    from pilegroup.studies.run.job import run_scenario

    doc["outputs"] = {"xdmf": False, "plots": False}
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PILEGROUP_MESH_CACHE", str(tmp / "cache"))
        mp.setenv("PILEGROUP_PROGRESS", "0")
        run_scenario(scenario_from_dict(doc), tmp / "run")
    return tmp / "run"


@pytest.fixture(scope="module")
def h_and_m(tmp_path_factory):
    """The verification pile under its H and M (half model y >= 0)."""
    doc = lateral_scenario("single")
    doc["site"] = dict(SMALL_SITE)
    return _run(tmp_path_factory.mktemp("h_and_m"), doc)


@pytest.fixture(scope="module")
def h_only(tmp_path_factory):
    """The verification pile under H alone, the whole model."""
    doc = lateral_scenario("single")
    doc["site"] = dict(SMALL_SITE)
    doc["stages"][1]["My_kNm"] = 0.0
    doc["numerics"] = {"symmetry": "none"}
    return _run(tmp_path_factory.mktemp("h_only"), doc)


def _lc() -> float:
    """Randolph's critical length of the verification pile (m)."""
    G = E_SOIL / (2.0 * (1.0 + NU_SOIL))
    return randolph_head(H_LAT, 0.0, D_LAT, E_PILE, G, NU_SOIL)[2]


def _consistent(folder: Path) -> None:
    """Head row, largest moment and head force: the profile's own values, every time and pile."""
    b, h = _table(folder / "pile_bending.csv"), _table(folder / "pile_heads.csv")
    mm, loads = _table(folder / "pile_max_moment.csv"), _table(folder / "pile_loads.csv")
    for r in range(h["t_day"].size):
        t, i = h["t_day"][r], h["pile"][r]
        prof = _at(b, t, i)
        assert prof["depth_m"][0] == 0.0 and np.all(np.diff(prof["depth_m"]) > 0.0)
        assert h["depth_m"][r] == 0.0
        for col in ("N_kN", "Vx_kN", "Vy_kN", "Mx_kNm", "My_kNm", "T_kNm"):
            assert h[col][r] == prof[col][0], col
        m = np.hypot(prof["Mx_kNm"], prof["My_kNm"])
        k = int(np.argmax(m))
        top = _at(mm, t, i)
        assert top["M_max_kNm"][0] == pytest.approx(m[k], rel=1e-8, abs=1e-9)
        assert top["depth_m"][0] == prof["depth_m"][k]
        assert _at(loads, t, i)["head_force_kN"][0] == h["N_kN"][r]


def test_the_head_row_is_the_applied_action(h_and_m):
    _consistent(h_and_m)
    prof = _at(_table(h_and_m / "pile_bending.csv"), 2.0, 1)
    assert prof["Vx_kN"][0] == pytest.approx(H_LAT, rel=1e-6)
    assert prof["My_kNm"][0] == pytest.approx(M_LAT, rel=1e-6)
    assert abs(prof["N_kN"][0]) <= 1e-6 * H_LAT
    # below the head the moment grows (H's lever arm) to its largest, then dies out
    assert np.max(prof["My_kNm"]) > 2.0 * M_LAT
    assert abs(prof["My_kNm"][-1]) < 0.01 * H_LAT * _lc()
    assert abs(prof["Vx_kN"][-1]) < 0.01 * H_LAT


def test_profile_under_h_against_randolph_and_free_of_y_components(h_only):
    _consistent(h_only)
    lc = _lc()
    prof = _at(_table(h_only / "pile_bending.csv"), 2.0, 1)
    d = prof["depth_m"]
    assert prof["Vx_kN"][0] == pytest.approx(H_LAT, rel=1e-6)
    assert abs(prof["My_kNm"][0]) <= 1e-6 * H_LAT * lc
    k = int(np.argmax(np.abs(prof["My_kNm"])))
    assert prof["My_kNm"][k] == pytest.approx(0.1 * H_LAT * lc, rel=0.15)
    assert 0.1 * lc < d[k] < 0.5 * lc
    assert d[-1] == pytest.approx(15.0) and d[-1] > 2.0 * lc * 0.99
    assert abs(prof["Vx_kN"][-1]) < 0.01 * H_LAT
    assert abs(prof["My_kNm"][-1]) < 0.01 * H_LAT * lc
    for col, ref in (("Vy_kN", "Vx_kN"), ("Mx_kNm", "My_kNm"), ("T_kNm", "My_kNm"),
                     ("uy_m", "ux_m")):
        assert np.max(np.abs(prof[col])) <= 1e-6 * np.max(np.abs(prof[ref])), col


@pytest.mark.slow
@pytest.mark.mpi
def test_group2x3_lateral_profiles(run_cli, tmp_path):
    """The bundled 2 x 3 group: heads balance the actions; x-only increment, y at the toes.

    Day 1 carries the vertical load alone, day 2 adds Fx = 800 kN and My = 6 MN m about the
    cap top's centre. The heads balance the applied actions to 1e-6 of the vertical load
    (measured 2e-9: the cap's own equilibrium, Newton's residual). The increment of day 1 to
    day 2 has no component in y: at the toes (the last 4 m of each pile) its Mx and Vy stay
    below 10 % of the head's My and Vx increments (measured 11 kN m and 5 kN against 201-254
    kN m and 110-150 kN): the moment goes mostly into axial forces (up to +-15 % of a pile's),
    and a pile's bending under its axial load (the group's spreading, in x and y, from day 1)
    changes with it.
    """
    out = tmp_path / "g"
    r = run_cli("group2x3_lateral", out, 2, ["time.end_day=2.5",
                                             "time.output_days=[0.0, 1.0, 2.0, 2.5]",
                                             "outputs.xdmf=false"], timeout=RUN_TIMEOUT_S)
    assert r.returncode == 0, r.stderr[-3000:]
    _consistent(out)
    h = _table(out / "pile_heads.csv")
    day2 = {k: v[h["t_day"] == 2.0] for k, v in h.items()}
    got = head_resultant(day2, (0.0, 0.0, 2.0))
    applied = np.array([800.0, 0.0, -24000.0, 0.0, 6000.0, 0.0])
    np.testing.assert_allclose(got, applied, rtol=0.0, atol=1e-6 * 24000.0)
    b = _table(out / "pile_bending.csv")
    for i in range(1, 7):
        one, two = _at(b, 1.0, i), _at(b, 2.0, i)
        d = {c: two[c] - one[c] for c in ("Vx_kN", "Vy_kN", "Mx_kNm", "My_kNm")}
        toe = two["depth_m"] >= two["depth_m"][-1] - 4.0
        assert np.max(np.abs(d["Mx_kNm"][toe])) < 0.1 * abs(d["My_kNm"][0]), i
        assert np.max(np.abs(d["Vy_kN"][toe])) < 0.1 * abs(d["Vx_kN"][0]), i
