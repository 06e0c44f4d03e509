"""The verification benchmark: error against wall time of the consolidation cases.

``pilegroup bench verification`` runs :func:`bench_verification`; the table goes to
docs/benchmarks.md, section "Verification: error vs wall time".
"""

from __future__ import annotations

import json
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from matplotlib.figure import Figure

from pilegroup.studies.verification.common import world
from pilegroup.studies.verification.consolidation import mandel, terzaghi
from pilegroup.studies.verification.registry import CaseResult

__all__ = ["BENCH_LEVELS", "bench_markdown", "bench_verification"]

#: Per case: the mesh levels, and the (steps per decade, dT_max) time levels.
BENCH_LEVELS: dict[str, dict[str, Any]] = {
    "terzaghi": {"mesh": [8, 16, 32], "time": [(8, 4e-3), (16, 2e-3), (32, 1e-3)]},
    "mandel": {"mesh": [4, 8, 16], "time": [(4, 0.04), (8, 0.02), (16, 0.01)]},
}


def _bench_run(case: str, pair: str, nmesh: int, spd: int, dtm: float) -> CaseResult:
    """One benchmark run of ``case`` at the given mesh and time levels."""
    if case == "terzaghi":
        return terzaghi(pair=pair, nz=nmesh, steps_per_decade=spd, dT_max=dtm)
    return mandel(pair=pair, n=nmesh, steps_per_decade=spd, dT_max=dtm)


def bench_verification(out_dir: str = "out/bench_verification",
                       cases: Sequence[str] = ("terzaghi", "mandel"),
                       pairs: Sequence[str] = ("Q2Q1", "Q1Q1"),
                       levels: dict[str, dict[str, Any]] | None = None) -> list[dict[str, Any]]:
    """Error against wall time: each case x element pair x 3 meshes x 3 step counts.

    Writes ``bench_verification.json``, ``bench_verification.png`` (error vs wall time, log-log)
    and ``bench_verification.md`` (the table for docs/benchmarks.md, section "Verification: error
    vs wall time") to ``out_dir`` (rank 0), and returns the rows. Wall times are the cases' own
    (mesh, forms, all steps), measured on ``MPI.COMM_WORLD``.
    """
    comm = world()
    levels = levels or BENCH_LEVELS
    rows: list[dict[str, Any]] = []
    for case in cases:
        for pair in pairs:
            for nmesh in levels[case]["mesh"]:
                for spd, dtm in levels[case]["time"]:
                    r = _bench_run(case, pair, nmesh, spd, dtm)
                    row = {"case": case, "pair": pair, "mesh": nmesh, "steps": r.steps,
                           "dofs": r.dofs, "newton": r.newton_its, "error": r.error,
                           "tolerance": r.tolerance, "passed": r.passed, "wall_s": r.wall_s,
                           "ranks": comm.size}
                    rows.append(row)
                    if comm.rank == 0:
                        print(f"{case:<9} {pair} mesh {nmesh:>3} steps {r.steps:>5} "
                              f"dofs {r.dofs:>6} error {r.error:.3e} wall {r.wall_s:7.2f} s",
                              flush=True)
    if comm.rank == 0:
        out = Path(out_dir)
        out.mkdir(parents=True, exist_ok=True)
        (out / "bench_verification.json").write_text(json.dumps(rows, indent=1))
        (out / "bench_verification.md").write_text(bench_markdown(rows))
        _bench_plot(rows, out / "bench_verification.png")
    comm.barrier()
    return rows


def bench_markdown(rows: Sequence[dict[str, Any]]) -> str:
    """Markdown table of benchmark rows (one line per run)."""
    lines = ["| case | pair | mesh | steps | DOFs | Newton | error | tol | wall (s) |",
             "| --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"]
    for r in rows:
        lines.append(f"| {r['case']} | {r['pair']} | {r['mesh']} | {r['steps']} | {r['dofs']} "
                     f"| {r['newton']} | {r['error']:.2e} | {r['tolerance']:.0e} "
                     f"| {r['wall_s']:.2f} |")
    return "\n".join(lines) + "\n"


def _bench_plot(rows: Sequence[dict[str, Any]], path: Path) -> None:
    """Error against wall time, one panel per case, one line per pair and mesh."""
    cases = sorted({r["case"] for r in rows})
    fig = Figure(figsize=(5.5 * len(cases), 4.2))
    axes = fig.subplots(1, len(cases), squeeze=False)
    for ax, case in zip(axes[0], cases, strict=True):
        for pair, mk in (("Q2Q1", "o"), ("Q1Q1", "s")):
            for mesh in sorted({r["mesh"] for r in rows if r["case"] == case}):
                sel = [r for r in rows if r["case"] == case and r["pair"] == pair
                       and r["mesh"] == mesh]
                if sel:
                    ax.loglog([r["wall_s"] for r in sel], [r["error"] for r in sel],
                              marker=mk, ls="-" if pair == "Q2Q1" else "--",
                              label=f"{pair} mesh {mesh}")
        tol = next(r["tolerance"] for r in rows if r["case"] == case)
        ax.axhline(tol, color="k", lw=0.8, ls=":")
        ax.set_xlabel("wall time (s)")
        ax.set_ylabel("relative error")
        ax.set_title(f"{case}: error vs wall time (lines: step counts)")
        ax.legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
