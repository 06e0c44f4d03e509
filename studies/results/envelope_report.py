"""The envelope's files: ``envelope.csv``, ``combination_results.csv`` and ``envelope.md``.

The columns and what the rows mean are in :mod:`pilegroup.studies.results.envelope`;
:func:`write_envelope` reads every complete combination's run folder and writes the three files
(atomically) into the combinations folder. ``envelope.md``: the combinations with their factors,
combined cap actions and status (the ones that did not complete listed with their message), the
envelope of the cap and of any pile, then the envelope per pile.
"""

from __future__ import annotations

import csv
import io
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path

from pilegroup.fileio import write_text_atomic
from pilegroup.studies.results.envelope import (
    ENVELOPE_COLUMNS,
    ENVELOPE_CSV,
    ENVELOPE_MD,
    RESULT_COLUMNS,
    RESULTS_CSV,
    CombinationRun,
    EnvelopeRow,
    Extreme,
    Reading,
    combination_readings,
    envelope,
)

Cell = str | int


def _num(x: float | None) -> str:
    return "" if x is None else f"{x:.10g}"


def _cells(e: Extreme | None) -> list[Cell]:
    """Value, pile, depth and time of an extreme (empty cells for what does not exist)."""
    if e is None:
        return ["", "", "", ""]
    return [_num(e.value), "" if e.pile is None else e.pile, _num(e.depth_m), _num(e.t_day)]


def _csv(columns: Sequence[str], rows: Iterable[Sequence[Cell]]) -> str:
    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(columns)
    w.writerows(rows)
    return buf.getvalue()


def results_csv(runs: Sequence[CombinationRun], readings: Mapping[str, list[Reading]]) -> str:
    """``combination_results.csv``: every combination's rows (one row if it did not complete)."""
    rows: list[list[Cell]] = []
    for run in runs:
        if run.status != "complete":
            blank: list[Cell] = [""] * (len(RESULT_COLUMNS) - 3)
            rows.append([run.name, run.status, *blank, run.message or ""])
            continue
        for r in readings.get(run.name, []):
            rows.append([run.name, run.status, r.quantity.name, r.quantity.unit,
                         "" if r.pile is None else r.pile, r.time, *_cells(r.max),
                         *_cells(r.min), r.note])
    return _csv(RESULT_COLUMNS, rows)


def envelope_csv(rows: Sequence[EnvelopeRow]) -> str:
    """``envelope.csv``: one row per quantity, pile and time."""
    out: list[list[Cell]] = []
    for e in rows:
        hi, lo = _cells(e.max), _cells(e.min)
        out.append([e.quantity.name, e.quantity.unit, "" if e.pile is None else e.pile, e.time,
                    hi[0], e.max_combination, *hi[1:], lo[0], e.min_combination, *lo[1:],
                    e.count, e.excluded_text()])
    return _csv(ENVELOPE_COLUMNS, out)


def _md_table(head: Sequence[str], rows: Iterable[Sequence[object]]) -> list[str]:
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    lines += ["| " + " | ".join(str(c) for c in r) + " |" for r in rows]
    return lines


def _combinations_md(runs: Sequence[CombinationRun]) -> list[str]:
    components: list[str] = []
    for run in runs:
        components += [k for k in run.actions if k not in components]
    rows = []
    for run in runs:
        factors = " + ".join(f"{f:g} x {case}" for case, f in run.factors.items())
        rows.append([f"`{run.name}`", run.status, factors,
                     *(f"{run.actions[k]:g}" if k in run.actions else "" for k in components)])
    lines = _md_table(["combination", "status", "factors", *components], rows)
    failed = [r for r in runs if r.status != "complete"]
    if failed:
        lines += ["", "Not in the envelope (did not complete): " + "; ".join(
            f"`{r.name}` ({r.status}{': ' + r.message if r.message else ''})" for r in failed)
            + "."]
    return lines


def _extreme_md(e: Extreme | None, governs: str) -> list[str]:
    if e is None:
        return ["", "", "", "", ""]
    return [f"{e.value:.4g}", f"`{governs}`", "" if e.pile is None else str(e.pile),
            "" if e.depth_m is None else f"{e.depth_m:.3g}", f"{e.t_day:g}"]


def _without_values(rows: Sequence[EnvelopeRow]) -> list[str]:
    """One line naming the quantities no combination gave, with why (not drawn as rows)."""
    why: dict[str, list[str]] = {}
    for e in rows:
        if e.max is None and e.pile is None:
            reasons = "; ".join(sorted({w for _, w in e.excluded})) or "no combination"
            names = why.setdefault(reasons, [])
            if f"`{e.quantity.name}`" not in names:
                names.append(f"`{e.quantity.name}`")
    if not why:
        return []
    return ["", "Without a value in any combination: " + "; ".join(
        f"{', '.join(names)} ({reasons})" for reasons, names in why.items()) + "."]


def _envelope_md(rows: Sequence[EnvelopeRow], per_pile: bool) -> list[str]:
    head = ["quantity", "unit", *(["pile"] if per_pile else []), "time",
            "max", "governs", "at pile", "depth m", "t day",
            "min", "governs", "at pile", "depth m", "t day", "excluded"]
    body = []
    for e in rows:
        if (e.pile is not None) != per_pile or e.max is None:
            continue
        body.append([f"`{e.quantity.name}`", e.quantity.unit,
                     *([str(e.pile)] if per_pile else []), e.time,
                     *_extreme_md(e.max, e.max_combination),
                     *_extreme_md(e.min, e.min_combination), e.excluded_text()])
    return _md_table(head, body)


def envelope_md(title: str, intro: Sequence[str], runs: Sequence[CombinationRun],
                rows: Sequence[EnvelopeRow]) -> str:
    """The text of ``envelope.md``."""
    lines = [f"# Load combinations: {title}", "", *intro, "", "## Combinations", "",
             *_combinations_md(runs), "", "## Envelope: the cap and any pile", "",
             "`max`/`min`: the largest and the smallest value over the combinations (and over "
             "the piles of the foundation for a pile quantity), with the combination that "
             "governs, the pile, the depth and the output time where it occurs. `time`: `last` "
             "at each combination's last output time, `all` over every output time. "
             "`excluded`: combinations without a value, and why.", "",
             *_envelope_md(rows, per_pile=False), *_without_values(rows)]
    if any(e.pile is not None for e in rows):
        lines += ["", "## Envelope per pile", "", *_envelope_md(rows, per_pile=True)]
    return "\n".join(lines) + "\n"


def write_envelope(out: Path, runs: Sequence[CombinationRun], title: str,
                   intro: Sequence[str] = ()) -> list[EnvelopeRow]:
    """Read every complete combination's run folder; write the three files into ``out``."""
    readings = {r.name: combination_readings(r) for r in runs if r.status == "complete"}
    rows = envelope(runs, readings)
    write_text_atomic(out / RESULTS_CSV, results_csv(runs, readings))
    write_text_atomic(out / ENVELOPE_CSV, envelope_csv(rows))
    write_text_atomic(out / ENVELOPE_MD, envelope_md(title, intro, runs, rows))
    return rows


__all__ = ["envelope_csv", "envelope_md", "results_csv", "write_envelope"]
