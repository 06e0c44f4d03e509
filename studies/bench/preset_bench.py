"""Which linear-solver preset finishes the job first: the measurements behind ``auto``.

``pilegroup bench presets --presets P1 P2 ... --sizes H ... --symmetry S ...`` runs the whole
job (:func:`~pilegroup.studies.bench.pier_bench.bench_pier`: one ``pilegroup run`` per case in
its own process group) for every preset, size and model part, and prints the table of runs
(``bench_presets.md`` and ``.json``) and the source of
:data:`~pilegroup.studies.run.auto_preset.AUTO_TABLE` those runs select (``auto_table.py``),
which is what ``studies/run/auto_preset.py`` should hold. A preset that handed over to its
fallback during a run is reported as it ended (column ``preset_at_end``) and does not count as
its own result.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from pilegroup.fileio import write_text_atomic
from pilegroup.studies.bench.benchrun import write_table
from pilegroup.studies.bench.pier_bench import COLUMNS, bench_pier
from pilegroup.studies.run.auto_preset import fastest_rows, table_source

PRESET_COLUMNS = ("preset", "interface", *(c if c != "preset" else "preset_at_end"
                                           for c in COLUMNS))


def bench_presets(presets: Sequence[str], scenario: str = "pier667",
                  sizes: Sequence[float] = (1.0,), symmetries: Sequence[str] = ("auto",),
                  ranks: int = 2, out_dir: str | Path = "out/bench_presets",
                  timeout: float | None = None, sets: Sequence[str] = ()
                  ) -> list[dict[str, Any]]:
    """Run the job with every preset; print and write the runs and the regenerated table."""
    out = Path(out_dir)
    rows: list[dict[str, Any]] = []
    for preset in presets:
        runs = bench_pier(scenario, sizes, symmetries, ranks, out / preset, timeout,
                          [*sets, f"numerics.solver.preset={preset}"])
        for r in runs:
            at_end = r.pop("preset", None)
            complete = r["status"] == "complete" and at_end == preset
            itf = r.pop("interface_mode", None)
            rows.append({"preset": preset, "interface": None if itf is None else itf != "tied",
                         "preset_at_end": at_end,
                         **r, "status": r["status"] if complete or at_end is None
                         else f"handed over to {at_end}"})
    write_table(out, "bench_presets", rows, PRESET_COLUMNS,
                f"{scenario}; presets {', '.join(presets)}")
    source = table_source(fastest_rows(rows))
    write_text_atomic(out / "auto_table.py", source + "\n")
    print(source)
    return rows
