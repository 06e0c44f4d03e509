"""Machines too small: the memory estimate before meshing, checked against a measured peak, and
a run that cannot fit refused (exit 2, one line) before gmsh starts."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent

#: Runs ``pilegroup run`` as a child and prints the child's peak resident memory (MB).
MEASURE = r"""
import resource, subprocess, sys
r = subprocess.run(sys.argv[1:], capture_output=True, text=True)
sys.stderr.write(r.stderr[-3000:])
print(r.returncode, resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss / 1024.0)
"""

#: Pier 667 whole, with 1 m elements out to the block's sides: ~150 GB per rank estimated with
#: the in-core kept LU, named so that ``auto`` cannot turn out of core (whose fit, made on
#: models 20 times smaller, would extrapolate that far below it).
TOO_LARGE = ("numerics.mesh.far_field_size_m=1.0", 'numerics.symmetry="none"',
             'numerics.solver.preset="direct_reuse"')


def test_estimate_within_a_factor_two_of_the_measured_peak(tmp_path, small_pile):
    out = tmp_path / "run"
    cmd = [str(BIN / "pilegroup"), "run", small_pile, "--out", str(out),
           "--set", "outputs.xdmf=false", "--set", "outputs.plots=false"]
    env = {**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")}
    r = subprocess.run([sys.executable, "-c", MEASURE, *cmd], capture_output=True, text=True,
                       timeout=600, env=env)
    code, peak = r.stdout.split()
    assert code == "0", r.stderr
    mem = json.loads((out / "summary.json").read_text())["memory"]
    ratio = mem["estimate_mb_per_rank"] / float(peak)
    assert 0.5 <= ratio <= 2.0, (mem, peak)
    assert "MB per rank estimated" in r.stderr  # printed for every run
    assert mem["peak_rss_mb_per_rank"][0] == pytest.approx(float(peak), rel=0.25)


def test_a_run_that_cannot_fit_stops_before_meshing(tmp_path, run_cli):
    t0 = time.perf_counter()
    r = run_cli("pier667", tmp_path / "big", sets=TOO_LARGE)
    wall = time.perf_counter() - t0
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert r.returncode == 2 and len(lines) == 1, r.stderr[-2000:]
    assert "MB per rank estimated" in lines[0] and "MB available per rank" in lines[0]
    assert "--force" in lines[0] and "Traceback" not in r.stderr
    assert not (tmp_path / "big" / "mesh").exists()  # gmsh never started
    assert wall < 60.0


def test_force_lets_the_run_go_on(small_pile):
    from mpi4py import MPI

    from pilegroup.errors import MachineTooSmall
    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.model import load_scenario
    from pilegroup.model.loader import parse_override
    from pilegroup.studies.run.memory_check import estimated_peak_mb, memory_check

    sc = load_scenario("pier667", dict(parse_override(kv) for kv in TOO_LARGE))
    geo = resolve_geometry(sc)
    with pytest.raises(MachineTooSmall):
        memory_check(sc, geo, MPI.COMM_WORLD)
    rec = memory_check(sc, geo, MPI.COMM_WORLD, force=True)
    assert rec["forced"] and rec["estimate_mb_per_rank"] > rec["available_mb_per_rank"]
    # the fit goes through the measured peaks it was made from (docs/benchmarks.md)
    assert estimated_peak_mb(80_853, "direct_reuse_double", 2) == pytest.approx(1390.0, rel=0.1)
    assert estimated_peak_mb(80_853, "direct_reuse", 2) == pytest.approx(1143.0, rel=0.1)
    assert estimated_peak_mb(426_116, "fieldsplit_pier", 2) == pytest.approx(6600.0, rel=0.1)


def test_auto_turns_out_of_core_when_the_budget_is_short():
    """``auto`` resolved to the kept LU turns to its out-of-core variant when the in-core
    estimate exceeds the memory per rank; a preset named in the scenario is kept."""
    import dataclasses

    from pilegroup.model import load_scenario
    from pilegroup.studies.run.memory_check import estimated_peak_mb, preset_within

    sc = load_scenario("pier667")
    assert sc.numerics.solver.preset == "auto"
    n = 426_116  # the full pier at h = 0.3 m
    in_core, ooc = (estimated_peak_mb(n, p, 2) for p in ("direct_reuse", "direct_reuse_ooc"))
    assert ooc < 0.85 * in_core  # the measured peaks the fits come from
    assert preset_within(sc, "direct_reuse", n, 2, 4000.0) == "direct_reuse_ooc"
    assert preset_within(sc, "direct_reuse", n, 2, in_core + 1.0) == "direct_reuse"
    assert preset_within(sc, "direct_reuse", n, 2, None) == "direct_reuse"
    assert preset_within(sc, "fieldsplit_pier", n, 2, 100.0) == "fieldsplit_pier"
    named = dataclasses.replace(sc, numerics=dataclasses.replace(sc.numerics, solver=(
        dataclasses.replace(sc.numerics.solver, preset="direct_reuse"))))
    assert preset_within(named, "direct_reuse", n, 2, 4000.0) == "direct_reuse"


def test_memory_limit_lowers_the_budget_and_chooses_the_preset():
    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.model import load_scenario
    from pilegroup.model.loader import parse_override
    from pilegroup.studies.run.memory_check import memory_check

    sc = load_scenario("pier667", dict(parse_override(kv) for kv in (
        'numerics.symmetry="none"', "numerics.mesh.size_m=0.3")))
    geo = resolve_geometry(sc)
    free = memory_check(sc, geo, MPI.COMM_WORLD)
    assert free["budget_mb_per_rank"] == free["available_mb_per_rank"]
    need = free["estimate_mb_per_rank"]
    ranks = free["ranks_on_node"]
    rec = memory_check(sc, geo, MPI.COMM_WORLD, limit_mb=0.9 * need * ranks)
    assert rec["budget_mb_per_rank"] == pytest.approx(0.9 * need, abs=0.1)  # rounded to 0.1 MB
    assert rec["preset"] == "direct_reuse_ooc" and rec["estimate_mb_per_rank"] < 0.9 * need


@pytest.mark.parametrize("text, mb", [("8GB", 8192.0), ("6000mb", 6000.0), ("0.5 GB", 512.0)])
def test_memory_option_reads_a_size_with_its_unit(text, mb):
    from pilegroup.studies.cli.commands import memory_size

    assert memory_size(text) == mb


@pytest.mark.parametrize("text", ["8", "8TB", "-1GB", "0MB", "nanGB", "infGB", "GB"])
def test_memory_option_refuses_what_is_not_a_size(text):
    import argparse

    from pilegroup.studies.cli.commands import memory_size

    with pytest.raises(argparse.ArgumentTypeError, match="allowed: a positive size"):
        memory_size(text)


def test_a_memory_limit_too_small_stops_the_run_with_the_limit_named(tmp_path):
    """``--memory`` below any estimate: exit 2 before meshing, one line naming the limit; a
    value without a unit is refused by the command line (exit 2, the allowed form)."""
    run = [str(BIN / "pilegroup"), "run", "pier667", "--out", str(tmp_path / "r")]
    r = subprocess.run([*run, "--memory", "100MB"], capture_output=True, text=True, timeout=300)
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert r.returncode == 2 and len(lines) == 1, r.stderr[-2000:]
    assert "--memory 100 MB per node" in lines[0] and "Traceback" not in r.stderr
    assert not (tmp_path / "r" / "mesh").exists()
    r = subprocess.run([*run, "--memory", "8"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 2 and "allowed: a positive size with its unit" in r.stderr


def test_the_unknowns_counted_on_the_mesh_decide_again():
    """Before meshing the unknowns are estimated (the full pier at 0.3 m: 3.2e5 against
    426,116 counted); ``auto`` is resolved again with the counted ones."""
    from mpi4py import MPI

    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.model import load_scenario
    from pilegroup.model.loader import parse_override
    from pilegroup.studies.run.memory_check import estimated_peak_mb, memory_on_mesh

    sc = load_scenario("pier667", dict(parse_override(kv) for kv in (
        'numerics.symmetry="none"', "numerics.mesh.size_m=0.3")))
    geo, comm, n = resolve_geometry(sc), MPI.COMM_WORLD, 426_116
    in_core = estimated_peak_mb(n, "direct_reuse", comm.size)
    before = {"preset": "direct_reuse", "budget_mb_per_rank": 0.95 * in_core}
    rec = memory_on_mesh(sc, geo, n, comm, before)
    assert rec["preset"] == "direct_reuse_ooc" and rec["counted_unknowns"] == n
    assert rec["estimate_on_mesh_mb_per_rank"] < 0.95 * in_core
    rec = memory_on_mesh(sc, geo, n, comm, before | {"budget_mb_per_rank": 1.05 * in_core})
    assert rec["preset"] == "direct_reuse"


def test_a_batch_case_plans_on_its_ranks_share_of_the_node():
    """Serially the one case gets the node's memory (given, or available); the two-rank run
    of tests/studies/test_batch.py checks the share of cases side by side."""
    from mpi4py import MPI

    from pilegroup.studies.run.memory_check import available_mb, case_memory_mb

    world = MPI.COMM_WORLD
    if world.size == 1:
        assert case_memory_mb(world, world, 8000.0) == pytest.approx(8000.0)
        assert case_memory_mb(world, world) == pytest.approx(available_mb(), rel=0.2)
    single = world.Split(world.rank)
    try:
        assert case_memory_mb(world, single, 8000.0) == pytest.approx(8000.0 / world.size)
    finally:
        single.Free()


def test_refusal_names_the_element_and_the_keys_to_change():
    from mpi4py import MPI

    from pilegroup.errors import MachineTooSmall
    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.model import load_scenario
    from pilegroup.model.loader import parse_override
    from pilegroup.studies.run.memory_check import memory_check

    sets = (*TOO_LARGE, 'numerics.element="Q2Q1"')
    sc = load_scenario("pier667", dict(parse_override(kv) for kv in sets))
    with pytest.raises(MachineTooSmall) as err:
        memory_check(sc, resolve_geometry(sc), MPI.COMM_WORLD)
    text = str(err.value)
    assert "numerics.element = 'Q2Q1'" in text and "'Q1Q1'" in text
    assert "remove numerics.mesh.far_field_size_m" in text and "numerics.mesh.scale" in text
