"""The scenario's numerics reach the solver (no silently ignored key)."""

import dataclasses

from mpi4py import MPI

from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.studies.run import pipeline as pier


def test_newton_settings_reach_the_solver(tmp_path, monkeypatch, small_pile):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario(small_pile)
    num = dataclasses.replace(sc.numerics, newton_rtol=3e-7, newton_atol=2e-10,
                              time=dataclasses.replace(sc.numerics.time, max_newton=7))
    sc = dataclasses.replace(sc, numerics=num)
    pb = pier.build_problem(sc, resolve_geometry(sc), build_mesh(geometry_spec(sc), MPI.COMM_WORLD))
    nw = pb.options.newton
    assert (nw.rtol, nw.atol, nw.max_it) == (3e-7, 2e-10, 7)



def test_auto_preset_by_size():
    """``auto``: one LU per matrix when small, a kept LU when larger."""
    assert pier.auto_preset(pier.DIRECT_MAX_DOFS) == "direct"
    assert pier.auto_preset(pier.DIRECT_MAX_DOFS + 1) == "direct_reuse"
    assert pier.auto_preset(10 ** 7) == "direct_reuse"


def test_auto_preset_reaches_the_solver(tmp_path, monkeypatch, small_pile):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(pier, "DIRECT_MAX_DOFS", 0)
    sc = load_scenario(small_pile, {"numerics.solver.preset": "auto"})
    pb = pier.build_problem(sc, resolve_geometry(sc), build_mesh(geometry_spec(sc), MPI.COMM_WORLD))
    assert pb.linear_solver.preset == "direct_reuse"
