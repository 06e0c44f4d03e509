"""Scenario keys fitted to a measured history; every evaluation a model run of a batch.

Up to three keys (any key ``--set`` accepts) vary between their bounds; scipy's bounded least
squares (``trf``) minimises the misfit between the measured values and the model's at the same
times: a settlement history (layout of ``settlement.csv``: ``t_day,settlement_m``) or strain
gauge readings (layout of ``gauges.csv``: ``time_day,pile,section,strain``). The model's values
between its output times are interpolated linearly, so its ``time.output_days`` should hold the
measured times.

Each point the solver asks for is run together with its finite-difference neighbours (one step
of ``REL_STEP`` times the value per key, towards the inside of the bounds): ``1 + keys`` cases of
one batch (:func:`pilegroup.studies.batch.execute.run_batch`), which run side by side on the
batch's MPI groups. A case is named by the digest of its values and every batch holds every
case so far, so ``OUT/batch.csv`` is the record of all evaluations and a fit run again (the
same command) finds its cases complete and resumes where it stopped. Residuals are scaled by
the largest measured magnitude; the misfit is reported in the data's unit.
"""

from __future__ import annotations

import hashlib
import math
import time
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from mpi4py import MPI
from scipy.optimize import least_squares

from pilegroup.errors import FitError, ScenarioError
from pilegroup.fileio import read_json
from pilegroup.model import load_scenario
from pilegroup.studies.batch.batch_plan import BatchCase, BatchPlan
from pilegroup.studies.batch.execute import run_batch
from pilegroup.studies.batch.rows import RECORD
from pilegroup.studies.lab.fit_stats import FitResult, check_converged, rms, statistics
from pilegroup.studies.results.tables import (
    GAUGES_CSV,
    SETTLEMENT_CSV,
    Table,
    read_csv,
    read_table,
)

#: Relative finite-difference step of each key.
REL_STEP = 0.01
MAX_KEYS = 3
#: (required columns, value column, unit) of the two measured layouts.
LAYOUTS = {"settlement": (("t_day", "settlement_m"), "settlement_m", "m"),
           "gauges": (("time_day", "pile", "section", "strain"), "strain", "-")}


@dataclass(frozen=True)
class VaryKey:
    """A scenario key fitted between ``low`` and ``high``."""

    key: str
    low: float
    high: float


def parse_vary(text: str) -> VaryKey:
    """``KEY=LOW:HIGH`` -> :class:`VaryKey`."""
    key, _, rng = text.partition("=")
    lo, _, hi = rng.partition(":")
    try:
        low, high = float(lo), float(hi)
    except ValueError:
        low = high = math.nan
    if not key.strip() or not (math.isfinite(low) and math.isfinite(high) and low < high):
        raise ScenarioError("--vary", text, "must be KEY=LOW:HIGH with numbers LOW < HIGH, "
                            "e.g. layers[0].E_MPa=1:6")
    return VaryKey(key.strip(), low, high)


def scenario_value(sc: object, key: str) -> Any:
    """The value of a dotted key (``layers[1].interface.eta_MPa_day``) of a scenario."""
    node: Any = sc
    for part in key.split("."):
        name, _, idx = part.partition("[")
        node = getattr(node, name, None)
        if idx and node is not None:
            i = int(idx.rstrip("]"))
            node = node[i] if 0 <= i < len(node) else None
        if node is None:
            return None
    return node


@dataclass(frozen=True)
class Measured:
    """A measured history: its layout, its rows and the value of each row."""

    path: Path
    layout: str
    table: Table
    values: np.ndarray

    @property
    def times(self) -> np.ndarray:
        """Time of each row, days."""
        return self.table["t_day" if self.layout == "settlement" else "time_day"]

    def model_values(self, run_dir: Path) -> np.ndarray:
        """The model's values at the measured rows (linear in time between outputs)."""
        if self.layout == "settlement":
            t = read_csv(run_dir / SETTLEMENT_CSV)
            assert t is not None, run_dir
            return self._interp(t["t_day"], t["settlement_m"], self.times, run_dir)
        g = read_csv(run_dir / GAUGES_CSV)
        if g is None:
            raise ScenarioError(str(self.path), "gauges", "the scenario writes no gauges.csv; "
                                "set outputs.gauge_depths_m")
        out = np.empty(self.values.size)
        for i, (t, pile, sec) in enumerate(zip(self.times, self.table["pile"],
                                               self.table["section"], strict=True)):
            m = (g["pile"] == pile) & (g["section"] == sec)
            if not np.any(m):
                raise ScenarioError(f"{self.path} row {i + 2}", f"pile {pile:g} section "
                                    f"{sec:g}", "the model has no such gauge")
            out[i] = self._interp(g["time_day"][m], g["strain"][m], np.array([t]), run_dir)[0]
        return out

    def _interp(self, tm: np.ndarray, vm: np.ndarray, t: np.ndarray, run_dir: Path
                ) -> np.ndarray:
        if t.min() < tm.min() - 1e-9 or t.max() > tm.max() + 1e-9:
            raise ScenarioError(f"{self.path} times", f"{t.min():g}..{t.max():g} day",
                                f"must lie within the model's output times {tm.min():g}.."
                                f"{tm.max():g} day ({run_dir})")
        order = np.argsort(tm, kind="stable")
        return np.interp(t, tm[order], vm[order])


def read_measured(path: Path) -> Measured:
    """A measured settlement history or gauge readings, by the columns of the file."""
    if not path.is_file():
        raise ScenarioError("--data", str(path), "no such file")
    head = path.read_text(encoding="utf-8", errors="replace").splitlines()[:1]
    cols = {c.strip() for c in head[0].split(",")} if head else set()
    layout = "gauges" if "strain" in cols else "settlement"
    required, value, _ = LAYOUTS[layout]
    t = read_table(path, required)
    bad = np.nonzero(~np.isfinite(np.column_stack([t[c] for c in required])))[0]
    if bad.size:
        raise ScenarioError(f"{path} row {bad[0] + 2}", "empty", "every cell of "
                            + ", ".join(required) + " must be a number")
    return Measured(path, layout, t, t[value])


def case_name(values: Sequence[float]) -> str:
    """The case (run folder) of a point: a digest of its values."""
    text = ",".join(f"{v:.12g}" for v in values)
    return "run-" + hashlib.sha256(text.encode()).hexdigest()[:12]


class ScenarioFit:
    """The model runs of one fit: cases so far, their residuals, the batch that runs them."""

    def __init__(self, source: str, sets: Mapping[str, Any], vary: Sequence[VaryKey],
                 data: Measured, out: Path, ranks_per_case: int = 1,
                 comm: MPI.Comm = MPI.COMM_WORLD, progress: bool = False,
                 max_runs: int = 60) -> None:
        self.source, self.sets, self.vary, self.data = source, dict(sets), tuple(vary), data
        self.out, self.ranks, self.comm, self.progress = out, ranks_per_case, comm, progress
        self.max_runs = max_runs
        self.cases: dict[str, tuple[float, ...]] = {}
        self.model: dict[str, np.ndarray] = {}
        self.scale = float(np.abs(data.values).max()) or 1.0
        self.wall_s = 0.0

    def _overrides(self, x: Sequence[float]) -> tuple[tuple[str, Any], ...]:
        return tuple(self.sets.items()) + tuple((v.key, float(xi))
                                                for v, xi in zip(self.vary, x, strict=True))

    def step(self, x: np.ndarray, i: int) -> float:
        """The finite-difference step of key ``i`` at ``x`` (signed, towards the inside)."""
        v = self.vary[i]
        h = REL_STEP * max(abs(x[i]), 1e-3 * (v.high - v.low))
        return h if x[i] + h <= v.high else -h

    def run(self, points: Sequence[Sequence[float]]) -> None:
        """Run the points not run yet (one batch holding every case so far)."""
        new = [tuple(float(a) for a in p) for p in points]
        for p in new:
            self.cases.setdefault(case_name(p), p)
        if len(self.cases) > self.max_runs:
            raise FitError(f"the fit did not converge within --max-runs {self.max_runs} model "
                           "runs")
        plan = BatchPlan(self.source, tuple(BatchCase(n, self._overrides(p))
                                            for n, p in self.cases.items()), "fit")
        t0 = time.monotonic()
        run_batch(plan, self.out, self.ranks, self.comm, self.progress)
        self.wall_s += time.monotonic() - t0
        for n in (case_name(p) for p in new):
            if n not in self.model:
                self.model[n] = self._read(n)

    def _read(self, name: str) -> np.ndarray:
        run_dir = self.out / name
        summary = read_json(run_dir / "summary.json") or {}
        if summary.get("status") != "complete":
            rec = read_json(run_dir / RECORD) or {}
            raise FitError(f"model run {name} ({self.describe(self.cases[name])}) "
                           f"{rec.get('status', 'not run')}: {rec.get('message')}")
        return self.data.model_values(run_dir)

    def values_at(self, p: Sequence[float]) -> np.ndarray:
        """The model's values at the measured rows of the run of point ``p`` (run before)."""
        return self.model[case_name(p)]

    @property
    def unit(self) -> str:
        """The unit of the measured values."""
        return LAYOUTS[self.data.layout][2]

    def describe(self, p: Sequence[float]) -> str:
        """``key = value, ...`` of a point."""
        return ", ".join(f"{v.key} = {x:.6g}" for v, x in zip(self.vary, p, strict=True))

    def residual(self, x: np.ndarray) -> np.ndarray:
        """Scaled residuals at ``x``; runs ``x`` and its neighbours if not run yet."""
        if case_name(x) not in self.model:
            pts = [x] + [x + self.step(x, i) * np.eye(len(x))[i] for i in range(len(x))]
            self.run(pts)
        return (self.model[case_name(x)] - self.data.values) / self.scale

    def jacobian(self, x: np.ndarray) -> np.ndarray:
        """Forward differences of the scaled residuals (from the neighbours' runs)."""
        r0 = self.residual(x)
        cols = []
        for i in range(len(x)):
            h = self.step(x, i)
            xi = x + h * np.eye(len(x))[i]
            if case_name(xi) not in self.model:
                self.run([xi])
            cols.append((self.model[case_name(xi)] / self.scale - self.data.values / self.scale
                         - r0) / h)
        return np.column_stack(cols)

    def records(self) -> list[dict[str, Any]]:
        """One record per evaluation: values, misfit (data unit), status, wall time."""
        out = []
        for n, p in self.cases.items():
            rec = read_json(self.out / n / RECORD) or {}
            wall = (rec["end"] - rec["start"]) if rec.get("end") and rec.get("start") else None
            mis = rms(self.model[n] - self.data.values) if n in self.model else None
            out.append({"name": n, **{v.key: x for v, x in zip(self.vary, p, strict=True)},
                        "misfit": mis, "status": rec.get("status"), "wall_s": wall})
        return out


def start_point(source: str, sets: Mapping[str, Any], vary: Sequence[VaryKey],
                start: Mapping[str, float]) -> np.ndarray:
    """The start of each key: ``start``, else the scenario's value; inside its bounds."""
    if not 1 <= len(vary) <= MAX_KEYS:
        raise ScenarioError("--vary", len(vary), f"give 1 to {MAX_KEYS} keys")
    if len({v.key for v in vary}) != len(vary):
        raise ScenarioError("--vary", [v.key for v in vary], "each key once")
    for k in start:
        if k not in {v.key for v in vary}:
            raise ScenarioError("--start", k, "must name a --vary key")
    sc = load_scenario(source, sets)
    x0 = []
    for v in vary:
        val = start.get(v.key, scenario_value(sc, v.key))
        if isinstance(val, bool) or not isinstance(val, int | float):
            raise ScenarioError(v.key, val, "is not a number of the scenario; give --start "
                                f"{v.key}=VALUE")
        if not v.low <= val <= v.high:
            raise ScenarioError(f"start of {v.key}", val, f"must lie in [{v.low:g}, {v.high:g}]")
        load_scenario(source, {**sets, v.key: v.low})  # both bounds must make valid scenarios
        load_scenario(source, {**sets, v.key: v.high})
        x0.append(float(val))
    return np.array(x0)


def fit_scenario(fit: ScenarioFit, x0: np.ndarray) -> FitResult:
    """Run the fit from ``x0``; the fitted keys, their errors, the misfit and the records."""
    if fit.data.values.size < len(x0):
        raise ScenarioError(str(fit.data.path), f"{fit.data.values.size} data points",
                            f"fewer than the {len(x0)} keys fitted")
    lo = np.array([v.low for v in fit.vary])
    hi = np.array([v.high for v in fit.vary])
    res = least_squares(fit.residual, x0, jac=fit.jacobian, bounds=(lo, hi), x_scale=np.abs(x0),
                        method="trf", xtol=1e-4, ftol=1e-8, gtol=1e-8, max_nfev=fit.max_runs)
    names = tuple(v.key for v in fit.vary)
    check_converged(res, names, lo, hi, str(fit.data.path))
    se, corr = statistics(res.jac, res.fun, names, len(names))
    misfit = rms(res.fun * fit.scale)
    unit = LAYOUTS[fit.data.layout][2]
    details = (("scenario", fit.source), ("set", dict(fit.sets)), ("start", list(map(float, x0))),
               ("runs", len(fit.cases)), ("wall_s", round(fit.wall_s, 1)),
               ("best_run", case_name(res.x)), ("evaluations_record", fit.records()))
    return FitResult("scenario", str(fit.data.path), names, tuple(map(float, res.x)), se, corr,
                     misfit, unit, int(fit.data.values.size), len(fit.cases), details)


__all__ = ["LAYOUTS", "MAX_KEYS", "Measured", "REL_STEP", "ScenarioFit", "VaryKey",
           "case_name", "fit_scenario", "parse_vary", "read_measured", "scenario_value",
           "start_point"]
