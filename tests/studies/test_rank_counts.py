"""Any rank count gives the serial answer: 1, 3 and 4 ranks (some ranks hold no pile, no
interface facet or no pressure dof; 3 and 4 ranks oversubscribe a 2-core machine).

Tolerance 1e-8 relative on the settlement at every output time and on every pile's head force:
the ranks sum the same terms in another order, nothing else differs.
"""

import csv
from pathlib import Path

import pytest


def _run(run_cli, tmp: Path, scenario: Path, ranks: int) -> Path:
    r = run_cli(scenario, tmp / f"n{ranks}", ranks, ["outputs.plots=false"])
    assert r.returncode == 0, r.stderr[-3000:]
    return tmp / f"n{ranks}"


def _values(out: Path) -> dict[tuple[str, ...], float]:
    vals = {}
    with (out / "settlement.csv").open() as fh:
        vals.update({("w", r["t_day"]): float(r["settlement_m"]) for r in csv.DictReader(fh)})
    with (out / "pile_loads.csv").open() as fh:
        vals.update({("N", r["t_day"], r["pile"]): float(r["head_force_kN"])
                     for r in csv.DictReader(fh)})
    return vals


@pytest.fixture(scope="module")
def serial(run_cli, tmp_path_factory, small_pile_source):
    tmp = tmp_path_factory.mktemp("ranks")
    f = tmp / "small_pile.toml"
    f.write_text(small_pile_source)
    return tmp, f, _values(_run(run_cli, tmp, f, 1))


@pytest.mark.mpi
@pytest.mark.parametrize("ranks", [3, 4])
def test_rank_count_gives_the_serial_answer(run_cli, serial, ranks):
    tmp, f, ref = serial
    got = _values(_run(run_cli, tmp, f, ranks))
    assert got.keys() == ref.keys()
    for k, v in ref.items():
        assert got[k] == pytest.approx(v, rel=1e-8, abs=1e-12), k
