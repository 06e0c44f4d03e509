"""Meshing benchmark: the paper's five pile-surface sizes, counts, quality and times.

Not a test: ``python -m pilegroup.geometry.bench [h ...]`` prints a Markdown table next to the
paper's Table 2 element counts (Li et al. 2019, ABAQUS C3D8).
"""

from __future__ import annotations

import platform
import sys
import time
from typing import Any

from mpi4py import MPI

from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.spec import GeometrySpec, pier667_default

__all__ = ["PAPER_TABLE2", "benchmark_mesh_sizes", "format_table"]

#: Paper Table 2: mesh size h (m) -> ABAQUS element count.
PAPER_TABLE2 = {1.0: 57108, 0.8: 63553, 0.6: 71141, 0.3: 105522, 0.1: 255221}


def benchmark_mesh_sizes(sizes: tuple[float, ...] = tuple(PAPER_TABLE2),
                         spec: GeometrySpec | None = None, convert: bool = True,
                         comm: MPI.Comm | None = None) -> list[dict[str, Any]]:
    """Mesh ``spec`` (default Pier 667) at each h (m) without the cache; one row per size.

    Row: h, cells, vertices, plan quads, vertical divisions, min scaled Jacobian (gmsh
    "minSJ"), gmsh time (geometry + meshing, s), quality time, DOLFINx conversion time (s).
    """
    if comm is None:
        comm = MPI.COMM_WORLD
    base = spec if spec is not None else pier667_default()
    rows = []
    for h in sizes:
        t0 = time.perf_counter()
        md = build_mesh(base.with_h(h), comm, cache_dir=False)
        total = time.perf_counter() - t0
        i = md.info
        t = i["timings"]
        rows.append({
            "h": h, "cells": i["num_cells"], "vertices": i["num_vertices"],
            "plan_quads": i["n_plan_quads"], "n_circ": i["n_circ"],
            "nz": i["n_vertical_soil"] + i["n_vertical_cap"], "min_sj": i["min_sj"],
            "gmsh_s": t["geometry_s"] + t["mesh_s"], "quality_s": t["quality_s"],
            "convert_s": t["convert_s"], "total_s": total,
            "paper_cells": PAPER_TABLE2.get(h),
        })
        del md
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    """Markdown table of :func:`benchmark_mesh_sizes` rows."""
    head = ("| h (m) | cells (hex) | vertices | plan quads | N around pile | element layers "
            "| min SJ | gmsh mesh (s) | quality (s) | to DOLFINx (s) | paper Table 2 cells |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        paper = f"{r['paper_cells']:,}" if r["paper_cells"] else "-"
        lines.append(f"| {r['h']:g} | {r['cells']:,} | {r['vertices']:,} | {r['plan_quads']:,} "
                     f"| {r['n_circ']} | {r['nz']} | {r['min_sj']:.3f} | {r['gmsh_s']:.2f} "
                     f"| {r['quality_s']:.2f} | {r['convert_s']:.2f} | {paper} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: optional sizes (m)."""
    args = sys.argv[1:] if argv is None else argv
    sizes = tuple(float(a) for a in args) if args else tuple(PAPER_TABLE2)
    rows = benchmark_mesh_sizes(sizes)
    print(f"# meshing benchmark, Pier 667, {platform.node()} ({platform.machine()})")
    print(format_table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
