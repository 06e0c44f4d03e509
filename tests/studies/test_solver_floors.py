"""``pilegroup bench floors``: the machine's rates and the floors derived from them."""

import json

import pytest
from mpi4py import MPI

from pilegroup.errors import ScenarioError
from pilegroup.studies.bench.solver_floors import bench_floors, machine_rates, mumps_count


def test_mumps_counts_below_zero_are_millions():
    assert mumps_count(1234) == 1234.0
    assert mumps_count(-5) == 5e6


def test_machine_rates_are_those_of_a_computer():
    """A streaming pass between 0.1 and 1,000 GB/s per rank, a matrix product between 0.1 and
    10,000 GFlop/s per rank: units or word counts mixed up would leave these ranges."""
    bandwidth, flops = machine_rates(MPI.COMM_WORLD, repeats=2)
    assert 1e8 < bandwidth < 1e12
    assert 1e8 < flops < 1e13


def test_floors_table_on_the_small_pile(tmp_path, small_pile, monkeypatch):
    """Every MatMult row and the kept LU's solve carry a floor, positive and (out of cache, or
    not) within a factor 100 of the measured time; the machine rows carry their rates; the
    split's own solve and its two iteration floors (blocks by LU) converge."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    rows = bench_floors(small_pile, out_dir=tmp_path / "floors", repeats=2)
    by = {r["piece"]: r for r in rows}
    assert by["machine: streaming pass, every rank at once"]["rate"].endswith("GB/s per rank")
    floored = [r for r in rows if r["piece"].startswith("MatMult")
               or r["piece"].startswith("direct_reuse")]
    assert len(floored) == 5
    for r in floored:
        assert r["floor_s"] is not None and r["apply_s"] is not None, r
        assert 0.0 < r["floor_s"] < 100.0 * max(r["apply_s"], 1e-5), r
    lu = by["direct_reuse: block low-rank LU factorisation / one solve"]
    assert "factor entries" in lu["rate"] and lu["iterations"] >= 1
    own = by["fieldsplit_pier: FGMRES solve (kept set-up)"]
    exact = by["fieldsplit_pier: FGMRES, every block by LU"]
    fixed_stress = by["fieldsplit_gamg: FGMRES, displacement and pressure blocks by LU "
                      "(the fixed-stress floor)"]
    for r in (own, exact, fixed_stress):
        assert r["rate"] == "converged" and r["iterations"] >= 1, r
    if MPI.COMM_WORLD.rank == 0:
        saved = json.loads((tmp_path / "floors" / "bench_floors.json").read_text())
        assert [r["piece"] for r in saved] == [r["piece"] for r in rows]


@pytest.mark.mpi
def test_floors_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, ranks=2, timeout=300)


def test_floors_refuse_a_preset_without_blocks(small_pile):
    """Only a field-split preset has blocks to time: another is refused before meshing."""
    with pytest.raises(ScenarioError, match="bench floors --presets = 'direct_reuse'"):
        bench_floors(small_pile, preset="direct_reuse")
