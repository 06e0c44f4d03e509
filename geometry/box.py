"""Structured hexahedral boxes and columns for the verification cases.

The box spans ``[x0, x1] x [y0, y1] x [z_bottom, z_top]`` (m); z is vertical, upward. The cells
are hexahedra from ``dolfinx.mesh.create_box``; the vertical node levels may be graded (finer
towards the top, where the drained boundary creates a pressure boundary layer) and the soil may
be split into horizontal layers, each a cell group ``soil_layer_01`` (top) ... ``soil_layer_NN``
(bottom). Facet groups: ``side_xmin``, ``side_xmax``, ``side_ymin``, ``side_ymax``, ``bottom``
and ``ground_surface`` (the top). Ghost mode is ``shared_facet``.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence

import dolfinx.mesh as dmesh
import numpy as np
from mpi4py import MPI

from pilegroup.geometry.groups import (
    BOTTOM,
    FACET_TAGS,
    GROUND,
    SIDES,
    soil_layer,
    soil_layer_tag,
)
from pilegroup.geometry.meshdata import MeshData

__all__ = ["build_box", "graded_levels"]

#: The facet groups of a box: its sides, bottom and top (tags of :mod:`~.groups`).
FACET_NAMES = {name: FACET_TAGS[name] for name in (*SIDES, BOTTOM, GROUND)}


def graded_levels(z_bottom: float, z_top: float, n: int, ratio: float = 1.0) -> np.ndarray:
    """Node elevations (m, ascending) of ``n`` cells between ``z_bottom`` and ``z_top``.

    ``ratio`` is the size of the bottom cell over the size of the top cell (geometric growth
    downwards); ``ratio = 1`` gives uniform cells, ``ratio > 1`` refines towards the top.
    """
    if n < 1:
        raise ValueError(f"n = {n} cells; allowed: n >= 1")
    if not z_top > z_bottom:
        raise ValueError(f"z_top = {z_top} m must exceed z_bottom = {z_bottom} m")
    if not ratio > 0:
        raise ValueError(f"ratio = {ratio}; allowed: > 0")
    if n == 1 or abs(ratio - 1.0) < 1e-14:
        return np.linspace(z_bottom, z_top, n + 1)
    q = ratio ** (1.0 / (n - 1))  # growth per cell, top to bottom
    sizes = q ** np.arange(n)  # top cell first
    sizes *= (z_top - z_bottom) / sizes.sum()
    depth = np.concatenate([[0.0], np.cumsum(sizes)])
    z = z_top - depth
    z[-1] = z_bottom
    return z[::-1].copy()


def _graded_box(comm: MPI.Comm, x: tuple[float, float], y: tuple[float, float],
                zl: np.ndarray, nx: int, ny: int) -> dmesh.Mesh:
    """Hexahedral box on ``comm`` with its node levels moved to the elevations ``zl``."""
    nz = zl.size - 1
    msh = dmesh.create_box(
        comm,
        [np.array([x[0], y[0], 0.0]), np.array([x[1], y[1], float(nz)])],
        [nx, ny, nz],
        cell_type=dmesh.CellType.hexahedron,
        ghost_mode=dmesh.GhostMode.shared_facet,
    )
    gx = msh.geometry.x
    gx[:, 2] = np.interp(gx[:, 2], np.arange(nz + 1, dtype=float), zl)
    return msh


def _facet_tags(msh: dmesh.Mesh, x: tuple[float, float], y: tuple[float, float], zb: float,
                zt: float) -> dmesh.MeshTags:
    """Tags of the boundary facets: :data:`FACET_NAMES` by position."""
    fdim = msh.topology.dim - 1
    msh.topology.create_connectivity(fdim, fdim + 1)
    tol = 1e-8 * max(x[1] - x[0], y[1] - y[0], zt - zb)
    at: dict[str, Callable[[np.ndarray], np.ndarray]] = {
        SIDES[0]: lambda p: np.isclose(p[0], x[0], atol=tol),
        SIDES[1]: lambda p: np.isclose(p[0], x[1], atol=tol),
        SIDES[2]: lambda p: np.isclose(p[1], y[0], atol=tol),
        SIDES[3]: lambda p: np.isclose(p[1], y[1], atol=tol),
        BOTTOM: lambda p: np.isclose(p[2], zb, atol=tol),
        GROUND: lambda p: np.isclose(p[2], zt, atol=tol),
    }
    f_idx, f_val = [], []
    for name, marker in at.items():
        facets = dmesh.locate_entities_boundary(msh, fdim, marker)
        f_idx.append(facets)
        f_val.append(np.full(facets.size, FACET_NAMES[name], dtype=np.int32))
    f_idx_a = np.concatenate(f_idx).astype(np.int32)
    f_val_a = np.concatenate(f_val)
    order = np.argsort(f_idx_a, kind="stable")
    # edge facets belong to two groups only in degenerate boxes (never: facets are planar)
    return dmesh.meshtags(msh, fdim, f_idx_a[order], f_val_a[order])


def _layer_tags(msh: dmesh.Mesh, tops: list[float]) -> tuple[dmesh.MeshTags, dict[str, int]]:
    """Cell tags of the soil layers (by cell-centre elevation, numbered from the top) and names.

    ``tops``: the internal layer boundaries (m), descending.
    """
    tdim = msh.topology.dim
    imap = msh.topology.index_map(tdim)
    ncells = imap.size_local + imap.num_ghosts
    cells = np.arange(ncells, dtype=np.int32)
    zc = dmesh.compute_midpoints(msh, tdim, cells)[:, 2]
    layer = np.full(ncells, soil_layer_tag(1), dtype=np.int32)
    for t in tops:
        layer += (zc < t).astype(np.int32)
    names = {soil_layer(j): soil_layer_tag(j) for j in range(1, len(tops) + 2)}
    return dmesh.meshtags(msh, tdim, cells, layer), names


def build_box(
    comm: MPI.Comm,
    x: tuple[float, float],
    y: tuple[float, float],
    z_levels: Sequence[float] | np.ndarray,
    nx: int,
    ny: int,
    layer_tops: Sequence[float] | None = None,
) -> MeshData:
    """Build a structured hexahedral box with optional vertical grading and soil layers.

    Args:
        comm: communicator the mesh is distributed on.
        x: ``(x0, x1)`` extent in m.
        y: ``(y0, y1)`` extent in m.
        z_levels: ascending node elevations in m (``len = nz + 1``); see :func:`graded_levels`.
        nx: cells along x.
        ny: cells along y.
        layer_tops: elevations (m) of the tops of layers 2, 3, ... (internal layer boundaries),
            in any order; a cell belongs to the layer containing its centre. ``None`` gives one
            group ``soil_layer_01``.

    Returns:
        :class:`MeshData` with cell groups ``soil_layer_NN`` (numbered from the top) and the
        facet groups of the module docstring.
    """
    t0 = time.perf_counter()
    zl = np.asarray(z_levels, dtype=float)
    if zl.ndim != 1 or zl.size < 2 or np.any(np.diff(zl) <= 0):
        raise ValueError("z_levels must be a strictly ascending 1D array of >= 2 elevations (m)")
    msh = _graded_box(comm, x, y, zl, nx, ny)
    zb, zt = float(zl[0]), float(zl[-1])
    facet_tags = _facet_tags(msh, x, y, zb, zt)
    tops = sorted({float(t) for t in (layer_tops or []) if zb < float(t) < zt}, reverse=True)
    cell_tags, cell_names = _layer_tags(msh, tops)
    info = {
        "builder": "geometry.box.build_box",
        "x": list(x),
        "y": list(y),
        "z_bottom": zb,
        "z_top": zt,
        "cells": [nx, ny, zl.size - 1],
        "num_cells_global": int(msh.topology.index_map(msh.topology.dim).size_global),
        "layer_tops": tops,
        "seconds": time.perf_counter() - t0,
    }
    return MeshData(msh, cell_tags, facet_tags, cell_names, dict(FACET_NAMES), info)
