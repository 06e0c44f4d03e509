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
