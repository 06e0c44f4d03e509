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
    Stage,
    SurfaceLoad,
    TimeStepping,
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
    stages = stages or [Stage("geo", "geostatic"), Stage("load", "load", 0.0, 1.0),
                        Stage("cons", "consolidation", 2.0)]
    log = run_stages(pb, stages, TimeStepping(dt0=0.25, dt_min=1e-3))
    return pb, log


def test_failing_fieldsplit_falls_back_to_direct_reuse(caplog):
    """An instantaneous (undrained) load step that fieldsplit cannot solve: the fallback solves
    the same step, so the answer is the direct solver's."""
    ref, ref_log = _run("direct")
    with caplog.at_level(logging.WARNING, logger="pilegroup.solver.linsolve"):
        pb, log = _run("fieldsplit_gamg", {"ksp_max_it": 1})
    assert pb.linear_solver.preset == "direct_reuse"
    assert len(pb.linear_solver.fallbacks) == 1
    assert "'fieldsplit_gamg' failed" in pb.linear_solver.fallbacks[0]
    if MPI.COMM_WORLD.rank == 0:
        warnings = [r for r in caplog.records if r.levelno == logging.WARNING]
        assert len(warnings) == 1
    assert [s.dt for s in log.steps] == [s.dt for s in ref_log.steps]
    assert pb.max_displacement() == pytest.approx(ref.max_displacement(), rel=1e-8)
    p, p_ref = pb.p.x.array, ref.p.x.array
    assert np.max(np.abs(p - p_ref)) <= 1e-8 * max(np.max(np.abs(p_ref)), 1e-30)


def test_fallback_after_the_step_is_cut_to_dt_min():
    """A ramped load: the failing step is cut back to dt_min first, then the fallback goes on."""
    stages = [Stage("geo", "geostatic"), Stage("load", "load", 0.5, 1.0)]
    pb, log = _run("fieldsplit_gamg", {"ksp_max_it": 1}, stages)
    assert pb.linear_solver.preset == "direct_reuse" and log.rejected >= 1
    assert log.steps[-1].t == pytest.approx(0.5) and log.steps[-1].load_factor == 1.0


def test_a_preset_without_fallback_fails_the_step():
    with pytest.raises(SolverError, match="KSP diverged"):
        _run("direct", {"ksp_type": "gmres", "pc_type": "jacobi", "ksp_max_it": 1})


@pytest.mark.mpi
def test_linear_fallback_under_mpirun(rerun_under_mpirun):
    rerun_under_mpirun(__file__)
