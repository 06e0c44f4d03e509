"""``pilegroup scenario``: show a bundled scenario, validate a scenario file, list the keys.

``scenario validate`` refuses what a run refuses for a reason in the scenario, with the same
line and exit code 2, before any meshing: it builds the scenario (:mod:`pilegroup.model`) and
resolves its geometry (:func:`pilegroup.geometry.adapter.resolve_geometry`), as a run does
before it touches its output folder. ``scenario keys`` prints the reference of every key
(:mod:`pilegroup.model.keys`; ``--markdown`` is docs/scenario.md).
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Mapping

from pilegroup.errors import ScenarioError
from pilegroup.geometry.adapter import ResolvedGeometry, resolve_geometry
from pilegroup.model import BUNDLED, Scenario, bundled_text, load_scenario
from pilegroup.model import keys as scenario_keys
from pilegroup.model.loader import parse_override

SET_HELP = ("set a scenario key before validation (dotted path, TOML value), e.g. "
            "--set numerics.mesh.size_m=0.6 --set layers[0].E_MPa=3; repeatable")


def world_rank() -> int:
    """The rank of this process in ``MPI.COMM_WORLD`` (0 without mpi4py)."""
    try:
        from mpi4py import MPI
    except ImportError:  # pragma: no cover - mpi4py always ships with dolfinx
        return 0
    return MPI.COMM_WORLD.rank


def overrides(args: argparse.Namespace) -> dict[str, object]:
    """The ``--set`` overrides of a command (later ones win)."""
    return dict(parse_override(t) for t in (getattr(args, "set", None) or []))


def validate(source: str, sets: Mapping[str, object] | None = None
             ) -> tuple[Scenario, ResolvedGeometry]:
    """The scenario ``source`` (a file or a bundled name, with ``sets``) and its geometry.

    Every refusal a run makes for a reason in the scenario before meshing: raises
    :class:`~pilegroup.errors.ScenarioError` with the run's line.
    """
    sc = load_scenario(source, sets)
    return sc, resolve_geometry(sc)


def _cmd_show(args: argparse.Namespace) -> int:
    if world_rank() == 0:
        sys.stdout.write(bundled_text(args.name))
    return 0


def _cmd_validate(args: argparse.Namespace) -> int:
    sc, geo = validate(args.file, overrides(args))
    if world_rank() == 0:
        print(f"{args.file}: valid scenario {sc.name!r}: {len(sc.layers)} layers, "
              f"{sc.piles.count} piles, {len(sc.stages)} stages, end {sc.time.end_day:g} day")
        print(f"  {sc.discretisation_line()}")
        print(f"  model part: {geo.symmetry} ({geo.reason})")
        warning = sc.discretisation_warning()
        if warning:
            print(f"warning: {warning}", file=sys.stderr)
    return 0


def _cmd_keys(args: argparse.Namespace) -> int:
    if args.markdown and args.table is not None:
        raise ScenarioError("TABLE", args.table, "--markdown prints every table (the page"
                            " docs/scenario.md): leave TABLE out")
    text = scenario_keys.markdown() if args.markdown else scenario_keys.text(args.table)
    if world_rank() == 0:
        sys.stdout.write(text)
    return 0


def scenario_arguments(p: argparse.ArgumentParser) -> None:
    """The sub-commands of ``pilegroup scenario``."""
    ssub = p.add_subparsers(dest="action", required=True, metavar="ACTION")
    show = ssub.add_parser("show", help="print a bundled scenario (TOML, with its comments)",
                           description="Print a bundled scenario; copy it to start your own.")
    show.add_argument("name", nargs="?", default="pier667", choices=BUNDLED,
                      help="bundled scenario name (default: pier667)")
    show.set_defaults(func=_cmd_show)
    val = ssub.add_parser("validate", help="check a scenario file and report the first problem",
                          description="Check a scenario TOML file as a run does before meshing:"
                          " unknown, missing or mistyped keys, out-of-range values, unsupported"
                          " combinations and layouts the mesher cannot take are reported in "
                          "one line with the key, the value, its unit and what is allowed (exit"
                          " code 2).")
    val.add_argument("file", help="scenario TOML file (or a bundled name)")
    val.add_argument("--set", action="append", metavar="KEY=VALUE", help=SET_HELP)
    val.set_defaults(func=_cmd_validate)
    keys = ssub.add_parser("keys", help="every scenario key: type, unit, default, range, use",
                           description="List the scenario's keys, table by table: type, unit, "
                           "default, allowed values, which stage kinds, soil models and "
                           "interface modes use each, and its meaning (docs/scenario.md).")
    keys.add_argument("table", nargs="?", default=None, metavar="TABLE",
                      help="one table and those under it, e.g. layers, numerics, stages, "
                      "scenario (default: every table)")
    keys.add_argument("--markdown", action="store_true",
                      help="print the Markdown page docs/scenario.md instead")
    keys.set_defaults(func=_cmd_keys)


__all__ = ["SET_HELP", "overrides", "scenario_arguments", "validate", "world_rank"]
