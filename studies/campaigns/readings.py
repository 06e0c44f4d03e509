"""The paper's three findings and its settlement, tested on each run of a batch of readings.

For every complete run folder of a batch (``pilegroup batch``, e.g.
docs/examples/pier667_readings.toml): the cap settlement and the soft layers' centre-pile
friction at 1, 89 and 317 days, and whether the paper's findings hold (Section 2):

1. shaft friction grows with time in the soft layers (:func:`~pilegroup.studies.report.run_report.
   friction_change`: end of loading against the last output time, the soft layers of the
   scenario's ``[reference]``, layers 1-3 of pier667);
2. relative displacement grows fastest in the first 89 days
   (:func:`~pilegroup.studies.report.run_report.relative_rates`, every layer of the centre pile);
3. friction increases with depth to about 30 m, then decreases: the layer with the largest
   mean friction at the last output time ends between :data:`PEAK_DEPTH_M` ± 5 m and every
   deeper layer carries less.

``python -m pilegroup.studies.campaigns.readings BATCH_DIR`` prints the Markdown table.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from pilegroup.studies.report.run_report import friction_change, relative_rates, soft_layers
from pilegroup.studies.results.rundata import RunData, layer_series, load_run, zero_note

#: Depth (m) where the paper's measured friction stops growing with depth (Section 2: "from
#: 0 m to 30.36 m ... increases", then decreases to the pile bottom).
PEAK_DEPTH_M = 30.36
TIMES = (1.0, 89.0, 317.0)


def _at(t: np.ndarray, v: np.ndarray, tq: float) -> float:
    """``v`` at output time ``tq`` (NaN when the run has no such time)."""
    k = np.flatnonzero(np.isclose(t, tq))
    return float(v[k[0]]) if k.size else float("nan")


def _verdict(flags: dict[int, bool]) -> str:
    if not flags:
        return "n/a"
    if all(flags.values()):
        return "yes"
    some = [str(j) for j, ok in flags.items() if ok]
    return "no" + (f" (layers {', '.join(some)})" if some else "")


def friction_peak(run: RunData) -> tuple[int, bool] | None:
    """Layer of the largest centre-pile mean friction at the last time, and finding 3."""
    series = layer_series(run, "shaft_friction_kPa")
    if not series or run.history is None:
        return None
    f = {j: float(v[-1]) for j, (_, v) in series.items()}
    j = max(f, key=f.get)
    bottom = float(run.history["depth_bottom_m"][run.history["layer"] == j][0])
    deeper = [f[k] for k in f if k > j]
    return j, abs(bottom - PEAK_DEPTH_M) <= 5.0 and all(x < f[j] for x in deeper)


def case_row(run: RunData, times: tuple[float, ...] = TIMES) -> list[str]:
    """Settlement (mm) and soft-layer friction (kPa) at ``times``; the three findings."""
    s = run.settlement
    w = [1000 * _at(s["t_day"], s["settlement_m"], tq) for tq in times] if s is not None \
        else [float("nan")] * len(times)
    series = layer_series(run, "shaft_friction_kPa")
    fr = ["/".join(f"{_at(*series[j], tq):.2f}" if j in series else "-"
                   for j in soft_layers(run)) or "-" for tq in times]
    rates = {} if zero_note(run) else {j: r[5] for j, r in relative_rates(run).items()}
    peak = friction_peak(run)
    third = "n/a" if peak is None else ("yes" if peak[1] else "no") + f" (peak in layer {peak[0]})"
    return [*(f"{x:.2f}" for x in w), *fr,
            _verdict({j: c[2] for j, c in friction_change(run, soft_layers(run)).items()}),
            _verdict(rates), third]


HEADER = ("| case | settlement 1 d (mm) | 89 d | 317 d | friction layers 1/2/3, 1 d (kPa) "
          "| 89 d | 317 d | friction grows in soft layers | rel. displacement fastest 0-89 d "
          "| friction peaks at ~30 m |")


def readings_table(batch_dir: Path, times: tuple[float, ...] = TIMES) -> str:
    """The Markdown table of every complete case folder of ``batch_dir`` (three ``times``)."""
    lines = [HEADER, "| --- |" + " ---: |" * 6 + " --- | --- | --- |"]
    for case in sorted(p for p in Path(batch_dir).iterdir() if (p / "summary.json").is_file()):
        run = load_run(case)
        if run.complete:
            lines.append(f"| {case.name} | " + " | ".join(case_row(run, times)) + " |")
    return "\n".join(lines) + "\n"


if __name__ == "__main__":
    sys.stdout.write(readings_table(Path(sys.argv[1])))
