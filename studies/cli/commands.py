"""The ``pilegroup`` command line.

Exit codes: 0 success, 1 a run failed (e.g. no convergence), 2 invalid input (a clear one-line
message naming the key, the value and what is allowed; no traceback), 130/143/138 a run stopped by
SIGINT/SIGTERM/SIGUSR1 after saving a checkpoint (128 + the signal number).

Under MPI a :class:`~pilegroup.errors.PilegroupError` is raised on every rank alike (the
scenario, the stepper's decisions and the Newton checks are collective), so rank 0 prints its
one line; any other exception may be one rank's alone and ends every rank (:func:`_abort`).
An output file that cannot be written (:class:`~pilegroup.errors.OutputError`, e.g. a CSV file
rank 0 writes) is such an exception: ``pilegroup: run failed: cannot write FILE: why``, exit 1.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import shlex
import signal
import sys
import threading
import traceback
from collections.abc import Sequence
from pathlib import Path

from tqdm import tqdm

from pilegroup.errors import OutputError, RunInterrupted
from pilegroup.fileio import write_text_atomic
from pilegroup.model import BUNDLED, PilegroupError, ScenarioError, load_scenario
from pilegroup.studies.cli.batch_commands import COMMANDS as BATCH_COMMANDS
from pilegroup.studies.cli.batch_commands import memory_size
from pilegroup.studies.cli.lab_commands import COMMANDS as LAB_COMMANDS
from pilegroup.studies.cli.scenario_commands import SET_HELP, scenario_arguments
from pilegroup.studies.cli.scenario_commands import overrides as _overrides
from pilegroup.studies.cli.scenario_commands import world_rank as _world_rank
from pilegroup.studies.run.interrupt import abort_job

log = logging.getLogger("pilegroup")

EXIT_INPUT = 2
EXIT_FAILED = 1
SCENARIO_HELP = "scenario TOML file or bundled name, e.g. pier667"
#: The presets ``pilegroup bench presets`` compares unless ``--presets`` names others.
BENCH_PRESETS = ("direct_reuse", "fieldsplit_kept")

#: Descriptions of the sub-commands (``pilegroup COMMAND --help``).
DESCRIPTIONS = {
    "scenario": ("Show a bundled scenario, validate a scenario file (as a run does before "
                 "meshing) or list every scenario key (docs/scenario.md)."),
    "run": ("Validate the scenario, build its mesh and run every stage that is implemented; write "
            "outputs and summary.json to --out. One run at a time writes into a folder: a "
            "second run into the --out of a running one exits 2 naming the running process."),
    "stiffness": ("Run the scenario as the whole foundation and write, at its end, the cap's 6 x 6"
                  " stiffness matrix about the action point ([actions] point_m; default the cap"
                  " top's centre) to cap_stiffness.csv in --out: six small undrained probe "
                  "increments from the final state (without a cap: the single pile head's "
                  "matrix). --day DAY probes the state at that day (a stage's end or a day in a"
                  " consolidation stage). Everything a run writes is written too."),
    "mesh": ("Mesh the scenario with gmsh (cap, piles, layered soil; plan quads extruded through "
             "the layers), write mesh.xdmf with cell and facet tags (ParaView), "
             "mesh_summary.json, plan.png and cutaway.png, and print counts and quality. Meshes "
             "are cached by their parameters ($PILEGROUP_MESH_CACHE or "
             "~/.cache/pilegroup/meshes)."),
    "verify": ("Run verification cases through the real pipeline and print error, tolerance and "
               "pass/fail per case (exit 1 if any fails). Cases: terzaghi (1D consolidation), "
               "terzaghi-water-table (the same below 2 m of dry soil), "
               "mandel (Mandel-Cryer effect), triaxial (Mohr-Coulomb failure load), "
               "shaft-capacity (pile pushed to shaft failure), interface-patch (solver interface "
               "vs pointwise law), tied-limit (stiff interface vs tied pile), "
               "undrained-loading (a uniform fill on five meshes: uniform pressure), "
               "mcc-undrained-triaxial, mcc-compression-line, ssc-creep, ssc-oedometer (the "
               "soft-soil laws), and the ground, downdrag, lateral and capacity cases. Works "
               "under mpirun -n 2."),
    "bench": ("constitutive: law updates per second; meshing: cells, quality and time for the "
              "paper's five mesh sizes; verification: run time against error for Terzaghi and "
              "Mandel (table, JSON and PNG); pier: the whole job per mesh size and symmetry "
              "(unknowns, Newton and Krylov counts, factorisations, wall, peak memory); "
              "stability: the small scenario under extreme time steps, permeability, "
              "stiffness, loads, interface options and element pairs, each run in its own "
              "process under a timeout (status, counts, settlement, max |p|, NaN check); "
              "floors: the cost of each piece of a linear solve (MatMult, each block's "
              "preconditioner, the whole split, the LU) on the scenario's first load-step "
              "Jacobian, in process (run it under mpirun); presets: the whole job with each "
              "preset per size and model, and the table of `auto` those runs select; "
              "discretisation: each element pair's error on the undrained, lateral and "
              "consolidation cases against wall time and peak memory."),
    "report": ("Read the CSV and JSON files of a finished or interrupted run (settlement.csv, "
               "pile_profiles.csv, layer_history.csv, pile_loads.csv, load_settlement.csv, "
               "gauges.csv, pile_heads.csv, cap_motion.csv, summary.json), write PNG "
               "figures to OUT_DIR/plots (figures whose file is missing are skipped), the "
               "report an engineer hands on to OUT_DIR/report.md and OUT_DIR/report.html "
               "(self-contained: figures embedded, opens offline; a failed or stopped run "
               "says so at its top) and, with --markdown, a results section. A folder that is "
               "not a run or a CSV with a wrong header is invalid input (exit 2)."),
}


def setup_logging(verbose: int) -> None:
    """Log to stderr on rank 0 only (other ranks log warnings and errors)."""
    level = logging.DEBUG if verbose > 1 else logging.INFO
    if _world_rank() != 0:
        level = logging.WARNING
    logging.basicConfig(level=level, format="%(levelname)s %(name)s: %(message)s")


def _cmd_run(args: argparse.Namespace) -> int:
    from pilegroup.studies.run.interrupt import stop_on_signals
    from pilegroup.studies.run.job import run_scenario

    extra = {"outputs.cap_stiffness": True} if args.command == "stiffness" else {}
    sc = load_scenario(args.scenario, _overrides(args) | extra)
    if getattr(args, "day", None) is not None:
        from pilegroup.studies.run.stiffness import scenario_until

        sc = scenario_until(sc, args.day)
    out = Path(args.out) if args.out else Path("out") / sc.name
    with stop_on_signals():  # a stop signal: checkpoint at the next step boundary, then stop
        summary = run_scenario(sc, out, mesh_size=args.mesh_size, stop_after=args.stop_after,
                               resume=args.resume, force=args.force, memory_mb=args.memory)
    if _world_rank() == 0:
        print(json.dumps(summary, indent=2))
    return 0


def _run_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help=SCENARIO_HELP)
    p.add_argument("--out", help="output folder (default: out/<scenario name>)")
    p.add_argument("--mesh-size", type=float, default=None, metavar="H",
                   help="element size at the pile surfaces in m (overrides numerics.mesh.size_m)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help=SET_HELP)
    p.add_argument("--stop-after", choices=["mesh", "solve"], default="solve",
                   help="mesh: validate and mesh only (writes scenario.json, mesh/ and "
                   "summary.json); solve (default): run every stage")
    p.add_argument("--resume", action="store_true",
                   help="continue from the last checkpoint in --out (same scenario, --set "
                   "values and rank count); a complete run is not run again")
    p.add_argument("--force", action="store_true",
                   help="run even when the memory estimate per rank (printed for every run) "
                   "exceeds the memory available per rank (without it: exit 2 before meshing)")
    p.add_argument("--memory", type=memory_size, default=None, metavar="SIZE",
                   help="memory the run may use on each node, e.g. 8GB or 6000MB (default: what "
                   "the node has available); with preset auto a run whose in-core factors "
                   "would exceed it writes them out of core (TMPDIR)")
    p.set_defaults(func=_cmd_run)


def _stiffness_arguments(p: argparse.ArgumentParser) -> None:
    _run_arguments(p)
    p.add_argument("--day", type=float, default=None, metavar="DAY",
                   help="probe the state at this day (default: the scenario's end): a stage's "
                   "end or a day in a consolidation stage; the run ends there")


def _cmd_mesh(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from pilegroup.geometry.adapter import geometry_spec
    from pilegroup.geometry.output import format_summary, mesh_command

    sc = load_scenario(args.scenario, _overrides(args))
    out = Path(args.out) if args.out else Path("out") / sc.name / "mesh"
    summary = mesh_command(geometry_spec(sc, args.mesh_size), None, out, MPI.COMM_WORLD,
                           cache_dir=False if args.no_cache else None, render=not args.no_png)
    if _world_rank() == 0:
        print(format_summary(summary))
    return 0


def _mesh_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("scenario", help=SCENARIO_HELP)
    p.add_argument("--mesh-size", type=float, default=None, metavar="H",
                   help="element size at the pile surfaces in m (paper: 1.0/0.8/0.6/0.3/0.1)")
    p.add_argument("--out", help="output folder (default: out/<scenario>/mesh)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE", help=SET_HELP)
    p.add_argument("--no-cache", action="store_true", help="re-mesh even if cached")
    p.add_argument("--no-png", action="store_true", help="skip the PNG renders")
    p.set_defaults(func=_cmd_mesh)


def _cmd_verify(args: argparse.Namespace) -> int:
    from pilegroup.studies.verification import CASES, run_cases

    unknown = [c for c in args.cases if c not in CASES]
    if unknown:
        raise ScenarioError("CASE", unknown[0], f"unknown case; known: {', '.join(CASES)}")
    res = run_cases(args.cases, size=args.size, json=args.json, pair=args.pair,
                    preset=args.preset, quadrature=args.interface_quadrature)
    return 0 if all(r.passed for r in res) else EXIT_FAILED


def _verify_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("cases", nargs="*", metavar="CASE", help="cases to run (default: all)")
    p.add_argument("--json", action="store_true", help="one JSON object per case")
    p.add_argument("--size", choices=["fast", "bench"], default="fast",
                   help="fast: small meshes (test tier); bench: benchmark sizes")
    p.add_argument("--pair", choices=["Q2Q1", "Q1Q1"], default=None,
                   help="element pair (default: each case's own)")
    p.add_argument("--preset", choices=["direct", "fieldsplit_gamg"], default=None,
                   help="linear solver option set (default: each case's own)")
    p.add_argument("--interface-quadrature", choices=["nodal", "gauss"], default=None,
                   help="interface cases: law at the interface nodes or at facet Gauss "
                   "points (default: nodal)")
    p.set_defaults(func=_cmd_verify)


def _cmd_bench(args: argparse.Namespace) -> int:
    if args.what == "constitutive":
        from pilegroup.studies.bench.laws import main as bench_main

        return bench_main([])
    if args.what == "meshing":
        from pilegroup.studies.bench.meshing import main as bench_main

        return bench_main([str(h) for h in args.sizes or []] + ["--symmetry", *args.symmetry])
    if args.what == "pier":
        from pilegroup.studies.bench.pier_bench import bench_pier

        rows = bench_pier(args.scenario, args.sizes or [1.0], args.symmetry, args.ranks or 2,
                          args.out or "out/bench_pier", args.timeout, args.set or ())
        return 0 if all(r["status"] == "complete" for r in rows) else 1
    if len(args.scenario) > 1:
        raise ScenarioError("--scenario", " ".join(args.scenario),
                            f"bench {args.what} runs one scenario (several: bench pier)", "-")
    args.scenario = args.scenario[0]
    if args.what == "presets":
        from pilegroup.studies.bench.preset_bench import bench_presets

        rows = bench_presets(args.presets or list(BENCH_PRESETS), args.scenario,
                             args.sizes or [1.0], args.symmetry, args.ranks or 2,
                             args.out or "out/bench_presets", args.timeout, args.set or ())
        return 0 if any(r["status"] == "complete" for r in rows) else 1
    if args.what == "floors":
        from pilegroup.studies.bench.solver_floors import bench_floors

        if args.presets is not None and len(args.presets) != 1:
            raise ScenarioError.invalid("bench floors --presets", " ".join(args.presets),
                                        "one field-split preset (default: fieldsplit_pier)")
        bench_floors(args.scenario, args.set or (), args.out or "out/bench_floors",
                     (args.sizes or [None])[0],
                     preset=args.presets[0] if args.presets else "fieldsplit_pier")
        return 0
    if args.what == "stability":
        from pilegroup.studies.bench.stability import bench_stability

        rows = bench_stability(args.out or "out/bench_stability", args.cases, args.ranks or 1,
                               args.timeout or 900.0)
        return 0 if all(r["clean"] for r in rows) else 1
    if args.what == "discretisation":
        from pilegroup.studies.bench.discretisation import bench_discretisation

        bench_discretisation(args.out or "out/bench_discretisation",
                             timeout=args.timeout or 1800.0)
        return 0
    from pilegroup.studies.bench.verification_bench import bench_verification

    bench_verification(out_dir=args.out or "out/bench_verification")
    return 0


def _bench_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("what", choices=["constitutive", "meshing", "verification", "pier",
                                    "stability", "floors", "presets", "discretisation"])
    p.add_argument("--sizes", type=float, nargs="*", default=None, metavar="H",
                   help="meshing: pile-surface sizes in m (default: the paper's five); "
                   "pier, presets: the sizes to run (default: 1.0); floors: the one size "
                   "(default: the scenario's)")
    p.add_argument("--out", default=None,
                   help="verification, pier, presets, floors, stability: output folder")
    p.add_argument("--scenario", nargs="+", default=["pier667"],
                   help="pier: the scenarios to run, one after the other (the table gives each "
                   "run's wall time over the first scenario's at the same size and symmetry); "
                   "presets, floors: the one scenario to run (floors: under mpirun, in process)")
    p.add_argument("--symmetry", nargs="*", default=["auto"],
                   help="pier, presets, meshing: the numerics.symmetry values to run (default: "
                   "auto, the part the geometry's symmetry allows)")
    p.add_argument("--ranks", type=int, default=None,
                   help="pier, presets, stability: MPI ranks of each run (default: 2 for pier "
                   "and presets, 1 for stability)")
    p.add_argument("--timeout", type=float, default=None, metavar="S",
                   help="pier, presets, stability: seconds each run may take before it is "
                   "killed (default: no limit for pier and presets, 900 for stability)")
    p.add_argument("--presets", nargs="+", default=None,
                   metavar="PRESET", help="presets: the linear-solver presets to compare "
                   f"(default: {' '.join(BENCH_PRESETS)}); floors: the one field-split preset "
                   "measured (default: fieldsplit_pier)")
    p.add_argument("--cases", nargs="*", default=None, metavar="CASE",
                   help="stability: the cases to run (default: all)")
    p.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="pier, presets, floors: a scenario key for every run, e.g. "
                   "numerics.solver.preset=fieldsplit_pier (repeatable)")
    p.set_defaults(func=_cmd_bench)


def _cmd_report(args: argparse.Namespace) -> int:
    from pilegroup.studies.report.handover import write_handover
    from pilegroup.studies.report.run_report import results_markdown

    out = Path(args.out_dir)
    paths = write_handover(out)
    for path in paths:
        print(path)
    if args.markdown:
        md = Path(args.markdown)
        rel = Path(os.path.relpath(out / "plots", md.parent)).as_posix()
        print(write_text_atomic(md, results_markdown(out, rel)))
    return 0


def _report_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("out_dir", metavar="OUT_DIR", help="run output folder, e.g. out/pier667")
    p.add_argument("--markdown", metavar="FILE", default=None,
                   help="also write the results section (Markdown) to FILE; image links are "
                   "relative to FILE's folder")
    p.set_defaults(func=_cmd_report)


def build_parser() -> argparse.ArgumentParser:
    """The argument parser of the ``pilegroup`` command."""
    p = argparse.ArgumentParser(
        prog="pilegroup",
        description="3D simulation of pile groups in layered soft soil over time: Biot "
        "consolidation, elastoplastic soil, elastic piles and cap, viscoplastic pile-soil "
        "interface (DOLFINx, gmsh, PETSc). Scenarios are TOML files whose keys carry their "
        "unit; bundled scenarios: " + ", ".join(BUNDLED) + ".",
        epilog="Under MPI: mpirun -n 2 pilegroup run pier667. Exit codes: 0 ok, 1 run failed, "
        "2 invalid input, 143/130/138 stopped by SIGTERM/SIGINT/SIGUSR1 (checkpoint saved; "
        "--resume).",
    )
    p.add_argument("-v", "--verbose", action="count", default=0, help="more log output")
    sub = p.add_subparsers(dest="command", required=True, metavar="COMMAND")
    for name, help_, add_arguments in (
        ("scenario", "show, validate or list the keys of scenario files", scenario_arguments),
        ("run", "run a scenario (main job)", _run_arguments),
        ("stiffness", "the cap's 6 x 6 stiffness matrix at the end of a run",
         _stiffness_arguments),
        ("mesh", "build the all-hexahedral mesh of a scenario", _mesh_arguments),
        ("verify", "run verification cases against closed forms", _verify_arguments),
        ("bench", "benchmarks that print tables (not tests)", _bench_arguments),
        ("report", "figures, report.md and report.html of a run's output folder",
         _report_arguments),
    ):
        add_arguments(sub.add_parser(name, help=help_, description=DESCRIPTIONS[name]))
    for name, help_, description, add_arguments in BATCH_COMMANDS + LAB_COMMANDS:
        add_arguments(sub.add_parser(name, help=help_, description=description))
    return p


def main(argv: Sequence[str] | None = None) -> int:
    """Entry point of the ``pilegroup`` console script; returns the exit code.

    Before the process ends, SIGPIPE gets Python's action back (ignored: a write to a closed
    pipe raises instead). PETSc installs a handler that turns it into ``MPI_Abort`` (exit 59),
    and Open MPI's ``mpirun`` closes its connections to the ranks as soon as one rank exits
    with a non-zero code, while the others still finalise: measured on a run stopped by
    SIGUSR1 on two ranks, which ended with 59 instead of 138 (docs/checkpoint.md, "Signals").

    The progress bars lock with a thread lock: tqdm's default, a ``multiprocessing`` lock,
    starts a resource-tracker process under Python 3.14 (forkserver), which Open MPI's SIGUSR1
    to the rank's processes killed, with two warnings after the stop line (measured).
    """
    tqdm.set_lock(threading.RLock())
    try:
        return _main(argv)
    finally:
        signal.signal(signal.SIGPIPE, signal.SIG_IGN)


def _main(argv: Sequence[str] | None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    setup_logging(args.verbose)
    try:
        return int(args.func(args) or 0)
    except ScenarioError as exc:  # raised on every rank alike: rank 0 tells
        _say(f"pilegroup: invalid input: {exc}")
        return EXIT_INPUT
    except RunInterrupted as exc:  # every rank alike; one line from rank 0
        _say(f"pilegroup: {exc}; resume with: {_resume_command(argv)}")
        return 128 + exc.signum
    except PilegroupError as exc:
        _say(f"pilegroup: failed: {exc}")
        return EXIT_FAILED
    except Exception as exc:  # a failure that may be one rank's alone: end every rank
        return _abort(exc, args.verbose)


def _resume_command(argv: Sequence[str] | None) -> str:
    """The command line that resumes this run: ``[mpirun -n N] pilegroup ARGS --resume``."""
    from mpi4py import MPI

    args = list(sys.argv[1:] if argv is None else argv)
    ranks = MPI.COMM_WORLD.size
    mpi = ["mpirun", "-n", str(ranks)] if ranks > 1 else []
    return shlex.join([*mpi, "pilegroup", *args] + ([] if "--resume" in args else ["--resume"]))


def _say(line: str) -> None:
    """One line on stderr from rank 0 of a collective failure (not one per rank)."""
    if _world_rank() == 0:
        print(line, file=sys.stderr, flush=True)


def _abort(exc: Exception, verbose: bool) -> int:
    """One line naming the rank and the error; under MPI every rank is ended (no hang)."""
    from mpi4py import MPI

    comm = MPI.COMM_WORLD
    where = f"rank {comm.rank} of {comm.size}" if comm.size > 1 else "run"
    if verbose:
        traceback.print_exc()
    what = str(exc) if isinstance(exc, OutputError) else f"{type(exc).__name__}: {exc}"
    line = f"pilegroup: {where} failed: {what}"
    if comm.size > 1:
        abort_job(line, EXIT_FAILED)
    else:
        print(line, file=sys.stderr, flush=True)
    return EXIT_FAILED


if __name__ == "__main__":
    sys.exit(main())
