"""``auto``: the measured table picks the preset per model part, interface and size; the
benchmark's results regenerate that table."""

import dataclasses

import pytest
from mpi4py import MPI

from pilegroup.errors import SolverInputError
from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.solver.linsolve import PRESETS
from pilegroup.studies.run import auto_preset as ap
from pilegroup.studies.run import pipeline as pier


def test_every_row_names_a_preset_and_the_table_covers_every_system():
    assert all(r.preset in PRESETS for r in ap.AUTO_TABLE)
    assert ap.AUTO_TABLE[0] == ap.SMALL_ROW and ap.AUTO_TABLE[-1] == ap.FALLBACK_ROW
    for model in ("quarter", "half", "none"):
        for itf in (True, False):
            for dofs in (1_000, 80_853, 301_772, 10 ** 7):
                assert ap.auto_preset(dofs, model, itf) in PRESETS
    assert ap.auto_preset(50_000, "none") == "direct"
    assert ap.auto_preset(80_853, "quarter") == "direct_reuse"


def test_split_presets_only_for_piles_with_an_interface():
    """The split presets need the piles as a body of their own: never for tied piles."""
    for model in ("quarter", "half", "none"):
        for dofs in (80_853, 301_772, 10 ** 7):
            assert not ap.auto_preset(dofs, model, False).startswith("fieldsplit")


def test_first_matching_row_wins_and_no_match_is_an_error():
    rows = (ap.AutoRow("none", True, 100, "direct"), ap.AutoRow("none", None, None, "direct_reuse"))
    assert ap.auto_preset(100, "none", True, rows) == "direct"
    assert ap.auto_preset(101, "none", True, rows) == "direct_reuse"
    with pytest.raises(SolverInputError, match="no preset in the auto table.*'quarter'"):
        ap.auto_preset(10, "quarter", True, rows)


def test_table_regenerated_from_benchmark_results():
    """Per (model, interface) and size the fastest complete run wins; the largest size holds
    for larger systems; equal neighbours merge; the printed source evaluates to the rows."""
    res = [{"symmetry": model, "interface": True, "dofs": dofs, "preset": preset,
            "status": status, "wall_s": wall}
           for model, dofs, preset, status, wall in (
               ("none", 301_772, "direct_reuse", "complete", 1287.0),
               ("none", 301_772, "fieldsplit_kept", "complete", 900.0),
               ("none", 426_116, "fieldsplit_kept", "complete", 2000.0),
               ("none", 426_116, "direct_reuse", "failed (timeout)", 100.0),
               ("quarter", 80_853, "direct_reuse", "complete", 85.0),
               ("quarter", 80_853, "fieldsplit_kept", "complete", 120.0))]
    rows = ap.fastest_rows(res)
    assert [(r.model, r.max_dofs, r.preset) for r in rows] == [
        ("none", None, "fieldsplit_kept"), ("quarter", None, "direct_reuse")]
    assert "direct_reuse 1287 s" in rows[0].measured and "failed" not in rows[0].measured
    table = eval(ap.table_source(rows).split("=", 1)[1], vars(ap))  # noqa: S307 - our own text
    assert table == (ap.SMALL_ROW, *rows, ap.FALLBACK_ROW)


@pytest.mark.parametrize("hypre", [False, True])
def test_table_with_a_hypre_preset_serves_a_petsc_without_it(monkeypatch, hypre):
    """Where the hypre preset wins at the large size, the table also holds the other presets'
    rows: a PETSc with hypre takes it past the crossover, one without it the kept LU."""
    from pilegroup.solver import presets

    res = [{"symmetry": "none", "interface": True, "dofs": d, "preset": p, "status": "complete",
            "wall_s": w}
           for d, p, w in ((100_000, "direct_reuse", 50.0), (100_000, "fieldsplit_hypre", 80.0),
                           (900_000, "direct_reuse", 900.0), (900_000, "fieldsplit_hypre", 300.0),
                           (900_000, "fieldsplit_kept", 1200.0))]
    rows = ap.fastest_rows(res)
    assert [(r.max_dofs, r.preset) for r in rows] == [
        (100_000, "direct_reuse"), (None, "fieldsplit_hypre"), (None, "direct_reuse")]
    monkeypatch.setattr(presets, "has_package", lambda package: hypre)
    table = (ap.SMALL_ROW, *rows, ap.FALLBACK_ROW)
    assert ap.auto_preset(90_000, "none", True, table) == "direct_reuse"
    assert ap.auto_preset(2_000_000, "none", True, table) == (
        "fieldsplit_hypre" if hypre else "direct_reuse")


def test_auto_reaches_the_solver(tmp_path, monkeypatch, small_pile):
    """The problem is built with the table's preset for its size, model and interface."""
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    monkeypatch.setattr(ap, "auto_preset", lambda dofs, model, itf: (
        "fieldsplit_kept" if (model, itf) == ("quarter", True) and dofs > 0 else "direct"))
    sc = load_scenario(small_pile, {"numerics.solver.preset": "auto"})
    geo = resolve_geometry(sc)
    pb = pier.build_problem(sc, geo, build_mesh(geometry_spec(sc), MPI.COMM_WORLD))
    assert geo.symmetry == "quarter" and pb.linear_solver.preset == "fieldsplit_kept"
    tied = dataclasses.replace(sc, interface=dataclasses.replace(sc.interface, mode="tied"))
    pb = pier.build_problem(tied, geo, build_mesh(geometry_spec(tied), MPI.COMM_WORLD))
    assert pb.linear_solver.preset == "direct"


def test_every_preset_can_be_named_in_a_scenario():
    """``numerics.solver.preset`` accepts ``auto`` and exactly the presets the solver has."""
    import typing

    from pilegroup.model.analysis import LinearSolver

    named = set(typing.get_args(typing.get_type_hints(LinearSolver)["preset"]))
    assert named == {"auto", *PRESETS}
