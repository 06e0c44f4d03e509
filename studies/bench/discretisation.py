"""The element pairs side by side: error against wall time and memory on four cases.

``pilegroup bench discretisation`` runs each verification case of :data:`CASES` (undrained,
lateral and consolidation) with each pair of :data:`PAIRS`, every run in a process of its own
(serial) so that its peak resident memory is its own, and prints the table kept in
docs/benchmarks.md ("The default discretisation: the options measured"). The errors and
tolerances are the cases' own (``pilegroup verify``).
"""

from __future__ import annotations

import json
import resource
import subprocess
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["CASES", "PAIRS", "bench_discretisation", "markdown"]

#: The cases (each a ``pilegroup verify`` case that takes ``pair``) and the pairs compared.
CASES = ("undrained-loading", "lateral-single-pile", "terzaghi", "mandel")
PAIRS = ("Q1Q1", "Q2Q1")


def _child(case: str, pair: str, size: str) -> None:
    """Run one case in this process and print its result and peak memory as JSON."""
    from pilegroup.studies.verification.registry import run_case

    r = run_case(case, size, pair=pair)
    peak_mb = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    print(json.dumps({"case": case, "pair": pair, "error": r.error, "tolerance": r.tolerance,
                      "passed": r.passed, "wall_s": r.wall_s, "dofs": r.dofs,
                      "peak_mb": peak_mb}))


def _run(case: str, pair: str, size: str, timeout: float) -> dict[str, Any]:
    cmd = [sys.executable, "-m", "pilegroup.studies.bench.discretisation", case, pair, size]
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        return {"case": case, "pair": pair, "status": f"timeout after {timeout:g} s"}
    lines = [ln for ln in out.stdout.splitlines() if ln.startswith("{")]
    if out.returncode != 0 or not lines:
        tail = (out.stderr.strip().splitlines() or ["no output"])[-1]
        return {"case": case, "pair": pair, "status": f"failed: {tail}"}
    return json.loads(lines[-1]) | {"status": "complete"}


def markdown(rows: Sequence[dict[str, Any]]) -> str:
    """The table of ``rows`` (Markdown)."""
    out = ["| case | pair | unknowns | error | tolerance | within | wall (s) | peak memory (MB) |",
           "| --- | --- | ---: | ---: | ---: | --- | ---: | ---: |"]
    for r in rows:
        if r["status"] != "complete":
            out.append(f"| {r['case']} | {r['pair']} | | | | {r['status']} | | |")
            continue
        out.append(f"| {r['case']} | {r['pair']} | {r['dofs']:,} | {r['error']:.3g} | "
                   f"{r['tolerance']:g} | {'yes' if r['passed'] else 'no'} | "
                   f"{r['wall_s']:.1f} | {r['peak_mb']:.0f} |")
    return "\n".join(out)


def bench_discretisation(out_dir: str = "out/bench_discretisation",
                         cases: Sequence[str] = CASES, pairs: Sequence[str] = PAIRS,
                         size: str = "fast", timeout: float = 1800.0) -> list[dict[str, Any]]:
    """Each case with each pair, one process per run; writes and prints the table."""
    rows = [_run(case, pair, size, timeout) for case in cases for pair in pairs]
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    (out / "bench_discretisation.json").write_text(json.dumps(rows, indent=1), encoding="utf-8")
    table = markdown(rows)
    (out / "bench_discretisation.md").write_text(table + "\n", encoding="utf-8")
    print(table)
    return rows


if __name__ == "__main__":
    _child(*sys.argv[1:4])
