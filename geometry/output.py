"""Mesh outputs: XDMF (mesh + tags, opens in ParaView), PNG renders, and ``mesh_command``.

``mesh_command`` is what ``pilegroup mesh SCENARIO [--mesh-size H] [--out DIR]`` runs once the
scenario is turned into a :class:`~pilegroup.geometry.spec.GeometrySpec`.
"""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any

import gmsh
import numpy as np
import pyvista as pv
from dolfinx.io import XDMFFile
from mpi4py import MPI

from pilegroup.fileio import write_text_atomic
from pilegroup.geometry.convert import build_mesh, ensure_msh, gmsh_session
from pilegroup.geometry.groups import CAP_TAG, PILE_TAGS, shaft_of
from pilegroup.geometry.meshdata import MeshData
from pilegroup.geometry.spec import GeometrySpec

__all__ = ["format_summary", "hex_grid", "mesh_command", "render_png", "write_xdmf"]


def write_xdmf(md: MeshData, path: str | Path) -> Path:
    """Write the mesh, ``cell_tags`` and ``facet_tags`` to one XDMF/HDF5 pair (collective).

    The name -> tag tables go to ``<path>.tags.json`` (written by rank 0).
    """
    path = Path(path)
    mesh = md.mesh
    comm = mesh.comm
    if comm.rank == 0:
        path.parent.mkdir(parents=True, exist_ok=True)
    comm.barrier()
    tdim = mesh.topology.dim
    mesh.topology.create_connectivity(tdim - 1, tdim)
    md.cell_tags.name = "cell_tags"
    md.facet_tags.name = "facet_tags"
    with XDMFFile(comm, str(path), "w") as f:
        f.write_mesh(mesh)
        f.write_meshtags(md.cell_tags, mesh.geometry)
        f.write_meshtags(md.facet_tags, mesh.geometry)
    if comm.rank == 0:
        path.with_suffix(".tags.json").write_text(json.dumps(
            {"cell_tags": md.cell_names, "facet_tags": md.facet_names}, indent=1))
    return path


def hex_grid(points: np.ndarray, hexes: np.ndarray) -> pv.UnstructuredGrid:
    """A pyvista grid of linear hexahedra: ``points`` (n, 3) in m, ``hexes`` (m, 8) indices.

    Vertex order of each hexahedron as in VTK (gmsh's and DOLFINx's XDMF order are the same).
    """
    hexes = np.asarray(hexes, dtype=np.int64).reshape(-1, 8)
    cells = np.hstack([np.full((hexes.shape[0], 1), 8), hexes]).ravel()
    return pv.UnstructuredGrid(cells, np.full(hexes.shape[0], pv.CellType.HEXAHEDRON),
                               np.asarray(points, dtype=float).reshape(-1, 3))


def _grid_from_msh(msh: Path) -> pv.UnstructuredGrid:
    """A pyvista grid of the hexahedra in ``msh`` with cell data ``region`` (physical tag)."""
    with gmsh_session():
        gmsh.open(str(msh))
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        order = np.argsort(tags)
        xyz = xyz.reshape(-1, 3)[order]
        index = np.empty(int(tags.max()) + 1, dtype=np.int64)
        index[tags[order].astype(np.int64)] = np.arange(tags.size)
        conns, regions = [], []
        for dim, ptag in gmsh.model.getPhysicalGroups(3):
            for ent in gmsh.model.getEntitiesForPhysicalGroup(dim, ptag):
                _, etags, enodes = gmsh.model.mesh.getElements(3, ent)
                for et, en in zip(etags, enodes, strict=True):
                    conns.append(index[np.asarray(en, dtype=np.int64)].reshape(-1, 8))
                    regions.append(np.full(len(et), ptag))
        gmsh.model.remove()
    grid = hex_grid(xyz, np.concatenate(conns))
    grid.cell_data["region"] = np.concatenate(regions)
    return grid


def _region_colors(region: np.ndarray) -> np.ndarray:
    """Scalar for colouring: soil layers 1..n, piles and cap mapped to distinct values."""
    out = region.astype(float).copy()
    out[np.isin(region, PILE_TAGS)] = -5.0
    out[region == CAP_TAG] = -10.0
    return out


def render_png(msh: str | Path, spec: GeometrySpec, out_dir: str | Path) -> list[Path]:
    """Render ``plan.png`` (plan view near the piles) and ``cutaway.png`` (3D cut-away).

    The cut-away is cut at the first pile row, or shows the plane y = 0 of a model reduced by
    symmetry about it. Serial (call it on one rank); pyvista off screen, no display needed.
    """
    pv.OFF_SCREEN = True
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    grid = _grid_from_msh(Path(msh))
    grid.cell_data["colour"] = _region_colors(grid.cell_data["region"])
    x0, x1, y0, y1 = spec.structured_region()
    planes = spec.cut_planes()
    x0, y0 = (0.0 if "x" in planes else x0), (0.0 if "y" in planes else y0)
    pad = max(3.0, 0.3 * max(x1 - x0, y1 - y0))
    files = []

    # plan view: a horizontal cut just below the ground surface, zoomed on the piles
    z_cut = -0.5 * min(spec.sizing.dz_surface, 0.5 * (spec.layers[0].thickness or 1.0))
    cc = grid.cell_centers().points
    keep = np.flatnonzero((cc[:, 0] > x0 - pad) & (cc[:, 0] < x1 + pad) & (cc[:, 1] > y0 - pad)
                          & (cc[:, 1] < y1 + pad) & (cc[:, 2] > z_cut - 5) & (cc[:, 2] < 0))
    sl = grid.extract_cells(keep).slice(normal="z", origin=(0.0, 0.0, z_cut),
                                        generate_triangles=False)
    p = pv.Plotter(off_screen=True, window_size=(1400, 1100))
    p.add_mesh(sl, scalars="colour", show_edges=True, cmap="tab20", show_scalar_bar=False)
    p.view_xy()
    p.add_text(f"plan at z = {z_cut:g} m, h = {spec.sizing.h_pile:g} m", font_size=12)
    f = out / "plan.png"
    p.screenshot(str(f))
    p.close()
    files.append(f)

    # 3D cut-away: the upper part of the pile group cut by the plane y = first pile row
    zb = -min(spec.block.depth, max(20.0, 0.35 * max(p_.length_in_soil for p_ in spec.piles)))
    zt = spec.cap.thickness if spec.cap is not None else 0.0
    w = 2.5 * pad
    if "y" in planes:  # the model's side y = 0 is the cut, seen from y < 0
        y_cut, look, y_range = 0.0, -1.0, (0.0, y1 + w)
    else:
        y_cut, look = min(p_.y for p_ in spec.piles), 1.0
        y_range = (y0 - w, y_cut)
    box = grid.clip_box((x0 - w, x1 + w, *y_range, zb, zt + 1), invert=False)
    p = pv.Plotter(off_screen=True, window_size=(1400, 1100))
    p.add_mesh(box, scalars="colour", show_edges=True, cmap="tab20", show_scalar_bar=False,
               edge_color="#333333", line_width=0.5)
    cx, cz = 0.5 * (x0 + x1), 0.5 * (zb + zt)
    dist = 1.6 * max(x1 - x0 + 2 * w, zt - zb)
    p.camera_position = [(cx + 0.45 * dist, y_cut + look * dist, cz + 0.55 * dist),
                         (cx, y_cut - look * 0.3 * w, cz), (0.0, 0.0, 1.0)]
    p.add_text(f"cut-away at y = {y_cut:g} m, z >= {zb:g} m, h = {spec.sizing.h_pile:g} m",
               font_size=12)
    f = out / "cutaway.png"
    p.screenshot(str(f))
    p.close()
    files.append(f)
    return files


def mesh_command(spec: GeometrySpec, h: float | None, out_dir: str | Path, comm: MPI.Comm,
                 cache_dir: str | Path | None = None, render: bool = True) -> dict[str, Any]:
    """Mesh ``spec`` (with ``h`` in m if given), write XDMF + PNG to ``out_dir``, return a summary.

    Collective over ``comm``; see :func:`mesh_outputs` for the files and the summary.
    """
    if h is not None:
        spec = spec.with_h(h)
    t0 = time.perf_counter()
    md = build_mesh(spec, comm, cache_dir=cache_dir)
    return mesh_outputs(md, spec, out_dir, render, t0)


def mesh_outputs(md: MeshData, spec: GeometrySpec, out_dir: str | Path, render: bool = True,
                 t0: float | None = None) -> dict[str, Any]:
    """Write the outputs of the built mesh ``md`` of ``spec`` to ``out_dir``; return a summary.

    Collective over ``md.mesh.comm``. Files: ``mesh.xdmf``/``.h5`` (mesh, ``cell_tags``,
    ``facet_tags``), ``mesh.tags.json`` (names), ``mesh_summary.json``, ``plan.png``,
    ``cutaway.png``. The summary holds global cell / vertex counts, the minimum scaled
    Jacobian, the number of groups and the timings (s; ``command_s`` from ``t0``).
    """
    comm = md.mesh.comm
    t0 = time.perf_counter() if t0 is None else t0
    out = Path(out_dir)
    xdmf = write_xdmf(md, out / "mesh.xdmf")
    info = md.info
    summary: dict[str, Any] = {
        "h_m": spec.sizing.h_pile,
        "symmetry": spec.symmetry,
        "piles_meshed": list(spec.kept_piles()),
        "cells": info["num_cells"],
        "vertices": info["num_vertices"],
        "hexahedra_gmsh": info["n_hex"],
        "min_scaled_jacobian": info["min_sj"],
        "plan_quads": info["n_plan_quads"],
        "circumferential_divisions": info["n_circ"],
        "vertical_divisions_soil": info["n_vertical_soil"],
        "vertical_divisions_cap": info["n_vertical_cap"],
        "cell_groups": len(md.cell_names),
        "facet_groups": len(md.facet_names),
        "shaft_groups": sum(1 for n in md.facet_names if shaft_of(n) is not None),
        "cache_hit": info["cache_hit"],
        "cache_key": info["cache_key"] if "cache_key" in info else None,
        "timings_s": info["timings"],
        "files": {"xdmf": str(xdmf)},
        "ranks": comm.size,
    }
    if comm.rank == 0:
        if render:
            msh = Path(info["msh_path"]) if "msh_path" in info else ensure_msh(spec)[0]
            t1 = time.perf_counter()
            pngs = render_png(msh, spec, out)
            summary["timings_s"]["render_s"] = time.perf_counter() - t1
            summary["files"]["png"] = [str(f) for f in pngs]
        summary["timings_s"]["command_s"] = time.perf_counter() - t0
        write_text_atomic(out / "mesh_summary.json", json.dumps(summary, indent=1))
    return comm.bcast(summary, root=0)


def format_summary(s: dict[str, Any]) -> str:
    """Human-readable lines of a :func:`mesh_command` summary."""
    t = s["timings_s"]
    part = ("" if s.get("symmetry", "none") == "none" else
            f"{s['symmetry']} model (piles {', '.join(map(str, s['piles_meshed']))}): ")
    return "\n".join([
        f"{part}h = {s['h_m']:g} m: {s['cells']:,} hexahedra, {s['vertices']:,} vertices "
        f"(plan {s['plan_quads']:,} quads x {s['vertical_divisions_soil']} soil layers of "
        f"elements + cap {s['vertical_divisions_cap']})",
        f"min scaled Jacobian {s['min_scaled_jacobian']:.3f}; {s['cell_groups']} cell groups, "
        f"{s['facet_groups']} facet groups ({s['shaft_groups']} shaft)",
        f"mesh {t.get('mesh_s', 0):.2f} s, convert {t.get('convert_s', 0):.2f} s, "
        f"cache {'hit' if s['cache_hit'] else 'miss'}",
        *(f"wrote {v}" for v in [s["files"]["xdmf"], *s["files"].get("png", [])]),
    ])
