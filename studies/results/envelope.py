"""The envelope of load combinations: what each combination gives and which one governs.

Pure: reads the run folders of a combinations batch (the CSV contract of
:mod:`pilegroup.studies.results.tables`) and writes ``envelope.csv``,
``combination_results.csv`` and ``envelope.md`` (:mod:`pilegroup.studies.results.envelope_report`).

Quantities (unit; file of the run folder):

* ``settlement_m`` (m; ``settlement.csv``): the cap settlement, down positive;
* ``ux_m``, ``uy_m``, ``uz_m`` (m), ``rx_rad``, ``ry_rad``, ``rz_rad`` (rad; ``cap_motion.csv``):
  the cap's displacement (z up) and rotation (right-hand rule) at the reference point;
* ``N_kN`` (kN; ``pile_heads.csv``): the axial force at a pile head, compression positive (a
  run folder without ``pile_heads.csv`` gives it from ``pile_loads.csv``'s ``head_force_kN``);
* ``V_kN`` (kN; ``pile_heads.csv``): the shear resultant at a pile head, ``sqrt(Vx^2 + Vy^2)``;
* ``M_max_kNm`` (kNm; ``pile_max_moment.csv``): the largest resultant bending moment along a
  pile, at the depth ``depth_m`` (m below the ground surface).

Each quantity is read over a set of piles and output times, a row of the tables:

* ``pile``: empty for the cap's quantities and for "any pile" (every pile of the foundation),
  a number for that pile alone;
* ``time``: ``last`` (the last output time of the file the quantity comes from) or ``all``
  (every output time: the extreme over the whole history).

Per combination and row, ``max`` and ``min`` are the largest and the smallest value over the
row's piles and times, each with the pile (``max_pile``), the depth (``max_depth_m``, for
``M_max_kNm``) and the output time (``max_t_day``) where it occurs. So ``N_kN`` of any pile
gives the largest head compression (``max``) and the smallest head force, a tension when
negative (``min``); ``M_max_kNm`` of any pile gives the largest bending moment of the
foundation with its pile and depth.

``combination_results.csv``: ``combination,status,quantity,unit,pile,time,max,max_pile,
max_depth_m,max_t_day,min,min_pile,min_depth_m,min_t_day,note``: each combination's rows; a
combination that did not complete (``failed``, ``interrupted``, ``pending``) is one row with its
status and its message in ``note``; a quantity whose file a complete run folder lacks has
empty values and ``note`` = ``no <file>``.

``envelope.csv``: ``quantity,unit,pile,time,max,max_combination,max_pile,max_depth_m,max_t_day,
min,min_combination,min_pile,min_depth_m,min_t_day,combinations,excluded``: for each row the
largest of the combinations' ``max`` and the smallest of their ``min`` with the combination
that governs (the first in the file's order on a tie), ``combinations`` the number of
combinations that gave a value and ``excluded`` those that did not, each with why
(``ULS_wind (failed); SLS (no pile_max_moment.csv)``). A value that does not exist is an empty
cell. Only complete combinations enter the envelope: a failed one is listed, never dropped
silently.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.studies.results.tables import (
    CAP_MOTION_CSV,
    HEADS_CSV,
    LOADS_CSV,
    MAX_MOMENT_CSV,
    SETTLEMENT_CSV,
    Table,
    read_csv,
)

log = logging.getLogger(__name__)

ENVELOPE_CSV = "envelope.csv"
ENVELOPE_MD = "envelope.md"
RESULTS_CSV = "combination_results.csv"
#: The files of a combinations folder (besides the batch's own).
ENVELOPE_FILES = (ENVELOPE_CSV, ENVELOPE_MD, RESULTS_CSV)

_EXTREME = ("max", "max_pile", "max_depth_m", "max_t_day", "min", "min_pile", "min_depth_m",
            "min_t_day")
#: Columns of ``combination_results.csv``.
RESULT_COLUMNS = ("combination", "status", "quantity", "unit", "pile", "time", *_EXTREME, "note")
#: Columns of ``envelope.csv``.
ENVELOPE_COLUMNS = ("quantity", "unit", "pile", "time", "max", "max_combination", "max_pile",
                    "max_depth_m", "max_t_day", "min", "min_combination", "min_pile",
                    "min_depth_m", "min_t_day", "combinations", "excluded")
#: The ``time`` of a row: the last output time, or every output time.
TIMES = ("last", "all")


@dataclass(frozen=True)
class Quantity:
    """A quantity of the envelope: its name, unit, file, and whether it belongs to each pile."""

    name: str
    unit: str
    file: str
    per_pile: bool
    what: str


#: The quantities, in the order of the tables.
QUANTITIES = (
    Quantity("settlement_m", "m", SETTLEMENT_CSV, False, "cap settlement, down positive"),
    *(Quantity(f"u{a}_m", "m", CAP_MOTION_CSV, False, f"cap displacement {a}")
      for a in "xyz"),
    *(Quantity(f"r{a}_rad", "rad", CAP_MOTION_CSV, False, f"cap rotation about {a}")
      for a in "xyz"),
    Quantity("N_kN", "kN", HEADS_CSV, True, "head axial force, compression positive"),
    Quantity("V_kN", "kN", HEADS_CSV, True, "head shear resultant"),
    Quantity("M_max_kNm", "kNm", MAX_MOMENT_CSV, True,
             "largest bending moment along the pile"),
)


@dataclass(frozen=True)
class CombinationRun:
    """A combination as the batch left it: its run folder, status and (for the report) loads.

    ``factors``: load case -> factor; ``actions``: the combined cap actions (component ->
    value, ``Fx_kN`` ... ``Mz_kNm``).
    """

    name: str
    run_dir: Path
    status: str = "complete"
    message: str | None = None
    factors: Mapping[str, float] = field(default_factory=dict)
    actions: Mapping[str, float] = field(default_factory=dict)


@dataclass(frozen=True)
class Extreme:
    """A value and where (pile, depth) and when (output time) it occurs."""

    value: float
    t_day: float
    pile: int | None = None
    depth_m: float | None = None


@dataclass(frozen=True)
class Reading:
    """One row of a combination: a quantity over ``pile`` (``None``: cap or any pile) at ``time``.

    ``max``/``min`` are ``None`` where the run folder has no value (``note`` says why).
    """

    quantity: Quantity
    pile: int | None
    time: str
    max: Extreme | None
    min: Extreme | None
    note: str = ""


@dataclass(frozen=True)
class Samples:
    """A quantity's values in a run folder: output time, pile (0: the cap), value, depth."""

    t: np.ndarray
    pile: np.ndarray
    value: np.ndarray
    depth: np.ndarray


def _samples(t: np.ndarray, value: np.ndarray, pile: np.ndarray | None = None,
             depth: np.ndarray | None = None) -> Samples:
    n = len(t)
    return Samples(t, np.zeros(n, int) if pile is None else pile.astype(int), value,
                   np.full(n, np.nan) if depth is None else depth)


def _quantity_samples(q: Quantity, tables: Mapping[str, Table | None]) -> Samples | None:
    """The values of ``q`` in the tables read from a run folder (``None``: its file is absent)."""
    if q.name == "settlement_m":
        t = tables[SETTLEMENT_CSV]
        return None if t is None else _samples(t["t_day"], t["settlement_m"])
    if q.file == CAP_MOTION_CSV:
        t = tables[CAP_MOTION_CSV]
        return None if t is None else _samples(t["t_day"], t[q.name])
    if q.file == MAX_MOMENT_CSV:
        t = tables[MAX_MOMENT_CSV]
        return None if t is None else _samples(t["t_day"], t["M_max_kNm"], t["pile"],
                                               t["depth_m"])
    heads = tables[HEADS_CSV]
    if heads is not None:
        value = heads["N_kN"] if q.name == "N_kN" else np.hypot(heads["Vx_kN"], heads["Vy_kN"])
        return _samples(heads["t_day"], value, heads["pile"])
    loads = tables[LOADS_CSV]
    if q.name == "N_kN" and loads is not None:
        return _samples(loads["t_day"], loads["head_force_kN"], loads["pile"])
    return None


def _extreme(s: Samples, mask: np.ndarray, largest: bool, per_pile: bool) -> Extreme | None:
    idx = np.flatnonzero(mask & np.isfinite(s.value))
    if idx.size == 0:
        return None
    i = idx[np.argmax(s.value[idx]) if largest else np.argmin(s.value[idx])]
    depth = float(s.depth[i]) if math.isfinite(s.depth[i]) else None
    return Extreme(float(s.value[i]), float(s.t[i]), int(s.pile[i]) if per_pile else None,
                   depth)


def quantity_readings(q: Quantity, s: Samples) -> list[Reading]:
    """The rows of ``q`` from its samples: any pile (or the cap), then each pile; last, all."""
    piles: list[int | None] = [None]
    if q.per_pile:
        piles += [int(p) for p in np.unique(s.pile)]
    last = s.t == np.max(s.t) if s.t.size else np.zeros(0, bool)
    out = []
    for pile in piles:
        on = np.ones(s.t.size, bool) if pile is None else s.pile == pile
        for time in TIMES:
            mask = on & last if time == "last" else on
            out.append(Reading(q, pile, time, _extreme(s, mask, True, q.per_pile),
                               _extreme(s, mask, False, q.per_pile)))
    return out


def _absent(q: Quantity, note: str) -> list[Reading]:
    return [Reading(q, None, time, None, None, note) for time in TIMES]


def _read_tables(run_dir: Path) -> tuple[dict[str, Table | None], dict[str, str]]:
    """The files the quantities need, and a note for each file absent or unreadable."""
    tables: dict[str, Table | None] = {}
    notes: dict[str, str] = {}
    for name in (SETTLEMENT_CSV, CAP_MOTION_CSV, HEADS_CSV, LOADS_CSV, MAX_MOMENT_CSV):
        try:
            tables[name] = read_csv(run_dir / name)
        except ScenarioError as exc:
            log.warning("envelope: %s", exc)
            tables[name], notes[name] = None, f"{name} unreadable"
        if tables[name] is None:
            notes.setdefault(name, f"no {name}")
    return tables, notes


def combination_readings(run: CombinationRun) -> list[Reading]:
    """Every row of a complete combination's run folder, in the order of :data:`QUANTITIES`."""
    tables, notes = _read_tables(run.run_dir)
    out: list[Reading] = []
    for q in QUANTITIES:
        s = _quantity_samples(q, tables)
        out += _absent(q, notes[q.file]) if s is None else quantity_readings(q, s)
    return out


@dataclass(frozen=True)
class EnvelopeRow:
    """One row of ``envelope.csv``: the extremes over the combinations and who governs."""

    quantity: Quantity
    pile: int | None
    time: str
    max: Extreme | None
    max_combination: str
    min: Extreme | None
    min_combination: str
    count: int
    excluded: tuple[tuple[str, str], ...]
    """The combinations without a value, each with why (its status, or ``no <file>``)."""

    def excluded_text(self) -> str:
        """``excluded`` as ``envelope.csv`` writes it: ``name (why); ...``."""
        return "; ".join(f"{name} ({why})" for name, why in self.excluded)


def _row_order(keys: set[tuple[str, int | None, str]]) -> list[tuple[str, int | None, str]]:
    rank = {q.name: i for i, q in enumerate(QUANTITIES)}
    return sorted(keys, key=lambda k: (rank[k[0]], -1 if k[1] is None else k[1],
                                       TIMES.index(k[2])))


def envelope(runs: Sequence[CombinationRun],
             readings: Mapping[str, list[Reading]]) -> list[EnvelopeRow]:
    """The envelope rows over ``runs`` (``readings``: the rows of each complete combination)."""
    index = {name: {(r.quantity.name, r.pile, r.time): r for r in rs}
             for name, rs in readings.items()}
    by_name = {q.name: q for q in QUANTITIES}
    keys = {k for own in index.values() for k in own}
    keys |= {(q.name, None, t) for q in QUANTITIES for t in TIMES}
    out = []
    for name, pile, time in _row_order(keys):
        hi: tuple[Extreme, str] | None = None
        lo: tuple[Extreme, str] | None = None
        count, excluded = 0, []
        for run in runs:
            if run.status != "complete":
                excluded.append((run.name, run.status))
                continue
            own = index.get(run.name, {})
            r = own.get((name, pile, time))
            if r is None or r.max is None or r.min is None:
                why = r if r is not None else own.get((name, None, time))  # a file's note
                excluded.append((run.name, why.note if why is not None and why.note
                                 else "no data"))
                continue
            count += 1
            if hi is None or r.max.value > hi[0].value:
                hi = (r.max, run.name)
            if lo is None or r.min.value < lo[0].value:
                lo = (r.min, run.name)
        out.append(EnvelopeRow(by_name[name], pile, time, hi[0] if hi else None,
                               hi[1] if hi else "", lo[0] if lo else None, lo[1] if lo else "",
                               count, tuple(excluded)))
    return out


__all__ = ["ENVELOPE_COLUMNS", "ENVELOPE_CSV", "ENVELOPE_FILES", "ENVELOPE_MD", "QUANTITIES",
           "RESULTS_CSV", "RESULT_COLUMNS", "TIMES", "CombinationRun", "EnvelopeRow", "Extreme",
           "Quantity", "Reading", "Samples", "combination_readings", "envelope",
           "quantity_readings"]
