"""The ``pilegroup batch``, ``combinations`` and ``study`` commands (registered by the CLI).

All run under MPI as they are (``mpirun -n N pilegroup batch PLAN --ranks-per-case k``, or
``srun``). Exit codes as the rest of the CLI: 0 every case complete, 1 a case failed, 2 invalid
input, 143/130/138 stopped by SIGTERM/SIGINT/SIGUSR1 (the running cases recorded
``interrupted``); the one-line message of an invalid input is printed by world rank 0 only.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path
from typing import TYPE_CHECKING, Any

from pilegroup.errors import ScenarioError
from pilegroup.model.loader import parse_override
from pilegroup.studies.batch.rows import BatchRow
from pilegroup.studies.campaigns.mesh_records import DEFAULT_SIZES

if TYPE_CHECKING:
    from pilegroup.studies.batch.execute import BatchResult

EXIT_INPUT = 2

BATCH_DESCRIPTION = (
    "Run the cases of a plan (TOML: a base scenario and [[case]] entries and/or a [sweep] of "
    "scenario keys; see README.md) on groups of --ranks-per-case MPI ranks, each group taking "
    "the next case from a shared queue (largest estimated mesh first). Every case is validated "
    "before anything runs (exit 2 naming the case and key). Each case writes its run folder "
    "OUT/<case>; a failed case is recorded and the others go on (exit 1 at the end). Running "
    "the plan again skips the cases already complete for the same scenario. Rank 0 shows the "
    "progress and keeps OUT/batch.csv and OUT/batch.json current.")
COMBINATIONS_DESCRIPTION = (
    "Run load combinations (TOML: a base scenario, its load stage, [load_cases.NAME] tables of "
    "cap actions Fx_kN Fy_kN Fz_kN Mx_kNm My_kNm Mz_kNm or cap_load_kN, and [[combination]] "
    "entries with factors on the load cases; see README.md) as the cases of a batch, then "
    "write the envelope: OUT/envelope.csv, OUT/envelope.md and OUT/combination_results.csv "
    "(cap displacement and rotation, pile head axial force and shear, largest bending moment "
    "along the piles: the extremes over the combinations at the last output time and over "
    "every output time, with the combination that governs). Every combination is validated "
    "before anything runs (exit 2 naming the file, the combination and the key). MPI groups, "
    "failures, resume and stopping as pilegroup batch; a combination that failed is listed as "
    "not in the envelope.")
STUDY_DESCRIPTION = (
    "Mesh-sensitivity study: a batch over numerics.mesh.size_m (--sizes), the coarsest and "
    "finest sizes again with the interface normal penalty x --penalty-factor, and a report "
    "(mesh_study.md, PNG figures, mesh_study.csv, gci.csv): cells, unknowns, wall time, memory "
    "and settlement per size, Richardson extrapolation, observed order and GCI (Celik et al. "
    "2008), error against time, centre-pile profiles for every size, the penalty check; sizes "
    "that are invalid or would not fit the machine's memory are reported, not run. A published "
    "mesh study is set beside ours only where the scenario carries one ([reference.mesh_study], "
    "docs/scenario.md).")


def memory_size(text: str) -> float:
    """``--memory``'s value in MB: a number with its unit, MB or GB (1 GB = 1024 MB)."""
    units = {"MB": 1.0, "GB": 1024.0}
    value, unit = text.strip()[:-2], text.strip()[-2:].upper()
    try:
        mb = float(value) * units[unit]
    except (KeyError, ValueError):
        mb = math.nan
    if not mb > 0.0 or math.isinf(mb):
        raise argparse.ArgumentTypeError(
            f"{text[:40]!r}: allowed: a positive size with its unit, e.g. 8GB or 6000MB")
    return mb


def _memory_argument(p: Any, default: str) -> None:
    """``--memory SIZE`` on parser or group ``p``: the memory the cases may use together."""
    p.add_argument("--memory", type=memory_size, default=None, metavar="SIZE",
                   help=f"memory the cases may use together{default}, e.g. 8GB or 6000MB; each "
                   "case gets the share of its ranks, and with preset auto a case whose in-core "
                   "factors would exceed it writes them out of core")


def _world_rank() -> int:
    from mpi4py import MPI

    return MPI.COMM_WORLD.rank


def _input_error_once(exc: ScenarioError) -> int:
    """Invalid input under MPI: world rank 0 reports it (through the CLI), the others exit."""
    if _world_rank() == 0:
        raise exc
    return EXIT_INPUT


def _print_rows(rows: list[BatchRow]) -> None:
    for r in rows:
        wall = "" if r.get("wall_s") is None else f" {r['wall_s']:.1f} s"
        why = f": {r['message']}" if r["status"] == "failed" else ""
        skip = " (complete before, skipped)" if r.get("skipped") else ""
        print(f"{r['name']}: {r['status']}{skip}{wall}{why}")


def _finish(result: BatchResult, what: str, files: str, again: str) -> int:
    """Rank 0 prints the cases and the files; the exit code of a batch (every rank)."""
    from pilegroup.studies.run.interrupt import signal_name

    if _world_rank() == 0:
        _print_rows(result.rows)
        print(f"{what}: {files}")
        if result.signum:
            print(f"pilegroup: {what} interrupted by {signal_name(result.signum)}; {again}",
                  file=sys.stderr, flush=True)
    if result.signum:
        return 128 + result.signum
    return 1 if result.failed else 0


def _cmd_batch(args: argparse.Namespace) -> int:
    from pilegroup.studies.batch.batch_plan import load_plan
    from pilegroup.studies.batch.execute import run_batch
    from pilegroup.studies.run.interrupt import stop_on_signals

    try:
        plan = load_plan(args.plan)
        out = Path(args.out) if args.out else Path("out") / Path(args.plan).stem
        with stop_on_signals():  # running cases stop at a step boundary, recorded interrupted
            result = run_batch(plan, out, args.ranks_per_case, progress=not args.no_progress,
                               memory_mb=args.memory)
    except ScenarioError as exc:
        return _input_error_once(exc)
    return _finish(result, "batch", f"{out / 'batch.csv'}, {out / 'batch.json'}",
                   "run the plan again to run the cases not complete")


def batch_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``pilegroup batch``."""
    p.add_argument("plan", metavar="PLAN.toml", help="the plan file")
    p.add_argument("--out", help="batch folder (default: out/<plan file stem>)")
    p.add_argument("--ranks-per-case", type=int, default=1, metavar="K",
                   help="MPI ranks of each case (must divide the number of ranks; default 1)")
    _memory_argument(p, " on each node (default: what the node has available)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_batch)


def _cmd_combinations(args: argparse.Namespace) -> int:
    from pilegroup.studies.campaigns.load_combinations import run_combinations
    from pilegroup.studies.results.envelope import ENVELOPE_CSV, ENVELOPE_MD
    from pilegroup.studies.run.interrupt import stop_on_signals

    try:
        out = Path(args.out) if args.out else Path("out") / Path(args.file).stem
        with stop_on_signals():  # running cases stop at a step boundary, recorded interrupted
            result = run_combinations(args.file, out, args.ranks_per_case,
                                      progress=not args.no_progress, memory_mb=args.memory)
    except ScenarioError as exc:
        return _input_error_once(exc)
    return _finish(result, "combinations", f"{out / ENVELOPE_MD}, {out / ENVELOPE_CSV}",
                   "run the command again to run the combinations not complete")


def combinations_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``pilegroup combinations``."""
    p.add_argument("file", metavar="COMBINATIONS.toml", help="the combinations file")
    p.add_argument("--out", help="folder of the combinations' runs and the envelope (default: "
                   "out/<file stem>)")
    p.add_argument("--ranks-per-case", type=int, default=1, metavar="K",
                   help="MPI ranks of each combination's run (must divide the number of ranks; "
                   "default 1)")
    _memory_argument(p, " on each node (default: what the node has available)")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=_cmd_combinations)


def _cmd_study_mesh(args: argparse.Namespace) -> int:
    from pilegroup.studies.campaigns.mesh_study import run_mesh_study

    try:
        sets = dict(parse_override(t) for t in (args.set or []))
        out = Path(args.out) if args.out else Path("out") / (
            "mesh_study_" + Path(args.scenario).stem)
        memory = args.memory if args.memory_gb is None else args.memory_gb * 1024.0
        failed = run_mesh_study(args.scenario, sets, args.sizes, out, args.ranks_per_case,
                                args.penalty_factor, memory, progress=not args.no_progress)
    except ScenarioError as exc:
        return _input_error_once(exc)
    if _world_rank() == 0:
        print(f"mesh study: {out / 'mesh_study.md'}")
    return 1 if failed else 0


def study_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``pilegroup study``."""
    sub = p.add_subparsers(dest="study", required=True, metavar="STUDY")
    m = sub.add_parser("mesh", help="mesh-sensitivity study with GCI (beside a published one "
                       "where the scenario carries it)", description=STUDY_DESCRIPTION)
    m.add_argument("scenario", help="scenario TOML file or bundled name, e.g. pier667")
    m.add_argument("--sizes", type=float, nargs="+", metavar="H",
                   default=list(DEFAULT_SIZES),
                   help="element sizes at the pile surfaces in m (default: "
                   f"{' '.join(f'{h:g}' for h in DEFAULT_SIZES)})")
    m.add_argument("--out", help="study folder (default: out/mesh_study_<scenario>)")
    m.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="set a scenario key in every case (as pilegroup run --set); repeatable")
    m.add_argument("--ranks-per-case", type=int, default=1, metavar="K",
                   help="MPI ranks of each case (default 1)")
    m.add_argument("--penalty-factor", type=float, default=10.0, metavar="F",
                   help="multiplier of interface.normal_stiffness_factor for the penalty check "
                   "(default 10; 1 skips it)")
    mem = m.add_mutually_exclusive_group()
    _memory_argument(mem, " (default: the machine's memory)")
    mem.add_argument("--memory-gb", type=float, default=None, metavar="GB",
                     help="the same in GB, a number without its unit")
    m.add_argument("--no-progress", action="store_true", help="no progress bar")
    m.set_defaults(func=_cmd_study_mesh)


#: (name, help, description, add_arguments) of the commands of this module.
COMMANDS = (
    ("batch", "run the cases of a plan file on groups of MPI ranks", BATCH_DESCRIPTION,
     batch_arguments),
    ("combinations", "run load combinations of cap actions as a batch; their envelope",
     COMBINATIONS_DESCRIPTION, combinations_arguments),
    ("study", "studies made of batches (mesh sensitivity)", "Studies made of batches of runs.",
     study_arguments),
)

