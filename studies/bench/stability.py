"""The numerical stress suite: the small scenario under extreme steps, soils, loads and options.

``pilegroup bench stability`` runs the small scenario (:mod:`pilegroup.studies.bench.small_pile`)
through the cases of :func:`stress_cases` (with a capacity stage, whose failed foundation must end
``complete`` with its capacity, and a mesh too large for the machine, which must be refused
before meshing), each one ``pilegroup run`` with ``--set``
overrides in its own process group under a timeout, so that a crash or a hang is a row of the
table and not the end of the benchmark. A case must finish, or stop cleanly: exit 1 with one
line (``no equilibrium beyond load factor ...`` when the stepper gives up) and ``summary.json``
with ``status = "failed"``, or exit 2 with one line when the scenario rejects a value. Never a
traceback, a hang, or a non-finite number in any CSV, JSON, XDMF or HDF5 output
(:func:`nonfinite_files`).

Per case the table gives the status, exit code, wall time, accepted and rejected steps and
Newton iterations (``summary_solver.json``, also written by a run that stopped), the settlement
at the last accepted step (``load_settlement.csv``), the largest ``|p|`` over the output times
and the final state, the memory estimate per rank against the measured peak (``summary.json``),
whether a non-finite number was found, and the message (for a capacity stage, its result).
Results: ``bench_stability.json`` and ``bench_stability.md`` in the output folder.
"""

from __future__ import annotations

import csv
import json
import math
import platform
import shutil
import time
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI

from pilegroup.fileio import write_text_atomic
from pilegroup.model import Scenario, ScenarioError
from pilegroup.model.bounds import BOUNDS
from pilegroup.studies.bench.benchrun import (
    Finished,
    error_line,
    read_json,
    run_command,
    run_isolated,
    write_table,
)
from pilegroup.studies.bench.small_pile import small_pile_scenario, small_pile_text

COLUMNS = ("case", "overrides", "status", "exit", "wall_s", "steps", "rejected", "newton",
           "settlement_mm", "max_abs_p_kPa", "memory_mb", "nan", "message")

#: Outcomes that are a clean end of a case (with no non-finite number written).
CLEAN = ("complete", "stopped", "failed", "invalid input")

#: A pile has failed when its head settles by 10 % of its diameter (EN 1997-1, 7.6.1.1(3)).
FAILURE_SETTLEMENT_PER_DIAMETER = 0.1


@dataclass(frozen=True)
class StressCase:
    """One case of the suite: its name, its group, its ``--set`` overrides and what it means."""

    name: str
    group: str
    sets: tuple[str, ...]
    note: str = ""


def _num(x: float) -> str:
    """A TOML float with 6 significant digits (``300.0``, ``5.184e-17``)."""
    text = f"{x:.6g}"
    return text if any(c in text for c in ".en") else text + ".0"


def _time_cases(sc: Scenario) -> list[StressCase]:
    """From a 1e-6 day step to the whole run in one step per stage."""
    end = sc.time.end_day
    load = next(i for i, st in enumerate(sc.stages) if st.kind == "load")
    tiny = ("numerics.time.dt_initial_day=1e-06", "numerics.time.dt_min_day=1e-07")
    return [
        StressCase("dt_start_1e-6", "time step", tiny,
                   "first step 1e-6 day, growing after easy steps"),
        StressCase("dt_1e-6_only", "time step",
                   (*tiny, "time.end_day=2e-06", "time.output_days=[0.0, 1e-06, 2e-06]",
                    f"stages[{load}].duration_day=1e-06"),
                   "the whole run 2e-6 day: one step of 1e-6 day per stage"),
        StressCase("dt_fixed_0.05", "time step",
                   ("numerics.time.dt_initial_day=0.05", "numerics.time.dt_max_day=0.05"),
                   "every step 0.05 day"),
        StressCase("dt_whole_run", "time step",
                   (f"numerics.time.dt_initial_day={_num(end)}",
                    f"numerics.time.dt_max_day={_num(end)}",
                    f"time.output_days=[0.0, {_num(end)}]"),
                   "one step per stage (the stage ends are landing points)"),
    ]


def _layer_cases(sc: Scenario, key: str, group: str, factors: Sequence[float], tag: str
                 ) -> list[StressCase]:
    """``key`` of every layer times each factor, then every layer at the key's lower bound."""
    out = []
    for f in factors:
        sets = tuple(f"layers[{j}].{key}={_num(getattr(lay, key) * f)}"
                     for j, lay in enumerate(sc.layers))
        out.append(StressCase(f"{tag}_x{f:g}", group, sets, f"{key} of every layer x {f:g}"))
    lo = BOUNDS[f"layers.{key}"].lo
    sets = tuple(f"layers[{j}].{key}={_num(lo)}" for j in range(len(sc.layers)))
    out.append(StressCase(f"{tag}_lowest", group, sets,
                          f"{key} of every layer at the lowest the scenario accepts ({lo:g})"))
    return out


def _load_cases(sc: Scenario) -> list[StressCase]:
    """The cap load x3, x10 and far beyond capacity (x1000), with variants of the last."""
    load = [(i, st.cap_load_kN) for i, st in enumerate(sc.stages) if st.kind == "load"]

    def scaled(f: float) -> tuple[str, ...]:
        return tuple(f"stages[{i}].cap_load_kN={_num(q * f)}" for i, q in load)

    tied, q2 = 'interface.mode="tied"', 'numerics.element="Q2Q1"'
    return [
        StressCase("load_x3", "load", scaled(3.0), "cap load x 3"),
        StressCase("load_x10", "load", scaled(10.0), "cap load x 10"),
        StressCase("load_x1000", "load", scaled(1000.0), "cap load x 1000 (far above capacity)"),
        StressCase("load_x1000_dtmin", "load",
                   (*scaled(1000.0), "numerics.time.dt_min_day=0.01"),
                   "x 1000 with dt_min 0.01 day: the stepper gives up after a few cuts"),
        StressCase("load_x1000_tied", "load", (*scaled(1000.0), tied), "x 1000, tied pile"),
        StressCase("load_x1000_tied_Q2Q1", "load", (*scaled(1000.0), tied, q2),
                   "x 1000, tied pile, Q2-Q1"),
    ]


def _capacity_cases(sc: Scenario) -> list[StressCase]:
    """The last stage made a capacity stage: the foundation must fail and the run complete.

    Up to 10 x the cap load over the stage: Q1-Q1, Q2-Q1, a tied pile with Q2-Q1, where
    the stepper gives up at the limit load (bracketed by its cut-backs), and Q1-Q1 with the
    toe's resistance given as a base bearing limit (9 c_u + sigma'_v0).
    """
    last = len(sc.stages) - 1
    q = sc.total_cap_load()
    toe_depth = max(sc.piles.lengths)
    toe, sv_toe = sc.layer_at(toe_depth), sc.vertical_effective_stress(toe_depth)

    def capacity(f: float) -> tuple[str, ...]:
        return (f'stages[{last}].kind="capacity"', f"stages[{last}].max_load_kN={_num(q * f)}",
                f"stages[{last}].duration_day={_num(sc.time.end_day - 0.5)}")

    return [
        StressCase("capacity", "capacity", capacity(10.0), "capacity stage to 10 x the load"),
        StressCase("capacity_Q2Q1", "capacity", (*capacity(10.0), 'numerics.element="Q2Q1"'),
                   "capacity stage, Q2-Q1 (no locking under isochoric plastic flow)"),
        StressCase("capacity_tied_Q2Q1", "capacity",
                   (*capacity(10.0), 'interface.mode="tied"', 'numerics.element="Q2Q1"'),
                   "capacity stage, tied pile, Q2-Q1: the stepper finds no equilibrium"),
        StressCase("capacity_base_bearing", "capacity",
                   (*capacity(10.0), f"layers[{toe}].interface.base_bearing_kPa="
                    f"{_num(9.0 * sc.layers[toe].c_kPa + sv_toe)}"),
                   "capacity stage, Q1-Q1, the toe's layer with base_bearing_kPa = 9 c_u +"
                   " sigma'_v0 at the toe"),
    ]


def _memory_cases() -> list[StressCase]:
    """A mesh far too large for the machine: refused before meshing (exit 2, one line)."""
    return [StressCase("memory_too_large", "memory",
                       ("numerics.mesh.size_m=0.05", "numerics.mesh.far_field_size_m=0.05"),
                       "0.05 m elements everywhere: ~2e5 MB per rank estimated")]


def _option_cases() -> list[StressCase]:
    """Interface modes, law variants and integrators; the element pairs."""
    out = [StressCase("interface_tied", "interface", ('interface.mode="tied"',)),
           StressCase("interface_elastic", "interface", ('interface.mode="elastic"',))]
    for variant in ("default", "seed"):
        for scheme in ("implicit", "explicit"):
            out.append(StressCase(
                f"interface_{variant}_{scheme}", "interface",
                ('interface.mode="viscoplastic"', f'interface.variant="{variant}"',
                 f'interface.integrator="{scheme}"'),
                f"viscoplastic, {variant} law, {scheme} integration"))
    return out + [StressCase(f"element_{pair}", "element", (f'numerics.element="{pair}"',))
                  for pair in ("Q1Q1", "Q2Q1")]


def _soft_soil_sets(sc: Scenario, model: str) -> tuple[str, ...]:
    """Every layer as ``model``, its parameters from the layer's ``E_MPa`` and ``e0``.

    The correlation of the bundled ``pier667_soft_soil`` (its file states the sources):
    ``lambda* = 100 kPa / (E ln 2)``, ``kappa* = lambda*/5``, ``mu* = lambda*/25``, OCR 1.5,
    an effective friction angle of 25 deg; Cam Clay takes ``lam = lambda* (1 + e0)``,
    ``kappa = kappa* (1 + e0)`` and ``phi_cs_deg`` = 25.
    """
    out = []
    for j, lay in enumerate(sc.layers):
        lam = 100.0 / (lay.E_MPa * 1000.0 * math.log(2.0))
        keys = {"model": f'"{model}"', "OCR": "1.5"}
        if model == "soft_soil_creep":
            keys |= {"phi_deg": "25.0", "lambda_star": _num(lam), "kappa_star": _num(lam / 5.0),
                     "mu_star": _num(lam / 25.0)}
        else:
            keys |= {"phi_cs_deg": "25.0", "lam": _num(lam * (1.0 + lay.e0)),
                     "kappa": _num(lam / 5.0 * (1.0 + lay.e0))}
        out += [f"layers[{j}].{k}={v}" for k, v in keys.items()]
    return tuple(out)


def _soft_soil_cases(sc: Scenario) -> list[StressCase]:
    """Soft Soil Creep and Modified Cam Clay: as given, overloaded, a tiny step, unloaded.

    Unloading: the last stage becomes a load stage that takes the cap load back to 0 over
    the rest of the run (the soil swells along its unloading line; the creep slows down).
    """
    load = [(i, st.cap_load_kN) for i, st in enumerate(sc.stages) if st.kind == "load"]
    last, end = len(sc.stages) - 1, sc.time.end_day
    t_last = sc.stage_times()[-1][1]  # the last stage's start
    x10 = tuple(f"stages[{i}].cap_load_kN={_num(q * 10.0)}" for i, q in load)
    unload = (f'stages[{last}].kind="load"', f"stages[{last}].cap_load_kN=0.0",
              f"stages[{last}].duration_day={_num(end - t_last)}")
    tiny = ("numerics.time.dt_initial_day=1e-06", "numerics.time.dt_min_day=1e-07")
    out = []
    for model, tag in (("soft_soil_creep", "ssc"), ("modified_cam_clay", "mcc")):
        sets = _soft_soil_sets(sc, model)
        out += [StressCase(tag, "soft soil", sets, f"every layer {model}"),
                StressCase(f"{tag}_load_x10", "soft soil", (*sets, *x10),
                           f"every layer {model}, cap load x 10"),
                StressCase(f"{tag}_dt_1e-6", "soft soil", (*sets, *tiny),
                           f"every layer {model}, first step 1e-6 day"),
                StressCase(f"{tag}_unloading", "soft soil", (*sets, *unload),
                           f"every layer {model}, the cap load taken off after loading")]
    return out


def stress_cases(sc: Scenario) -> tuple[StressCase, ...]:
    """Every case of the suite for scenario ``sc`` (its values scaled, its keys set)."""
    tied = 'interface.mode="tied"'
    stiff = _layer_cases(sc, "E_MPa", "stiffness", (0.01, 100.0), "E")
    lowest_tied = StressCase("E_lowest_tied", "stiffness", (*stiff[-1].sets, tied),
                             stiff[-1].note + ", tied pile")
    return tuple([*_time_cases(sc),
                  *_layer_cases(sc, "k_m_per_day", "permeability", (1e-12, 1e3), "k"),
                  *stiff, lowest_tied, *_load_cases(sc), *_option_cases(),
                  *_soft_soil_cases(sc), *_capacity_cases(sc), *_memory_cases()])


# ---------------------------------------------------------------------------- output checks
def _csv_nonfinite(path: Path) -> bool:
    with path.open(newline="", encoding="utf-8") as f:
        for row in csv.reader(f):
            for cell in row:
                try:
                    if not math.isfinite(float(cell)):
                        return True
                except ValueError:
                    continue
    return False


def _json_nonfinite(path: Path) -> bool:
    found = []
    json.loads(path.read_text(encoding="utf-8"), parse_constant=found.append)
    return bool(found)


def _xdmf_nonfinite(path: Path) -> bool:
    for el in ET.parse(path).getroot().iter("Time"):
        if not math.isfinite(float(el.get("Value", "0"))):
            return True
    return False


def _h5_nonfinite(path: Path) -> bool:
    import h5py

    found = []

    def visit(name: str, obj: object) -> None:
        if isinstance(obj, h5py.Dataset) and obj.dtype.kind == "f" \
                and not np.isfinite(obj[()]).all():
            found.append(name)

    with h5py.File(path, "r") as f:
        f.visititems(visit)
    return bool(found)


_CHECKS = {".csv": _csv_nonfinite, ".json": _json_nonfinite, ".xdmf": _xdmf_nonfinite,
           ".h5": _h5_nonfinite}


def nonfinite_files(folder: str | Path) -> list[str]:
    """The output files under ``folder`` that hold a NaN or an infinity (relative paths).

    CSV cells, JSON numbers (``NaN``/``Infinity`` tokens; a message that mentions NaN is text),
    XDMF time values and every floating-point HDF5 dataset are read; temporary files of an
    atomic write (names starting with a dot) are skipped.
    """
    folder = Path(folder)
    return [str(p.relative_to(folder)) for p in sorted(folder.rglob("*"))
            if p.suffix in _CHECKS and not p.name.startswith(".") and p.is_file()
            and _CHECKS[p.suffix](p)]


def max_abs_pressure(folder: Path, solver: dict[str, Any]) -> float | None:
    """Largest ``|p|`` (kPa) in the XDMF pressure fields and the final state of the run."""
    import h5py

    vals = [abs(v) for k in ("max_excess_pore_pressure_kPa", "min_excess_pore_pressure_kPa")
            if isinstance(v := solver.get(k), int | float) and math.isfinite(v)]

    def visit(name: str, obj: object) -> None:
        if isinstance(obj, h5py.Dataset) and "excess_pore_pressure" in name:
            a = np.abs(obj[()])
            if a.size and np.isfinite(a).any():
                vals.append(float(a[np.isfinite(a)].max()))

    for path in sorted(folder.glob("results*.h5")):
        with h5py.File(path, "r") as f:
            f.visititems(visit)
    return max(vals) if vals else None


def end_settlement_mm(folder: Path) -> float | None:
    """Settlement (mm) at the last accepted step, from ``load_settlement.csv``."""
    try:
        with (folder / "load_settlement.csv").open(newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
    except OSError:
        return None
    return 1000.0 * float(rows[-1]["settlement_m"]) if rows else None


def capacity_line(cap: dict[str, Any]) -> str:
    """One line of a capacity result: the ultimate load, each criterion, how the stage ended."""
    g = cap.get("group") or {}

    def kn(x: float | None) -> str:
        return "-" if x is None else f"{x:.4g} kN"

    end = cap.get("end") or {}
    return (f"capacity {kn(g.get('ultimate_kN'))} ({g.get('governing')}); plunging "
            f"{kn((g.get('plunging') or {}).get('load_kN'))}, at 10 % D "
            f"{kn((g.get('settlement_10pct_d') or {}).get('load_kN'))}; stage end: "
            f"{end.get('reason')}")


def memory_cell(mem: dict[str, Any] | None) -> str:
    """``estimate / measured peak`` per rank (MB) of a run's ``summary.json`` memory record."""
    if not mem:
        return ""
    peak = max(mem.get("peak_rss_mb_per_rank") or [0.0])
    return f"{mem['estimate_mb_per_rank']:.0f} / {peak:.0f}"


# ---------------------------------------------------------------------------- one case
def classify(fin: Finished, summary: dict[str, Any] | None) -> tuple[str, str]:
    """The outcome of a run and its message line.

    Outcomes: those of :data:`CLEAN`; ``timeout`` (killed), ``traceback`` (one was printed),
    ``crashed`` (any other end: an unexpected exception, no summary, several error lines).
    """
    if fin.timed_out:
        return "timeout", f"killed after {fin.wall_s:.0f} s"
    line = error_line(fin)
    if "Traceback (most recent call last)" in fin.stderr:
        return "traceback", line
    status = (summary or {}).get("status")
    if fin.returncode == 0:
        return ("complete", "") if status == "complete" else ("crashed", "exit 0, no summary")
    tagged = [ln for ln in fin.stderr.splitlines() if ln.startswith("pilegroup:")]
    if len(tagged) != 1:
        return "crashed", f"{len(tagged)} pilegroup lines: {line}"
    if fin.returncode == 2 and line.startswith("pilegroup: invalid input:"):
        return "invalid input", line
    if fin.returncode == 1 and line.startswith("pilegroup: failed:") and status == "failed":
        return ("stopped" if "no equilibrium beyond load factor" in line else "failed"), line
    return "crashed", line


def _round(x: float | None, digits: int = 4) -> float | None:
    return None if x is None else float(f"{x:.{digits}g}")


def case_row(case: StressCase, folder: Path, fin: Finished, diameter_m: float
             ) -> dict[str, Any]:
    """The table row of ``case`` run into ``folder``."""
    summary = read_json(folder / "summary.json")
    solver = read_json(folder / "summary_solver.json") or {}
    status, message = classify(fin, summary)
    bad = nonfinite_files(folder) if folder.is_dir() else []
    settlement = end_settlement_mm(folder)
    capacity = (summary or {}).get("capacity")
    if status == "complete" and capacity:
        message = capacity_line(capacity)
    elif status == "complete" and settlement is not None \
            and settlement > 1000.0 * FAILURE_SETTLEMENT_PER_DIAMETER * diameter_m:
        message = (f"settlement {settlement / 1000:.3g} m > 10 % of the pile diameter "
                   "(a failed pile by EN 1997-1)")
    return {"case": case.name, "group": case.group, "note": case.note,
            "overrides": " ".join(case.sets), "status": status, "exit": fin.returncode,
            "wall_s": round(fin.wall_s, 1), "steps": solver.get("steps"),
            "rejected": solver.get("rejected_steps"), "newton": solver.get("newton_iterations"),
            "settlement_mm": _round(settlement), "max_abs_p_kPa": _round(
                max_abs_pressure(folder, solver) if folder.is_dir() else None),
            "memory_mb": memory_cell((summary or {}).get("memory")),
            "nan": ("yes: " + ", ".join(bad)) if bad else "no",
            "message": message if len(message) <= 200 else message[:197] + "...",
            "full_message": message, "clean": status in CLEAN and not bad}


def run_case(case: StressCase, scenario: Path, out: Path, ranks: int = 1,
             timeout: float | None = 900.0, diameter_m: float = 1.0,
             extra_sets: Sequence[str] = ()) -> dict[str, Any]:
    """Run ``case`` into ``out/<case name>`` (a folder left by an earlier run is removed).

    ``extra_sets``: overrides after the case's own.
    """
    folder = out / case.name
    shutil.rmtree(folder, ignore_errors=True)
    fin = run_isolated(run_command(scenario, folder, (*case.sets, *extra_sets), ranks), timeout)
    return case_row(case, folder, fin, diameter_m)


def bench_stability(out_dir: str | Path = "out/bench_stability",
                    names: Sequence[str] | None = None, ranks: int = 1,
                    timeout: float | None = 900.0, extra_sets: Sequence[str] = ()
                    ) -> list[dict[str, Any]]:
    """Run the cases ``names`` (default: all), print and write the table; returns the rows.

    Each case runs on ``ranks`` ranks under ``timeout`` s, with ``extra_sets`` added to its
    overrides (e.g. ``outputs.plots=false``). Under ``mpirun`` only rank 0 drives the cases
    (the others return at once with no rows).
    """
    if MPI.COMM_WORLD.rank != 0:
        return []
    out = Path(out_dir)
    text = small_pile_text()
    sc = small_pile_scenario()
    cases = {c.name: c for c in stress_cases(sc)}
    unknown = [n for n in names or () if n not in cases]
    if unknown:
        raise ScenarioError("--cases", unknown[0], f"unknown case; known: {', '.join(cases)}")
    out.mkdir(parents=True, exist_ok=True)
    scenario = write_text_atomic(out / "small_pile.toml", text)
    rows = []
    for name in names or list(cases):
        rows.append(run_case(cases[name], scenario, out, ranks, timeout, min(sc.piles.diameters),
                             extra_sets))
        print(json.dumps({k: rows[-1][k] for k in COLUMNS}), flush=True)
    header = (f"{time.strftime('%Y-%m-%d')}, {platform.node()} ({platform.machine()}); the "
              f"small scenario, {ranks} rank(s) per run, timeout {timeout} s per run"
              + (f"; every run also with {' '.join(extra_sets)}" if extra_sets else ""))
    write_table(out, "bench_stability", rows, COLUMNS, header)
    return rows


__all__ = ["CLEAN", "COLUMNS", "StressCase", "bench_stability", "capacity_line", "case_row",
           "classify", "memory_cell", "end_settlement_mm", "max_abs_pressure", "nonfinite_files",
           "run_case", "stress_cases"]
