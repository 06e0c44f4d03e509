"""The cost of each piece of a linear solve on a scenario's own Jacobian: the floors.

``mpirun -n R pilegroup bench floors SCENARIO [--set KEY=VALUE ...]`` builds the scenario's mesh
and problem, runs its geostatic stage and the first two steps of its first load stage, assembles
the Jacobian there (with the fixed-stress preconditioning matrix) and times, on the ranks of the
run, every piece a Newton solve is made of:

* a matrix–vector product with the whole Jacobian and with each field-split block;
* each block's preconditioner of the field-split preset measured (``fieldsplit_pier``, or
  ``--presets NAME``, e.g. ``fieldsplit_hypre`` where PETSc has hypre) on its own: set-up (LU
  factorisation, AMG hierarchy) and one application (triangular solves, one V-cycle), with the
  options the preset gives that block;
* the whole field-split preconditioner: set-up and one application, and the FGMRES solve to the
  preset's tolerance (iterations, time) of ``A d = b``, ``d`` the second load step's increment
  (smooth, as a Newton correction is; a random ``d`` is far easier for a split);
* the iteration floors: the same FGMRES solve with every block of the split solved exactly
  (MUMPS LU in double precision), and with the two-block displacement–pressure split of the
  fixed-stress scheme solved exactly: the iterations that no better block preconditioner goes
  below, the first from the blocks' coupling (the displacement split between structure and
  soil, the band's width), the second from the fixed-stress splitting alone;
* the kept LU of ``direct_reuse``: one factorisation and one solve with it, and its FGMRES
  iterations on the same ``A d = b``;
* the machine's own floors, every rank at once: the memory bandwidth of a streaming pass
  (numpy, single precision) and the single-precision matrix product's rate (numpy's BLAS, one
  thread per rank as in a run). From them the ``floor_s`` of a matrix–vector product (its
  values and column indices read once) and of a solve with the kept LU (the effective factor
  entries MUMPS reports, ``INFOG(35)``, read once in single precision): what that piece would
  take at the machine's bandwidth, against the measured ``apply_s``.

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

import numpy as np
from mpi4py import MPI
from petsc4py import PETSc

from pilegroup.errors import ScenarioError
from pilegroup.solver.linsolve import clear_options, create_ksp, get_preset, merged_options
from pilegroup.solver.presets import check_available
from pilegroup.studies.bench.benchrun import write_table

COLUMNS = ("piece", "rows", "nonzeros", "set_up_s", "apply_s", "iterations", "floor_s", "rate")
#: Bytes per nonzero of an AIJ product (a double value and a 32-bit column index).
AIJ_BYTES = 12
#: Single-precision words of the streaming pass per rank (200 MB each of three arrays).
STREAM_WORDS = 50_000_000
#: Order of the single-precision matrix product timed.
GEMM_N = 2000
#: A field-split block solved exactly (the iteration floors).
EXACT_BLOCK = {"ksp_type": "preonly", "pc_type": "lu", "pc_factor_mat_solver_type": "mumps",
               "pc_precision": "double"}


class _SecondLoadStep(Exception):
    """Raised by the step callback once the second load step is done (stops the run there)."""


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
         its: int | None = None, floor: float | None = None,
         rate: str | None = None) -> dict[str, Any]:
    rows = M.getSize()[0] if M is not None else None
    nnz = int(M.getInfo(PETSc.Mat.InfoType.GLOBAL_SUM)["nz_used"]) if M is not None else None
    return {"piece": piece, "rows": rows, "nonzeros": nnz,
            "set_up_s": None if set_up is None else round(set_up, 4),
            "apply_s": None if apply is None else round(apply, 5), "iterations": its,
            "floor_s": None if floor is None else float(f"{floor:.3g}"), "rate": rate}


def machine_rates(comm: MPI.Comm, repeats: int = 5) -> tuple[float, float]:
    """``(bytes/s, flop/s)`` per rank with every rank at once: a streaming pass, a matrix product.

    The pass is ``c = 2 a; c += b`` over single-precision arrays of :data:`STREAM_WORDS` (five
    words moved per entry); the product is of two :data:`GEMM_N` square single-precision
    matrices. Best of ``repeats``, the slowest rank's (collective).
    """
    a, b = np.ones(STREAM_WORDS, np.float32), np.ones(STREAM_WORDS, np.float32)
    c = np.empty_like(a)

    def stream() -> None:
        np.multiply(a, 2.0, out=c)
        np.add(c, b, out=c)

    rng = np.random.default_rng(comm.rank)
    x, y = (rng.random((GEMM_N, GEMM_N), dtype=np.float32) for _ in range(2))
    t_stream = min(_timed(comm, stream) for _ in range(repeats))
    t_gemm = min(_timed(comm, lambda: x @ y) for _ in range(repeats))
    return 5 * 4 * STREAM_WORDS / t_stream, 2.0 * GEMM_N ** 3 / t_gemm


def mumps_count(value: int) -> float:
    """A MUMPS ``INFO``/``INFOG`` count: negative values are millions."""
    return float(value) if value >= 0 else -1e6 * value


def _machine_rows(comm: MPI.Comm) -> tuple[list[dict[str, Any]], float]:
    """The machine's rows and its bandwidth per rank (bytes/s)."""
    bandwidth, flops = machine_rates(comm)
    return [_row("machine: streaming pass, every rank at once", None, None, None,
                 rate=f"{bandwidth / 1e9:.1f} GB/s per rank"),
            _row("machine: single-precision matrix product, every rank at once", None, None,
                 None, rate=f"{flops / 1e9:.1f} GFlop/s per rank")], bandwidth


def _mult_floor(comm: MPI.Comm, M: PETSc.Mat, bandwidth: float) -> float:
    """Seconds of one product with ``M`` at ``bandwidth``: the largest rank's nonzeros read."""
    local = M.getInfo(PETSc.Mat.InfoType.LOCAL)["nz_used"]
    return comm.allreduce(local, op=MPI.MAX) * AIJ_BYTES / bandwidth


def _block_rows(comm: MPI.Comm, A: PETSc.Mat, P: PETSc.Mat, splits: list,
                opts: dict[str, Any], repeats: int, bandwidth: float) -> list[dict[str, Any]]:
    """MatMult, set-up and one application of each block's preconditioner on its own."""
    rows = []
    for name, is_, nns in splits:
        M = P.createSubMatrix(is_, is_)
        if nns is not None:
            M.setNearNullSpace(nns)
        x, y = M.createVecs()
        x.setRandom()
        mult = _timed(comm, lambda M=M, x=x, y=y: M.mult(x, y), repeats)
        rows.append(_row(f"MatMult {name} block", M, None, mult,
                         floor=_mult_floor(comm, M, bandwidth)))
        ksp = _block_ksp(comm, M, f"floor_{name}_", name, opts)
        pc = ksp.getPC()
        set_up = _timed(comm, pc.setUp)
        apply = _timed(comm, lambda pc=pc, x=x, y=y: pc.apply(x, y), repeats)
        rows.append(_row(f"{name}: {pc.getType()} set-up / one application", M, set_up, apply))
        ksp.destroy()
        M.destroy()
    return rows


def measure_floors(pb: Any, repeats: int = 5, with_lu: bool = True,
                   solution: PETSc.Vec | None = None) -> list[dict[str, Any]]:
    """The rows of the floor table on the current Jacobian of problem ``pb``.

    ``pb``: a :class:`~pilegroup.solver.problem.BiotProblem` built with the field-split preset
    measured. The FGMRES solves have the right-hand side ``A solution``: ``solution`` is a
    step's increment (smooth, as a Newton correction is: random vectors are far easier for a
    split), or a random vector where none is given (collective).
    """
    comm = pb.comm
    rows, bandwidth = _machine_rows(comm)
    pb.assemble_jacobian(force=True)
    solver = pb.linear_solver
    name = solver.spec.name
    A, P = solver.A, solver.P if solver.P is not None else solver.A
    x, y = A.createVecs()
    x.setRandom()
    rows.append(_row("MatMult whole Jacobian", A, None,
                     _timed(comm, lambda: A.mult(x, y), repeats),
                     floor=_mult_floor(comm, A, bandwidth)))
    band = solver.spec.band_layers if pb.options.band_layers is None else pb.options.band_layers
    splits = pb.layout.splits(A, solver.spec.splits, band)
    rows += _block_rows(comm, A, P, splits, merged_options(name), repeats, bandwidth)
    ksp = solver.ksp
    pc = ksp.getPC()
    def first() -> None:  # the blocks are set up at the first application
        ksp.setUp()
        pc.apply(x, y)

    first_apply = _timed(comm, first)
    apply = _timed(comm, lambda: pc.apply(x, y), repeats)
    rows.append(_row(f"{name}: set-up / one application", A, first_apply - apply, apply))
    b = x.duplicate()
    A.mult(x if solution is None else solution, b)
    y.set(0.0)
    pc.setReusePreconditioner(True)
    solve = _timed(comm, lambda: ksp.solve(b, y))
    rows.append(_row(f"{name}: FGMRES solve (kept set-up)", A, None, solve,
                     ksp.getIterationNumber(), rate=_reason(ksp)))
    rows += _iteration_floors(pb, A, P, b, y, splits)
    if with_lu:
        rows.append(_lu_row(comm, A, x, y, repeats, bandwidth, b))
    return rows


def _reason(ksp: PETSc.KSP) -> str:
    reason = ksp.getConvergedReason()
    return "converged" if reason > 0 else f"not converged (reason {reason})"


def _iteration_floors(pb: Any, A: PETSc.Mat, P: PETSc.Mat, b: PETSc.Vec, y: PETSc.Vec,
                      splits: list) -> list[dict[str, Any]]:
    """FGMRES solves of ``A y = b`` with the blocks of a split solved exactly (:data:`EXACT_BLOCK`).

    The split measured (its index sets ``splits``) and the two-block displacement–pressure
    split of ``fieldsplit_gamg`` (fixed-stress), each to the measured preset's tolerance.
    """
    comm, measured = pb.comm, pb.linear_solver.spec
    tol = {"ksp_rtol": merged_options(measured.name)["ksp_rtol"], "ksp_max_it": 400,
           "ksp_gmres_restart": 400}
    u_p = get_preset("fieldsplit_gamg").splits
    rows = []
    for name, what, sets in (
            (measured.name, "every block by LU", splits),
            ("fieldsplit_gamg", "displacement and pressure blocks by LU (the fixed-stress floor)",
             pb.layout.splits(A, u_p))):
        exact = {f"fieldsplit_{blk}_{k}": v for blk in get_preset(name).splits
                 for k, v in EXACT_BLOCK.items()}
        ksp = create_ksp(comm, A, P, "floor_exact_", name, {**exact, **tol}, sets)
        y.set(0.0)
        solve = _timed(comm, lambda ksp=ksp: ksp.solve(b, y))
        rows.append(_row(f"{name}: FGMRES, {what}", A, None, solve, ksp.getIterationNumber(),
                         rate=_reason(ksp)))
        ksp.destroy()
    clear_options("floor_exact_")
    return rows


def _lu_row(comm: MPI.Comm, A: PETSc.Mat, x: PETSc.Vec, y: PETSc.Vec,
            repeats: int, bandwidth: float, b: PETSc.Vec) -> dict[str, Any]:
    """One factorisation of ``A`` with the options of ``direct_reuse`` and one solve with it.

    The row's iterations: those of the preset's FGMRES solve of ``A y = b`` with that LU.

    The solve's floor reads the largest rank's share of the effective (compressed) factor
    entries once, 4 bytes each in single precision (the preset's, where this PETSc's MUMPS has
    it) and 8 in double; a rank's share is its share of the uncompressed entries
    (``INFO(27)``).
    """
    word = 4 if merged_options("direct_reuse").get("pc_precision") == "single" else 8
    ksp = create_ksp(comm, A, None, "floor_lu_", "direct_reuse")
    pc = ksp.getPC()
    set_up = _timed(comm, pc.setUp)
    apply = _timed(comm, lambda: pc.apply(x, y), repeats)
    y.set(0.0)
    ksp.solve(b, y)
    its = ksp.getIterationNumber()
    F = pc.getFactorMatrix()
    effective = mumps_count(F.getMumpsInfog(35))
    local = mumps_count(F.getMumpsInfo(27))
    share = comm.allreduce(local, op=MPI.MAX) / max(comm.allreduce(local), 1.0)
    ksp.destroy()
    return _row("direct_reuse: block low-rank LU factorisation / one solve", A, set_up, apply,
                its, floor=effective * share * word / bandwidth,
                rate=f"{effective:.3g} factor entries, {share:.0%} on the largest rank")


def bench_floors(scenario: str, sets: Sequence[str] = (), out_dir: str | Path = "out/bench_floors",
                 mesh_size: float | None = None, repeats: int = 5,
                 with_lu: bool = True, preset: str = "fieldsplit_pier") -> list[dict[str, Any]]:
    """Time the pieces of a linear solve at the second load step of ``scenario``.

    Builds the scenario (with ``--set`` overrides ``sets``) with the field-split preset
    ``preset``, solves its geostatic stage and first two load steps, then prints and writes the
    table (collective).
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

    if not get_preset(preset).fieldsplit:
        raise ScenarioError.invalid("bench floors --presets", preset, "a field-split preset")
    comm = MPI.COMM_WORLD
    over: dict[str, Any] = dict(parse_override(kv) for kv in sets)
    if mesh_size is not None:
        over["numerics.mesh.size_m"] = mesh_size
    sc = load_scenario(scenario, over)
    geo = resolve_geometry(sc)
    check_available(preset, "bench floors --presets")
    md = build_mesh(geo.spec, comm)
    pb = build_problem(sc, geo, md, preset=preset)
    stages = [st for st in solver_stages(sc) if st.kind in ("geostatic", "load")][:2]

    before, after = pb.x.duplicate(), pb.x.duplicate()
    load_steps = [0]

    def stop(_pb: Any, _t: float, stage: str) -> None:
        after.copy(before)
        pb.layout.fields_to_x(after)
        load_steps[0] += stage == stages[-1].name
        if load_steps[0] == 2:
            raise _SecondLoadStep

    try:
        run_stages(pb, stages, time_stepping(sc), on_step=stop, geostatic_tol=GEOSTATIC_TOL_M,
                   t_start=sc.time.start_day)
    except _SecondLoadStep:
        pass
    after.axpy(-1.0, before)  # the second load step's increment
    rows = measure_floors(pb, repeats, with_lu, solution=after)
    if comm.rank == 0:
        head = (f"{time.strftime('%Y-%m-%d')}, {platform.node()}, {comm.size} MPI ranks, "
                f"{scenario}, {pb.num_dofs} unknowns, symmetry {geo.symmetry}, {preset}"
                + "".join(f"; --set {kv}" for kv in sets))
        write_table(Path(out_dir), "bench_floors", rows, COLUMNS, head)
    return rows
