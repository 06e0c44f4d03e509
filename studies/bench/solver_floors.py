"""The cost of each piece of a linear solve on a scenario's own Jacobian: the floors.

``mpirun -n R pilegroup bench floors SCENARIO [--set KEY=VALUE ...]`` builds the scenario's mesh
and problem, runs its geostatic stage and the first step of its first load stage, assembles the
Jacobian there (with the fixed-stress preconditioning matrix) and times, on the ranks of the
run, every piece a Newton solve is made of:

* a matrix–vector product with the whole Jacobian and with each field-split block;
* each block's preconditioner of ``fieldsplit_pier`` on its own: set-up (LU factorisation, AMG
  hierarchy) and one application (triangular solves, one V-cycle), with the options the preset
  gives that block;
* the whole field-split preconditioner: set-up and one application, and the FGMRES solve of a
  random right-hand side to the preset's tolerance (iterations, time);
* the kept LU of ``direct_reuse``: one factorisation and one solve with it.

Times are the median of repeated applications (the set-ups: one each). A whole run's time is
about (Newton solves) x (preconditioner set-ups and Krylov iterations) x these costs, which is
how docs/benchmarks.md reads a run's PETSc log against them. Results: a table on rank 0 and
``bench_floors.json`` and ``bench_floors.md`` in the output folder.
"""

from __future__ import annotations

import platform
import statistics
import time
from collections.abc import Callable, Sequence
from pathlib import Path
from typing import Any

from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.solver.linsolve import create_ksp, merged_options
from pilegroup.studies.bench.benchrun import write_table

COLUMNS = ("piece", "rows", "nonzeros", "set_up_s", "apply_s", "iterations")


class _FirstLoadStep(Exception):
    """Raised by the step callback once the first load step is done (stops the run there)."""


def _timed(comm: MPI.Comm, fn: Callable[[], Any], repeats: int = 1) -> float:
    """Median wall time (s, the slowest rank's) of ``repeats`` calls of ``fn`` (collective)."""
    times = []
    for _ in range(repeats):
        comm.Barrier()
        t0 = time.perf_counter()
        fn()
        times.append(comm.allreduce(time.perf_counter() - t0, op=MPI.MAX))
    return statistics.median(times)


def _block_ksp(comm: MPI.Comm, M: PETSc.Mat, prefix: str, block: str,
               opts: dict[str, Any]) -> PETSc.KSP:
    """A one-application KSP of ``M`` with the preset's options of field-split block ``block``."""
    db = PETSc.Options()
    head = f"fieldsplit_{block}_"
    for k, v in opts.items():
        if k.startswith(head):
            db[f"{prefix}{k[len(head):]}"] = v
    ksp = PETSc.KSP().create(comm)
    ksp.setOptionsPrefix(prefix)
    ksp.setOperators(M)
    ksp.setFromOptions()
    return ksp


def _row(piece: str, M: PETSc.Mat | None, set_up: float | None, apply: float | None,
         its: int | None = None) -> dict[str, Any]:
    rows = M.getSize()[0] if M is not None else None
    nnz = int(M.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]) if M is not None else None
    return {"piece": piece, "rows": rows, "nonzeros": nnz,
            "set_up_s": None if set_up is None else round(set_up, 4),
            "apply_s": None if apply is None else round(apply, 5), "iterations": its}


def _block_rows(comm: MPI.Comm, A: PETSc.Mat, P: PETSc.Mat, splits: list,
                opts: dict[str, Any], repeats: int) -> list[dict[str, Any]]:
    """MatMult, set-up and one application of each block's preconditioner on its own."""
    rows = []
    for name, is_, nns in splits:
        M = P.createSubMatrix(is_, is_)
        if nns is not None:
            M.setNearNullSpace(nns)
        x, y = M.createVecs()
        x.setRandom()
        mult = _timed(comm, lambda M=M, x=x, y=y: M.mult(x, y), repeats)
        rows.append(_row(f"MatMult {name} block", M, None, mult))
        ksp = _block_ksp(comm, M, f"floor_{name}_", name, opts)
        pc = ksp.getPC()
        set_up = _timed(comm, pc.setUp)
        apply = _timed(comm, lambda pc=pc, x=x, y=y: pc.apply(x, y), repeats)
        rows.append(_row(f"{name}: {pc.getType()} set-up / one application", M, set_up, apply))
        ksp.destroy()
        M.destroy()
    return rows


def measure_floors(pb: Any, repeats: int = 5, with_lu: bool = True) -> list[dict[str, Any]]:
    """The rows of the floor table on the current Jacobian of problem ``pb``.

    ``pb``: a :class:`~pilegroup.solver.problem.BiotProblem` built with a field-split preset
    of the blocks ``p``, ``structure``, ``soil`` (collective).
    """
    comm = pb.comm
    pb.assemble_jacobian(force=True)
    solver = pb.linear_solver
    A, P = solver.A, solver.P if solver.P is not None else solver.A
    x, y = A.createVecs()
    x.setRandom()
    rows = [_row("MatMult whole Jacobian", A, None,
                 _timed(comm, lambda: A.mult(x, y), repeats))]
    opts = merged_options("fieldsplit_pier")
    splits = pb.layout.splits(A, solver.spec.splits, pb.options.band_layers or 0)
    rows += _block_rows(comm, A, P, splits, opts, repeats)
    ksp = solver.ksp
    pc = ksp.getPC()
    def first() -> None:  # the blocks are set up at the first application
        ksp.setUp()
        pc.apply(x, y)

    first_apply = _timed(comm, first)
    apply = _timed(comm, lambda: pc.apply(x, y), repeats)
    set_up = first_apply - apply
    rows.append(_row("fieldsplit_pier: set-up / one application", A, set_up, apply))
    b = x.duplicate()
    A.mult(x, b)
    y.set(0.0)
    pc.setReusePreconditioner(True)
    solve = _timed(comm, lambda: ksp.solve(b, y))
    rows.append(_row("fieldsplit_pier: FGMRES solve (kept set-up)", A, None, solve,
                     ksp.getIterationNumber()))
    if with_lu:
        rows.append(_lu_row(comm, A, x, y, repeats))
    return rows


def _lu_row(comm: MPI.Comm, A: PETSc.Mat, x: PETSc.Vec, y: PETSc.Vec,
            repeats: int) -> dict[str, Any]:
    """One factorisation of ``A`` with the options of ``direct_reuse`` and one solve with it."""
    ksp = create_ksp(comm, A, None, "floor_lu_", "direct_reuse")
    pc = ksp.getPC()
    set_up = _timed(comm, pc.setUp)
    apply = _timed(comm, lambda: pc.apply(x, y), repeats)
    ksp.destroy()
    return _row("direct_reuse: block low-rank LU factorisation / one solve", A, set_up, apply)


def bench_floors(scenario: str, sets: Sequence[str] = (), out_dir: str | Path = "out/bench_floors",
                 mesh_size: float | None = None, repeats: int = 5,
                 with_lu: bool = True) -> list[dict[str, Any]]:
    """Time the pieces of a linear solve at the first load step of ``scenario``.

    Builds the scenario (with ``--set`` overrides ``sets``), solves its geostatic stage and
    first load step, then prints and writes the table (collective).
    """
    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.geometry.convert import build_mesh
    from pilegroup.model.loader import load_scenario, parse_override
    from pilegroup.solver.stepping import run_stages
    from pilegroup.studies.run.pipeline import (
        GEOSTATIC_TOL_M,
        build_problem,
        solver_stages,
        time_stepping,
    )

    comm = MPI.COMM_WORLD
    over: dict[str, Any] = dict(parse_override(kv) for kv in sets)
    if mesh_size is not None:
        over["numerics.mesh.size_m"] = mesh_size
    sc = load_scenario(scenario, over)
    geo = resolve_geometry(sc)
    md = build_mesh(geo.spec, comm)
    pb = build_problem(sc, geo, md, preset="fieldsplit_pier")
    stages = [st for st in solver_stages(sc) if st.kind in ("geostatic", "load")][:2]

    def stop(_pb: Any, _t: float, stage: str) -> None:
        if stage == stages[-1].name:
            raise _FirstLoadStep

    try:
        run_stages(pb, stages, time_stepping(sc), on_step=stop, geostatic_tol=GEOSTATIC_TOL_M,
                   t_start=sc.time.start_day)
    except _FirstLoadStep:
        pass
    rows = measure_floors(pb, repeats, with_lu)
    if comm.rank == 0:
        head = (f"{time.strftime('%Y-%m-%d')}, {platform.node()}, {comm.size} MPI ranks, "
                f"{scenario}, {pb.num_dofs} unknowns, symmetry {geo.symmetry}"
                + "".join(f"; --set {kv}" for kv in sets))
        write_table(Path(out_dir), "bench_floors", rows, COLUMNS, head)
    return rows
