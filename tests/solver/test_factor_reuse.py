"""The ``direct_reuse`` preset: one LU factorisation serves many Newton iterations and steps,
and the run gives the ``direct`` answer (GMRES on the exact Jacobian, rtol 1e-10)."""

import dataclasses

import pytest
from mpi4py import MPI

from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.solver.probes import SettlementProbe
from pilegroup.solver.stepping import run_stages
from pilegroup.studies.run import pipeline as pier


@pytest.mark.parametrize("mode", ["tied", "viscoplastic"])
def test_direct_reuse_matches_direct(tmp_path, monkeypatch, mode, small_pile):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario(small_pile)
    sc = dataclasses.replace(sc, interface=dataclasses.replace(sc.interface, mode=mode))
    md = build_mesh(geometry_spec(sc), MPI.COMM_WORLD)
    out = {}
    for preset in ("direct", "direct_reuse"):
        pb = pier.build_problem(sc, resolve_geometry(sc), md, preset)
        probe = SettlementProbe(pb, pier.loaded_facets(sc, md))
        log = run_stages(pb, pier.solver_stages(sc), pier.time_stepping(sc),
                         geostatic_tol=pier.GEOSTATIC_TOL_M)
        out[preset] = (probe(), log.newton_total, pb.refactorisations)
    w_direct, newton_direct, factors_direct = out["direct"]
    w_reuse, newton_reuse, factors = out["direct_reuse"]
    assert w_reuse == pytest.approx(w_direct, rel=1e-8)
    assert newton_reuse == newton_direct  # Newton itself is unchanged
    assert 1 <= factors < newton_reuse  # fewer factorisations than Newton iterations
    assert factors_direct >= newton_direct  # direct: one per assembled Newton matrix
