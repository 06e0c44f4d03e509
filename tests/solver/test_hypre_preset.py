"""The hypre preset (``fieldsplit_hypre``): the direct answer where PETSc has hypre (tests marked
``hypre``, run in the Docker image by ``tools/container-smoke.sh``; skipped with the reason
elsewhere), and one line and exit 2 where it has none (``auto`` passing it over there:
tests/studies/test_auto_preset.py)."""

import json

import pytest
from mpi4py import MPI

from pilegroup.errors import PresetUnavailable
from pilegroup.geometry.adapter import geometry_spec
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.solver import presets

HAS_HYPRE = presets.has_package("hypre")


@pytest.fixture
def small(tmp_path, monkeypatch, small_pile):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario(small_pile)
    return sc, build_mesh(geometry_spec(sc), MPI.COMM_WORLD)


@pytest.mark.hypre
def test_hypre_preset_gives_the_direct_answer(small, run_preset):
    """BoomerAMG on the soil and the pressure, the kept LU of the structure: the settlement
    of MUMPS LU to 1e-6 (relative), the same Newton iterations, at most 40 Krylov iterations
    per Newton solve, no hand-over to the fallback."""
    sc, md = small
    _, w_ref, log_ref = run_preset(sc, md, "direct")
    pb, w, log = run_preset(sc, md, "fieldsplit_hypre")
    assert pb.linear_solver.preset == "fieldsplit_hypre" and not pb.linear_solver.fallbacks
    assert w == pytest.approx(w_ref, rel=1e-6)
    assert log.newton_total == log_ref.newton_total
    assert max(s.ksp_max for s in log.steps) <= 40


@pytest.mark.hypre
@pytest.mark.mpi
def test_hypre_preset_under_mpirun_gives_the_serial_answer(tmp_path, small_pile, run_cli):
    """``mpirun -n 2`` with the hypre preset settles as the serial run with LU (1e-6)."""
    runs = {}
    for name, ranks, preset in (("lu", 1, "direct"), ("hypre", 2, "fieldsplit_hypre")):
        r = run_cli(small_pile, tmp_path / name, ranks=ranks, timeout=600,
                    sets=(f'numerics.solver.preset="{preset}"', "outputs.xdmf=false",
                          "outputs.plots=false"))
        assert r.returncode == 0, r.stderr[-2000:]
        runs[name] = json.loads((tmp_path / name / "summary_solver.json").read_text())
    assert runs["hypre"]["linear_solver"] == "fieldsplit_hypre"
    assert runs["hypre"]["ksp_iterations_max_per_solve"] <= 40
    assert runs["hypre"]["settlement_m"][-1] == pytest.approx(runs["lu"]["settlement_m"][-1],
                                                              rel=1e-6)


def test_hypre_preset_refused_in_one_line_without_hypre(tmp_path, small_pile, run_cli):
    """A scenario naming the hypre preset on a PETSc without hypre: one line naming the key,
    the preset and what it needs, exit 2, before meshing (no mesh cache written)."""
    if HAS_HYPRE:
        pytest.skip("this PETSc has hypre: the preset runs (tests marked hypre)")
    r = run_cli(small_pile, tmp_path / "run", sets=('numerics.solver.preset="fieldsplit_hypre"',),
                timeout=300)
    assert r.returncode == 2
    lines = [ln for ln in r.stderr.splitlines() if ln.startswith("pilegroup:")]
    assert len(lines) == 1 and "numerics.solver.preset = 'fieldsplit_hypre'" in lines[0]
    assert "hypre" in lines[0].split("needs")[1] and "Traceback" not in r.stderr
    assert not (tmp_path / "cache").exists()


def test_check_available_names_the_missing_package(monkeypatch):
    """``check_available`` raises :class:`PresetUnavailable` for a preset whose package this
    PETSc lacks and passes a preset without requirements."""
    monkeypatch.setattr(presets, "has_package", lambda package: False)
    with pytest.raises(PresetUnavailable, match="needs a PETSc with hypre"):
        presets.check_available("fieldsplit_hypre")
    presets.check_available("direct_reuse")
    assert presets.missing_packages("fieldsplit_hypre") == ("hypre",)
