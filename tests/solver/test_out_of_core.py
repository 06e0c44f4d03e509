"""The ``direct_reuse_ooc`` preset: the kept LU with its factors out of core gives the in-core
answer, in a folder of its own that goes with the solver; serially and on 2 ranks."""

import dataclasses
import tempfile

import pytest
from mpi4py import MPI

from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.studies.run import pipeline as pier


def test_out_of_core_factors_give_the_in_core_answer(tmp_path, monkeypatch, small_pile,
                                                     run_preset):
    """``direct_reuse_ooc``: MUMPS writes the factors to a folder of the solver's own under
    TMPDIR, the run gives the in-core kept LU's settlement (the same factorisation, read back
    from files), and closing the solver removes the folder with its files."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setenv("TMPDIR", str(tmp_path / "scratch"))
    (tmp_path / "scratch").mkdir()
    monkeypatch.setattr(tempfile, "tempdir", None)  # TMPDIR read anew
    sc = load_scenario(small_pile)
    # Newton to 1e-11: the out-of-core solve reads the factors back block by block and rounds
    # differently from the in-core one, so at the default tolerance (1e-8) the two runs stop at
    # iterates 1.3e-8 apart (measured); converged further, they agree to round-off (1.6e-12).
    sc = dataclasses.replace(
        sc, interface=dataclasses.replace(sc.interface, mode="viscoplastic"),
        numerics=dataclasses.replace(sc.numerics, newton_rtol=1e-11))
    md = build_mesh(geometry_spec(sc), MPI.COMM_WORLD)
    out = {}
    for preset in ("direct_reuse", "direct_reuse_ooc"):
        pb, w, log = run_preset(sc, md, preset)
        folders = sorted((tmp_path / "scratch").glob("pilegroup-ooc-*"))
        files = [f for d in folders for f in d.iterdir()]
        out[preset] = (w, log.newton_total, folders, files)
        pb.linear_solver.close()
        assert not any(d.exists() for d in folders)
    assert out["direct_reuse"][2] == []  # in core: no folder
    w, newton, folders, files = out["direct_reuse_ooc"]
    assert len(folders) == 1 and files  # this rank's folder, MUMPS's factor files in it
    assert w == pytest.approx(out["direct_reuse"][0], rel=1e-10)
    assert newton == out["direct_reuse"][1]


def test_out_of_core_folder_that_cannot_be_made_is_named(tmp_path):
    from pilegroup.errors import SolverInputError
    from pilegroup.solver.mumps import OutOfCoreFolder

    with pytest.raises(SolverInputError, match="mat_mumps_ooc_tmpdir.*no folder"):
        OutOfCoreFolder(tmp_path / "missing" / "deeper")
    folder = OutOfCoreFolder(tmp_path)
    (folder.path / "factor").write_bytes(b"x")
    folder.remove()
    folder.remove()  # once only; the second call does nothing
    assert folder.removed and not folder.path.exists()


def test_out_of_core_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, ranks=2, timeout=300)


def test_a_failed_run_empties_its_factor_files_at_once(
        tmp_path, monkeypatch, small_pile):
    """After a failure this rank's factor files are emptied at once (``abandon``, not
    collective); closing the solver afterwards still works and removes the folder."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario(small_pile)
    md = build_mesh(geometry_spec(sc), MPI.COMM_WORLD)
    opts = {"mat_mumps_ooc_tmpdir": str(tmp_path)}
    sc = dataclasses.replace(sc, numerics=dataclasses.replace(sc.numerics, solver=(
        dataclasses.replace(sc.numerics.solver, options=opts))))
    pb = pier.build_problem(sc, resolve_geometry(sc), md, "direct_reuse_ooc")
    pb.set_step(0.5, 0.5)
    pb.residual_state(0.5)
    pb.assemble_jacobian()
    pb.solve_linear(pb.b, pb.dx)
    (folder,) = tmp_path.glob("pilegroup-ooc-*")
    assert any(folder.iterdir())  # the factors, on this rank's folder under the option's path
    pb.linear_solver.abandon()
    files = list(folder.iterdir())
    assert files and all(f.stat().st_size == 0 for f in files)
    pb.linear_solver.close()  # MUMPS removes its (empty) files, then the folder goes
    assert not folder.exists()
