"""A failing iterative preset hands over to its fallback with one warning and the same answer."""

import logging

import numpy as np
import pytest
from mpi4py import MPI

from pilegroup.constitutive.soil import LinearElastic
from pilegroup.geometry import groups
from pilegroup.geometry.box import build_box
from pilegroup.solver import (
    BiotProblem,
    DisplacementBC,
    PressureBC,
    SoilMaterial,
    SolverError,
    SolverOptions,
    SolverStage,
    StepControl,
    SurfaceLoad,
    run_stages,
)


def _run(preset, overrides=None, stages=None):
    md = build_box(MPI.COMM_WORLD, (0, 1), (0, 1), np.linspace(-4, 0, 9), 2, 2)
    soil = SoilMaterial(LinearElastic(1.0e4, 0.3), 1e-3, 0.4, gamma_sat=18.0)
    bcs = [DisplacementBC(s, c) for s, c in zip(groups.SIDES, (0, 0, 1, 1), strict=True)]
    bcs.append(DisplacementBC(groups.BOTTOM, 2))
    pb = BiotProblem(md, {groups.soil_layer(1): soil}, displacement_bcs=bcs,
                     pressure_bcs=[PressureBC(groups.GROUND)],
                     loads=[SurfaceLoad(groups.GROUND, 50.0)],
                     options=SolverOptions(preset=preset, overrides=overrides or {},
                                           prefix=f"fb_{preset}_"))
    stages = stages or [SolverStage("geo", "geostatic"), SolverStage("load", "load", 0.0, 1.0),
                        SolverStage("cons", "consolidation", 2.0)]
    log = run_stages(pb, stages, StepControl(dt0=0.25, dt_min=1e-3))
    return pb, log


@pytest.mark.parametrize(("preset", "fallback"), [("fieldsplit_gamg", "direct_reuse"),
                                                ("direct_reuse", "direct_reuse_double"),
                                                ("direct_reuse_ooc", "direct_reuse_ooc_double")])
def test_a_failing_preset_falls_back(caplog, preset, fallback):
    """An instantaneous (undrained) load step that the preset cannot solve (one Krylov
    iteration allowed): its fallback solves the same step, so the answer is the direct
    solver's. The split hands over to the kept LU; the kept single-precision LU to the same
    method in double precision, in core or, for the out-of-core LU (taken when memory is
    short), out of core."""
    ref, ref_log = _run("direct")
    with caplog.at_level(logging.WARNING, logger="pilegroup.solver.linsolve"):
        pb, log = _run(preset, {"ksp_max_it": 1})
    assert pb.linear_solver.preset == fallback
    assert pb.linear_solver.spec.out_of_core == preset.endswith("_ooc")
    assert len(pb.linear_solver.fallbacks) == 1
    assert f"'{preset}' failed" in pb.linear_solver.fallbacks[0]
    if MPI.COMM_WORLD.rank == 0:
        warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
        assert len(warnings) == 1
    assert [s.dt for s in log.steps] == [s.dt for s in ref_log.steps]
    assert pb.max_displacement() == pytest.approx(ref.max_displacement(), rel=1e-8)
    p, p_ref = pb.p.x.array, ref.p.x.array
    assert np.max(np.abs(p - p_ref)) <= 1e-8 * max(np.max(np.abs(p_ref)), 1e-30)
    pb.linear_solver.close()  # MUMPS ends before its out-of-core folder goes


def test_a_failed_krylov_solve_hands_over_without_cutting_the_step():
    """A ramped load: the step whose Krylov solve fails is tried again at once, at the same
    size, with the fallback (a smaller step does not cure a preconditioner), so the run takes
    the direct solver's steps and gives its answer."""
    stages = [SolverStage("geo", "geostatic"), SolverStage("load", "load", 0.5, 1.0)]
    ref, ref_log = _run("direct", stages=stages)
    pb, log = _run("fieldsplit_gamg", {"ksp_max_it": 1}, stages)
    assert pb.linear_solver.preset == "direct_reuse" and len(pb.linear_solver.fallbacks) == 1
    assert log.rejected == 1 and ref_log.rejected == 0
    assert [s.dt for s in log.steps] == [s.dt for s in ref_log.steps]
    assert log.steps[-1].t == pytest.approx(0.5) and log.steps[-1].load_factor == 1.0
    assert pb.max_displacement() == pytest.approx(ref.max_displacement(), rel=1e-8)


def test_a_preset_without_fallback_fails_the_step():
    with pytest.raises(SolverError, match="KSP diverged"):
        _run("direct", {"ksp_type": "gmres", "pc_type": "jacobi", "ksp_max_it": 1})


@pytest.mark.mpi
def test_linear_fallback_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__, ranks=2, timeout=300)
