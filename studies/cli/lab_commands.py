"""The ``pilegroup lab`` and ``pilegroup fit`` commands (registered by the CLI).

Exit codes as the rest of the CLI: 0 done, 1 a fit failed (did not converge, a parameter the
data do not determine, a model run failed), 2 invalid input (a missing column, a value that is
not a number, fewer points than parameters, ...: one line naming the file, the column or key and
the value). ``fit scenario`` runs under MPI as it is (its model runs are batch cases); its
invalid-input line is printed by world rank 0 only.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from pilegroup.errors import ScenarioError
from pilegroup.fileio import write_json_atomic
from pilegroup.model.loader import parse_override
from pilegroup.studies.lab.interface_tests import InterfaceProtocol
from pilegroup.studies.lab.lab_params import INTERFACE_KEYS, SOIL_KEYS, SOIL_MODELS, VARIANTS
from pilegroup.studies.lab.lab_tables import TESTS
from pilegroup.studies.lab.soil_tests import SoilProtocol

EXIT_INPUT = 2
LAB_DESCRIPTION = (
    "Element tests of the laws at one material point, no mesh: interface direct shear at "
    "several normal stresses (to failure), creep under held shear, relaxation under held slip, "
    "shear at several rates (both readings of Eq. 15, default and seed, side by side); soil "
    "drained and undrained triaxial compression and oedometer (load steps, a creep stage, "
    "unloading), for Mohr-Coulomb, Drucker-Prager, linear elastic, Modified Cam Clay and Soft "
    "Soil Creep. Parameters from a scenario's layer (--scenario pier667 --layer mud) and/or "
    "given (--K 296 --n 0.29 ...; a given value replaces the layer's). Writes OUT/<test>.csv "
    "(columns: docs/lab.md) and OUT/<test>.png.")
FIT_DESCRIPTION = (
    "Parameters fitted to data with scipy's bounded least squares, printed under the "
    "scenario's key names with standard errors from the Jacobian and their correlations. "
    "interface-shear: K, n, R_f, delta_deg from direct-shear curves; interface-creep: "
    "eta_MPa_day (and N) from creep curves (the CSV layout pilegroup lab writes); oedometer: "
    "Soft Soil Creep's lambda_star, kappa_star, mu_star (and OCR) from an oedometer test with "
    "load steps and creep stages, the law run through its programme; scenario: up "
    "to three scenario keys fitted to a measured settlement.csv or gauges.csv history, each "
    "evaluation a model run of a batch (parallel under mpirun, resumable).")


def _param_arguments(p: argparse.ArgumentParser) -> None:
    g = p.add_argument_group("material (scenario key names; a given value replaces the layer's)")
    g.add_argument("--scenario", default=None, help="scenario TOML file or bundled name")
    g.add_argument("--layer", default=None, help="layer name (or index from 0) in --scenario")
    g.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="set a scenario key before the layer is read (as pilegroup run --set)")
    for k in INTERFACE_KEYS + SOIL_KEYS:
        if k == "soil_model":
            g.add_argument("--soil_model", choices=list(SOIL_MODELS), default=None)
        else:
            g.add_argument(f"--{k}", type=float, default=None, metavar="X")


def _material(args: argparse.Namespace):
    from pilegroup.studies.lab.lab_params import lab_material

    given = {k: getattr(args, k, None) for k in INTERFACE_KEYS + SOIL_KEYS}
    sets = dict(parse_override(t) for t in (args.set or []))
    return lab_material(given, args.scenario, args.layer, sets)


def _cmd_lab(args: argparse.Namespace) -> int:
    from pilegroup.studies.lab.lab_run import run_lab

    material = _material(args)
    default_sn = (25.0, 50.0, 100.0, 200.0) if args.test == "interface-shear" else (100.0,)
    iface = InterfaceProtocol(
        normal_stresses_kPa=tuple(args.normal_stresses_kPa or default_sn),
        rate_mm_per_min=args.rate_mm_per_min,
        rates_mm_per_min=tuple(args.rates_mm_per_min or InterfaceProtocol.rates_mm_per_min),
        max_slip_mm=args.max_slip_mm,
        levels=tuple(args.levels or InterfaceProtocol.levels),
        shear_stresses_kPa=tuple(args.shear_stresses_kPa or ()), days=args.days,
        steps=args.steps)
    soil = SoilProtocol(
        confining_stresses_kPa=tuple(args.confining_stresses_kPa
                                     or SoilProtocol.confining_stresses_kPa),
        max_axial_strain=args.max_axial_strain, steps=args.steps,
        oedometer_start_kPa=args.oedometer_start_kPa, oedometer_max_kPa=args.oedometer_max_kPa,
        step_days=args.step_days, creep_days=args.creep_days,
        substeps_per_decade=args.substeps_per_decade,
        strain_rate_per_day=args.axial_strain_rate_per_day)
    out = run_lab(args.test, material, Path(args.out), iface, soil,
                  tuple(args.variant or VARIANTS))
    print(f"{args.test} ({out.source}): {out.csv}, {out.png}")
    return 0


def lab_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``pilegroup lab``."""
    p.add_argument("test", choices=TESTS, help="the element test")
    p.add_argument("--out", required=True, help="output folder (OUT/<test>.csv, .png)")
    p.add_argument("--variant", action="append", choices=VARIANTS,
                   help="interface tests: only this Eq. 15 reading (repeatable; default both)")
    _param_arguments(p)
    t = p.add_argument_group("test protocol")
    t.add_argument("--normal-stresses-kPa", type=float, nargs="+", metavar="S",
                   help="interface: effective normal stresses, compression positive (default "
                   "25 50 100 200 for interface-shear, 100 for the others; interface-rate "
                   "uses the first)")
    t.add_argument("--rate-mm-per-min", type=float, default=0.8,
                   help="interface-shear: slip rate (default 0.8)")
    t.add_argument("--rates-mm-per-min", type=float, nargs="+", metavar="R",
                   help="interface-rate: slip rates (default 0.0008 0.008 0.08 0.8)")
    t.add_argument("--max-slip-mm", type=float, default=20.0,
                   help="interface-shear: largest slip if failure comes later; interface-rate: "
                   "the slip sheared to (default 20)")
    t.add_argument("--levels", type=float, nargs="+", metavar="L",
                   help="creep, relaxation: held shear as fractions of the hyperbola's "
                   "asymptote p tan(delta)/R_f (default 0.3 0.5 0.7 0.8 0.9)")
    t.add_argument("--shear-stresses-kPa", type=float, nargs="+", metavar="T",
                   help="creep, relaxation: held shear stresses in kPa (instead of --levels)")
    t.add_argument("--days", type=float, default=30.0, help="creep, relaxation: duration")
    t.add_argument("--steps", type=int, default=60, help="steps per curve (default 60)")
    t.add_argument("--confining-stresses-kPa", type=float, nargs="+", metavar="P",
                   help="triaxial: cell pressures (default 50 100 200)")
    t.add_argument("--max-axial-strain", type=float, default=0.15,
                   help="triaxial: final axial strain (default 0.15)")
    t.add_argument("--axial-strain-rate-per-day", type=float, default=0.24,
                   help="triaxial: axial strain rate (default 0.24, 1 %% per hour; Soft Soil "
                   "Creep creeps over each step)")
    t.add_argument("--oedometer-start-kPa", type=float, default=12.5,
                   help="oedometer: vertical stress of the start (default 12.5)")
    t.add_argument("--oedometer-max-kPa", type=float, default=800.0,
                   help="oedometer: largest vertical stress (default 800; doubling from the "
                   "start)")
    t.add_argument("--step-days", type=float, default=1.0,
                   help="oedometer: duration of each load step (default 1)")
    t.add_argument("--creep-days", type=float, default=30.0,
                   help="oedometer: the creep stage at the largest stress (default 30; 0: none)")
    _substeps_argument(t)
    p.set_defaults(func=_cmd_lab)


def _substeps_argument(p: Any) -> None:
    """``--substeps-per-decade`` on a parser or an argument group."""
    p.add_argument("--substeps-per-decade", type=int, default=20,
                   help="oedometer, Soft Soil Creep: backward-Euler steps per decade of time "
                   "in each hold (default 20)")


def _report(result, args: argparse.Namespace, figure: Path | None) -> None:
    if args.json:
        data = result.as_json()
        if figure is not None:
            data["figure"] = str(figure)
        print(json.dumps(data, indent=2))
    else:
        print(result.text())
        if figure is not None:
            print(f"  figure: {figure}")


def _cmd_fit_oedometer(args: argparse.Namespace) -> int:
    from pilegroup.studies.lab.fit_plots import write_oedometer_fit_figure
    from pilegroup.studies.lab.oedometer_fit import fit_oedometer

    path = Path(args.file)
    fit = fit_oedometer(path, _material(args), args.OCR, args.substeps_per_decade)
    out = Path(args.out) if args.out else path.parent
    figure = write_oedometer_fit_figure(out / f"{path.stem}_fit.png", fit)
    _report(fit.result, args, figure)
    return 0


def _cmd_fit_curves(args: argparse.Namespace) -> int:
    from pilegroup.studies.lab.fit_plots import write_fit_figure
    from pilegroup.studies.lab.interface_fit import fit_creep, fit_shear

    path = Path(args.file)
    if args.fit == "interface-shear":
        cf = fit_shear(path, args.variant)
    else:
        cf = fit_creep(path, _material(args), args.variant, args.fit_N)
    out = Path(args.out) if args.out else path.parent
    figure = write_fit_figure(out / f"{path.stem}_fit.png", cf)
    _report(cf.result, args, figure)
    return 0


def _cmd_fit_scenario(args: argparse.Namespace) -> int:
    from mpi4py import MPI

    from pilegroup.studies.lab.scenario_fit import (
        ScenarioFit,
        fit_scenario,
        parse_vary,
        read_measured,
        start_point,
    )
    from pilegroup.studies.run.interrupt import stop_on_signals

    comm = MPI.COMM_WORLD
    out = Path(args.out)
    try:
        sets = dict(parse_override(t) for t in (args.set or []))
        vary = [parse_vary(v) for v in args.vary]
        start = {k: float(v) for k, v in (parse_override(t) for t in (args.start or []))}
        x0 = start_point(args.scenario, sets, vary, start)
        fit = ScenarioFit(args.scenario, sets, vary, read_measured(Path(args.data)), out,
                          args.ranks_per_case, comm, not args.no_progress, args.max_runs)
        with stop_on_signals():
            result = fit_scenario(fit, x0)
    except ScenarioError:
        if comm.rank == 0:
            raise
        return EXIT_INPUT
    if comm.rank == 0:
        from pilegroup.studies.lab.fit_plots import write_scenario_fit_figure

        figure = write_scenario_fit_figure(out / "fit.png", fit, result)
        write_json_atomic(out / "fit.json", {**result.as_json(), "figure": str(figure)})
        if not args.json:
            for r in fit.records():
                print(f"{r['name']}: {fit.describe([r[v.key] for v in vary])}: misfit "
                      f"{r['misfit']:.4g}, {r['status']}")
        _report(result, args, figure)
    return 0


def fit_arguments(p: argparse.ArgumentParser) -> None:
    """Arguments of ``pilegroup fit``."""
    sub = p.add_subparsers(dest="fit", required=True, metavar="FIT")
    for name, help_ in (("interface-shear", "K, n, R_f, delta_deg from direct-shear curves"),
                        ("interface-creep", "eta_MPa_day (and N) from creep curves")):
        f = sub.add_parser(name, help=help_, description=FIT_DESCRIPTION)
        f.add_argument("file", metavar="FILE", help="CSV in the layout of pilegroup lab")
        f.add_argument("--variant", choices=VARIANTS, default=None,
                       help="the rows of this Eq. 15 reading (default: default, if present)")
        f.add_argument("--out", default=None, help="folder of the figure (default: FILE's)")
        f.add_argument("--json", action="store_true", help="one JSON object")
        if name == "interface-creep":
            f.add_argument("--fit-N", dest="fit_N", action="store_true",
                           help="fit the Perzyna exponent N too")
            _param_arguments(f)
        f.set_defaults(func=_cmd_fit_curves)
    o = sub.add_parser("oedometer", help="lambda_star, kappa_star, mu_star (and OCR) of Soft "
                       "Soil Creep from an oedometer test", description=FIT_DESCRIPTION)
    o.add_argument("file", metavar="FILE", help="CSV in the layout of pilegroup lab oedometer "
                   "(step, time_day, vertical_stress_kPa, vertical_strain)")
    o.add_argument("--out", default=None, help="folder of the figure (default: FILE's)")
    o.add_argument("--json", action="store_true", help="one JSON object")
    _substeps_argument(o)
    _param_arguments(o)
    o.set_defaults(func=_cmd_fit_oedometer)
    s = sub.add_parser("scenario", help="scenario keys fitted to a measured history",
                       description=FIT_DESCRIPTION)
    s.add_argument("scenario", help="scenario TOML file or bundled name")
    s.add_argument("--data", required=True, metavar="FILE",
                   help="measured history: settlement.csv or gauges.csv layout")
    s.add_argument("--vary", action="append", required=True, metavar="KEY=LOW:HIGH",
                   help="a scenario key to fit between bounds (repeatable, up to 3)")
    s.add_argument("--start", action="append", metavar="KEY=VALUE",
                   help="start of a --vary key (default: the scenario's value)")
    s.add_argument("--set", action="append", metavar="KEY=VALUE",
                   help="set a scenario key in every run (as pilegroup run --set)")
    s.add_argument("--out", required=True, help="fit folder: one run folder per evaluation, "
                   "batch.csv, fit.json, fit.png")
    s.add_argument("--ranks-per-case", type=int, default=1, metavar="K",
                   help="MPI ranks of each model run (default 1)")
    s.add_argument("--max-runs", type=int, default=60, help="most model runs (default 60)")
    s.add_argument("--json", action="store_true", help="one JSON object")
    s.add_argument("--no-progress", action="store_true", help="no progress bar")
    s.set_defaults(func=_cmd_fit_scenario)


#: (name, help, description, add_arguments) of the commands of this module.
COMMANDS = (
    ("lab", "element tests of the interface and soil laws at one point",
     LAB_DESCRIPTION, lab_arguments),
    ("fit", "law parameters or scenario keys fitted to data", FIT_DESCRIPTION, fit_arguments),
)
