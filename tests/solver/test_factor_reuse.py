"""The ``direct_reuse`` preset: one LU factorisation serves many Newton iterations and steps,
and the run gives the ``direct`` answer (GMRES on the exact Jacobian, rtol 1e-10)."""

import dataclasses

import numpy as np
import pytest
from mpi4py import MPI

from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.model import load_scenario
from pilegroup.solver.probes import SettlementProbe
from pilegroup.solver.stepping import run_stages
from pilegroup.studies.run import pipeline as pier


@pytest.mark.parametrize("mode", ["tied", "viscoplastic"])
def test_direct_reuse_matches_direct(tmp_path, monkeypatch, mode, small_pile, run_preset):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario(small_pile)
    sc = dataclasses.replace(sc, interface=dataclasses.replace(sc.interface, mode=mode))
    md = build_mesh(geometry_spec(sc), MPI.COMM_WORLD)
    out = {}
    for preset in ("direct", "direct_reuse"):
        pb, w, log = run_preset(sc, md, preset)
        out[preset] = (w, log.newton_total, pb.refactorisations)
    w_direct, newton_direct, factors_direct = out["direct"]
    w_reuse, newton_reuse, factors = out["direct_reuse"]
    assert w_reuse == pytest.approx(w_direct, rel=1e-8)
    assert newton_reuse == newton_direct  # Newton itself is unchanged
    assert 1 <= factors < newton_reuse  # fewer factorisations than Newton iterations
    assert factors_direct >= newton_direct  # direct: one per assembled Newton matrix


def _small_problem(small_pile, tmp_path, monkeypatch, forcing=0.1):
    monkeypatch.setenv("PILEGROUP_MESH_CACHE", str(tmp_path / "cache"))
    sc = load_scenario(small_pile)
    num = sc.numerics
    sc = dataclasses.replace(sc, interface=dataclasses.replace(sc.interface, mode="viscoplastic"),
                             numerics=dataclasses.replace(num, solver=dataclasses.replace(
                                 num.solver, krylov_forcing=forcing)))
    md = build_mesh(geometry_spec(sc), MPI.COMM_WORLD)
    return sc, md, pier.build_problem(sc, resolve_geometry(sc), md, "direct_reuse")


def test_forced_solve_leaves_each_block_within_its_tolerance(tmp_path, monkeypatch, small_pile):
    """Inexact Newton: the weighted GMRES solve stops with every block's true residual below
    its own bound, in fewer iterations than the preset's rtol 1e-10, and the Jacobian is
    restored after the weighting."""
    _, _, pb = _small_problem(small_pile, tmp_path, monkeypatch)
    pb.set_step(0.5, 0.5)
    pb.residual_state(0.5)
    pb.assemble_jacobian()
    pb.solve_linear(pb.b, pb.dx)  # factorises this Jacobian, kept for the next ones
    pb.set_step(2.0, 0.7)  # another step size and load: a new Jacobian, the LU kept
    rn, _ = pb.residual_state(0.7)
    pb.assemble_jacobian()
    norm_A = pb.A.norm()
    full = pb.b.duplicate()
    its_full = pb.solve_linear(pb.b, full)  # no bounds: rtol 1e-10
    block_tol = 1e-4 * rn + 1e-12  # as Newton gives them: never zero
    its = pb.solve_linear(pb.b, pb.dx, block_tol)
    r = pb.b.duplicate()
    pb.A.mult(pb.dx, r)
    r.aypx(-1.0, pb.b)  # b - A dx
    r.setAttr("_blocks", pb.b.getAttr("_blocks"))
    assert np.all(pb.block_norms(r) <= block_tol)
    assert its < its_full
    assert pb.A.norm() == pytest.approx(norm_A, rel=1e-13)


def test_forcing_keeps_newton_and_the_answer(tmp_path, monkeypatch, small_pile):
    """A run with ``krylov_forcing = 0.1`` takes the Newton iterations of one solved to the
    preset's tolerance (``krylov_forcing = 0``) and gives its settlement to the Newton
    tolerance (rtol 1e-8), with fewer Krylov iterations."""
    out = {}
    for forcing in (0.0, 0.1):
        sc, md, pb = _small_problem(small_pile, tmp_path, monkeypatch, forcing)
        probe = SettlementProbe(pb, pier.loaded_facets(sc, md))
        log = run_stages(pb, pier.solver_stages(sc), pier.time_stepping(sc),
                         geostatic_tol=pier.GEOSTATIC_TOL_M)
        out[forcing] = (probe(), log.newton_total, sum(s.ksp_its for s in log.steps))
    assert out[0.1][0] == pytest.approx(out[0.0][0], rel=1e-8)
    assert out[0.1][1] == out[0.0][1]
    assert out[0.1][2] < out[0.0][2]


def _shifted_laplacian(n: int, block: int):
    """``n`` x ``n`` serial AIJ: 1D Laplacians of ``block`` rows each, shifted (diagonal 2.5):
    well conditioned, not trivial."""
    from petsc4py import PETSc

    A = PETSc.Mat().createAIJ([n, n], nnz=3, comm=PETSc.COMM_SELF)
    for i in range(n):
        A.setValue(i, i, 2.5)
        if i % block:
            A.setValue(i, i - 1, -1.0)
            A.setValue(i - 1, i, -1.0)
    A.assemble()
    return A


def test_kept_lu_is_single_precision(monkeypatch):
    """``direct_reuse`` factorises in single precision (one solve with a fresh factorisation
    leaves a residual of single-precision size, the double preset one of double size); a
    PETSc whose MUMPS has no single precision gets the double factorisation instead."""
    from pilegroup.solver import linsolve, presets

    n = 400
    A = _shifted_laplacian(n, n)
    b, x, r = A.createVecLeft(), A.createVecLeft(), A.createVecLeft()
    b.setArray(np.sin(np.arange(n) + 1.0))
    residual = {}
    for preset in ("direct_reuse", "direct_reuse_double"):
        ksp = linsolve.create_ksp(MPI.COMM_SELF, A, None, f"prec_{preset}_", preset,
                                  {"ksp_max_it": 1, "mat_mumps_icntl_35": 0})
        ksp.setConvergenceTest(lambda *args: 0)  # one iteration, whatever it reaches
        ksp.solve(b, x)
        A.mult(x, r)
        r.axpy(-1.0, b)
        residual[preset] = r.norm() / b.norm()
        ksp.destroy()
    assert 1e-9 < residual["direct_reuse"] < 1e-4  # single: about 1e-7
    assert residual["direct_reuse_double"] < 1e-12
    assert presets.mumps_single_precision()
    monkeypatch.setattr(presets, "mumps_single_precision", lambda: False)
    assert linsolve.merged_options("direct_reuse")["pc_precision"] == "double"


def test_split_lu_blocks_are_single_precision(monkeypatch):
    """The field splits factorise their pressure and structure blocks in single precision
    (one application of each block's LU leaves a residual of single-precision size); a PETSc
    whose MUMPS has no single precision gets double factorisations of them instead."""
    from petsc4py import PETSc

    from pilegroup.solver import linsolve, presets

    A = _shifted_laplacian(300, 100)  # three decoupled blocks, one per split
    blocks = [(name, PETSc.IS().createStride(100, 100 * k, 1, comm=PETSc.COMM_SELF), None)
              for k, name in enumerate(("p", "structure", "soil"))]
    ksp = linsolve.create_ksp(MPI.COMM_SELF, A, None, "prec_split_", "fieldsplit_pier", None,
                              blocks)
    ksp.setUp()
    for name, sub in zip(("p", "structure"), ksp.getPC().getFieldSplitSubKSP()[:2], strict=True):
        B = sub.getOperators()[0]
        x, y, r = B.createVecLeft(), B.createVecLeft(), B.createVecLeft()
        x.setArray(np.sin(np.arange(100) + 1.0))
        sub.getPC().apply(x, y)
        B.mult(y, r)
        r.axpy(-1.0, x)
        assert 1e-9 < r.norm() / x.norm() < 1e-4, name  # single: about 1e-7
    ksp.destroy()
    monkeypatch.setattr(presets, "mumps_single_precision", lambda: False)
    opts = linsolve.merged_options("fieldsplit_kept")
    assert opts["fieldsplit_p_pc_precision"] == opts["fieldsplit_structure_pc_precision"] \
        == "double"


def test_first_solve_of_a_step_leaves_the_refactorisation_to_the_next():
    """A step's first solve beyond the limit keeps the factorisation when the step's next
    solve is within it (the matrix at a step's start is unlike the step's others); when the
    step ends after that first solve, the next step's first solve refactors; any other solve
    beyond the limit refactors at the next solve, as before."""
    from pilegroup.solver.linsolve import KSPSolver

    n = 400
    A = _shifted_laplacian(n, n)
    ls = KSPSolver(MPI.COMM_SELF, A, "reuse_policy_", "direct_reuse", None, lambda p: None)
    b, x = A.createVecLeft(), A.createVecLeft()
    b.setArray(np.sin(np.arange(n) + 1.0))
    base = np.full(n, 2.5)
    far = base + 8.0 * np.random.default_rng(1).random(n)  # 37 iterations on base's LU

    def solve(diagonal, new_step=False):
        for i in range(n):
            A.setValue(i, i, diagonal[i])
        A.assemble()
        ls.set_operators(A, None)
        if new_step:
            ls.new_step()
        return ls.solve(b, x, False), ls.refactorisations

    fresh, _ = solve(base, new_step=True)
    assert ls.refactorisations == 1
    limit = ls.spec.reuse_factor_its
    its, factors = solve(far, new_step=True)  # a step's first solve, beyond the limit
    assert its > fresh + limit and factors == 1
    its, factors = solve(base)  # the step's next: within, so the factorisation stays
    assert its <= fresh + limit and factors == 1
    solve(far, new_step=True)  # beyond the limit, and the step ends there
    _, factors = solve(far, new_step=True)  # so the next step's first solve refactors
    assert factors == 2
    solve(base, new_step=True)  # on far's LU: beyond the limit
    its, factors = solve(far)  # within the step: decided as before, no refactorisation...
    assert factors == 2
    solve(base)  # ...but a solve beyond the limit that is not a step's first refactors next
    _, factors = solve(base)
    assert factors == 3
    ls.close()


def test_a_step_far_longer_or_shorter_than_the_kept_lus_refactors_at_once():
    """The Jacobian's flow block scales with dt: a step whose dt is REFACTOR_DT_RATIO times
    the kept LU's (or a fraction of it) refactors at its first solve, even on the same matrix;
    a step within the ratio keeps the LU."""
    from pilegroup.solver.linsolve import REFACTOR_DT_RATIO, KSPSolver, dt_ratio

    assert dt_ratio(1.0, 8.0) == dt_ratio(8.0, 1.0) == 8.0 and dt_ratio(0.0, 5.0) == 1.0
    n = 200
    A = _shifted_laplacian(n, n)
    ls = KSPSolver(MPI.COMM_SELF, A, "reuse_dt_", "direct_reuse", None, lambda p: None)
    b, x = A.createVecLeft(), A.createVecLeft()
    b.setArray(np.sin(np.arange(n) + 1.0))

    def step(dt):
        ls.set_operators(A, None)
        ls.new_step(dt)
        ls.solve(b, x, False)
        return ls.refactorisations

    assert step(1.0) == 1
    assert step(0.5 * REFACTOR_DT_RATIO) == 1  # within the ratio: kept
    assert step(REFACTOR_DT_RATIO) == 2  # 8 times the LU's dt of 1 day: refactored
    assert step(REFACTOR_DT_RATIO / 2) == 2
    assert step(0.9) == 3  # 8.9 times shorter than the LU's
    assert step(0.0) == 3  # no flow block (geostatic, undrained): no comparison
    ls.close()
