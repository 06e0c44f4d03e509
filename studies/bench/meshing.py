"""Meshing benchmark: the paper's five pile-surface sizes, counts, quality and times.

Not a test: ``python -m pilegroup.studies.bench.meshing [h ...] [--symmetry MODE ...]`` prints a
Markdown table next to the paper's Table 2 element counts (Li et al. 2019, ABAQUS C3D8), one
row per size and model part (``none``: the whole model, ``quarter``, ``half_x``, ``half_y``;
``auto``: the part the geometry's symmetry allows). Table 2 counts the whole model.
"""

from __future__ import annotations

import argparse
import dataclasses
import platform
import time
from collections.abc import Sequence
from typing import Any

from mpi4py import MPI

from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.spec import GeometrySpec, pier667_default
from pilegroup.geometry.symmetry import mode_of

__all__ = ["PAPER_TABLE2", "benchmark_mesh_sizes", "format_table"]

#: Paper Table 2: mesh size h (m) -> ABAQUS element count.
PAPER_TABLE2 = {1.0: 57108, 0.8: 63553, 0.6: 71141, 0.3: 105522, 0.1: 255221}


def benchmark_mesh_sizes(sizes: tuple[float, ...] = tuple(PAPER_TABLE2),
                         spec: GeometrySpec | None = None, convert: bool = True,
                         comm: MPI.Comm | None = None,
                         symmetry: Sequence[str] = ("none",)) -> list[dict[str, Any]]:
    """Mesh ``spec`` (default Pier 667) at each h (m) without the cache; one row per size.

    ``symmetry``: the model parts to mesh at every size (``"auto"``: the part of the planes
    the geometry is symmetric about). Row: h, symmetry, cells, vertices, plan quads, vertical
    divisions, min scaled Jacobian (gmsh "minSJ"), far-field algorithm and triangle pairs
    joined, gmsh time (geometry + meshing, s), quality time, DOLFINx conversion time (s).
    """
    if comm is None:
        comm = MPI.COMM_WORLD
    base = spec if spec is not None else pier667_default()
    rows = []
    for h in sizes:
        for mode in symmetry:
            part = mode_of(base.symmetry_planes()) if mode == "auto" else mode
            t0 = time.perf_counter()
            md = build_mesh(dataclasses.replace(base.with_h(h), symmetry=part), comm,
                            cache_dir=False)
            total = time.perf_counter() - t0
            i = md.info
            t = i["timings"]
            rows.append({
                "h": h, "symmetry": part, "cells": i["num_cells"],
                "vertices": i["num_vertices"], "plan_quads": i["n_plan_quads"],
                "n_circ": i["n_circ"], "nz": i["n_vertical_soil"] + i["n_vertical_cap"],
                "min_sj": i["min_sj"], "far_algorithm": i["far_field_algorithm"],
                "far_pairs": i["far_field_pairs"], "gmsh_s": t["geometry_s"] + t["mesh_s"],
                "quality_s": t["quality_s"], "convert_s": t["convert_s"], "total_s": total,
                "paper_cells": PAPER_TABLE2.get(h),
            })
            del md
    return rows


def format_table(rows: list[dict[str, Any]]) -> str:
    """Markdown table of :func:`benchmark_mesh_sizes` rows."""
    head = ("| h (m) | model | cells (hex) | vertices | plan quads | N around pile | element "
            "layers | min SJ | far field: gmsh algorithm, triangle pairs | gmsh mesh (s) "
            "| quality (s) | to DOLFINx (s) | paper Table 2 cells (whole) |\n"
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    lines = [head]
    for r in rows:
        paper = f"{r['paper_cells']:,}" if r["paper_cells"] else "-"
        lines.append(f"| {r['h']:g} | {r['symmetry']} | {r['cells']:,} | {r['vertices']:,} "
                     f"| {r['plan_quads']:,} | {r['n_circ']} | {r['nz']} | {r['min_sj']:.3f} "
                     f"| {r['far_algorithm']}, {r['far_pairs']} | {r['gmsh_s']:.2f} "
                     f"| {r['quality_s']:.2f} | {r['convert_s']:.2f} | {paper} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    """Command-line entry: optional sizes (m) and ``--symmetry`` parts (default ``none``)."""
    p = argparse.ArgumentParser(prog="python -m pilegroup.studies.bench.meshing")
    p.add_argument("sizes", type=float, nargs="*", metavar="H")
    p.add_argument("--symmetry", nargs="+", default=["none"],
                   choices=["auto", "none", "quarter", "half_x", "half_y"])
    args = p.parse_args(argv)
    rows = benchmark_mesh_sizes(tuple(args.sizes) or tuple(PAPER_TABLE2),
                                symmetry=args.symmetry)
    print(f"# meshing benchmark, Pier 667, {platform.node()} ({platform.machine()})")
    print(format_table(rows))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
