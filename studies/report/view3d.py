"""One 3D view of a run's results at its last output time: ``plots/view3d.png``.

Input is the run's own XDMF/HDF5 output (:class:`~pilegroup.solver.exports.XDMFSeries`), read
with ``xml.etree`` and h5py (pyvista's XDMF reader crashes on DOLFINx's XDMF 3 files):

* separate pile and soil fields (``elastic`` / ``viscoplastic`` interface): ``results.xdmf``
  (soil, ``displacement_soil``) and ``results_structure.xdmf`` (piles and cap,
  ``displacement_structure``);
* tied piles: ``results.xdmf`` (whole mesh, ``displacement``) and ``results_pressure.xdmf``
  (the soil sub-mesh; its cells tell the soil from the piles and cap).

A symmetry-reduced model (its grid named ``..._reflect_about_x0_and_y0``) is mirrored about the
named planes first, so the view shows the whole foundation.

The time drawn is the last output time held by every file needed, so an interrupted run is
drawn at its last complete output. The picture: the undeformed soil near the pile group with
the quarter facing the camera cut away (corner on the group's vertical centre line), and the
piles and cap whole, all coloured on one scale by the settlement ``-u_z`` in mm (positive
down). Serial: call it on one rank.
"""

from __future__ import annotations

import dataclasses
import logging
import xml.etree.ElementTree as ET
from pathlib import Path

import h5py
import numpy as np
import pyvista as pv

from pilegroup.fileio import atomic_path
from pilegroup.geometry.output import hex_grid

log = logging.getLogger(__name__)

#: File name in the ``plots`` folder and picture size (pixels, width x height).
FILE = "view3d.png"
WINDOW = (1400, 1100)
SCALAR = "settlement_mm"
SCALAR_TITLE = "settlement (mm, + down)"


class ViewDataError(Exception):
    """The output files needed for the 3D view are missing or hold no common output time."""


@dataclasses.dataclass(frozen=True)
class ViewData:
    """The fields drawn: pyvista grids with point data ``settlement_mm`` (mm, down positive).

    ``structure`` (piles and cap) is ``None`` when the output does not separate them.
    """

    t_day: float
    soil: pv.UnstructuredGrid
    structure: pv.UnstructuredGrid | None


def _xdmf(path: Path) -> tuple[str, str, dict[str, dict[float, str]]]:
    """The mesh's geometry and topology references and every time series of an XDMF file.

    References are ``"file.h5:/dataset"`` strings; series map a field name to ``{t: ref}``.
    """
    if not path.is_file():
        raise ViewDataError(f"no {path.name}")
    domain = ET.parse(path).getroot().find("Domain")
    mesh = None if domain is None else domain.find("Grid[@GridType='Uniform']")
    if mesh is None:
        raise ViewDataError(f"{path.name} holds no mesh")
    geometry = mesh.findtext("Geometry/DataItem", "").strip()
    topology = mesh.findtext("Topology/DataItem", "").strip()
    series: dict[str, dict[float, str]] = {}
    for coll in domain.findall("Grid[@CollectionType='Temporal']"):
        for g in coll.findall("Grid"):
            t, ref = g.find("Time"), g.findtext("Attribute/DataItem", "").strip()
            if t is not None and ref:
                series.setdefault(coll.get("Name", ""), {})[float(t.get("Value", "nan"))] = ref
    return geometry, topology, series


def _h5(xdmf: Path, ref: str) -> np.ndarray:
    """The array of an XDMF ``"file.h5:/dataset"`` reference (file relative to the XDMF)."""
    fname, _, dataset = ref.rpartition(":")
    with h5py.File(xdmf.parent / fname, "r") as f:
        return np.asarray(f[dataset][...])


def _displacement(series: dict[str, dict[float, str]], path: Path
                  ) -> tuple[str, dict[float, str]]:
    """The first displacement series of an XDMF file: its name and ``{t: ref}``."""
    names = [n for n in series if n.startswith("displacement")]
    if not names:
        raise ViewDataError(f"{path.name} holds no displacement")
    return names[0], series[names[0]]


def _grid(path: Path, geometry: str, topology: str, u_ref: str | None
          ) -> pv.UnstructuredGrid:
    """Hexahedral grid of one XDMF mesh, with ``settlement_mm`` from ``u_ref`` if given."""
    grid = hex_grid(_h5(path, geometry), _h5(path, topology))
    if u_ref is not None:
        u = _h5(path, u_ref).reshape(grid.n_points, 3)
        grid.point_data[SCALAR] = -1000.0 * u[:, 2]
    return grid


def _centres(grid: pv.UnstructuredGrid) -> np.ndarray:
    """Cell centres (vertex means) of a hexahedral grid, m."""
    return grid.points[grid.cell_connectivity.reshape(-1, 8)].mean(axis=1)


def _rows_in(a: np.ndarray, b: np.ndarray, tol: float = 1e-6) -> np.ndarray:
    """Mask of the rows of ``a`` that are rows of ``b`` (equal to ``tol``, same units)."""
    keys = np.round(np.vstack([a, b]) / tol).astype(np.int64)
    _, inv = np.unique(keys, axis=0, return_inverse=True)
    inv = inv.ravel()
    return np.isin(inv[: len(a)], inv[len(a):])


def load_view_data(out_dir: Path) -> ViewData:
    """Soil and pile/cap settlement at the last output time common to the files needed.

    Raises :class:`ViewDataError` (or ``OSError`` / ``KeyError`` / ``ValueError`` /
    ``ET.ParseError`` for an unreadable file) if the view cannot be drawn.
    """
    out_dir = Path(out_dir)
    main = out_dir / "results.xdmf"
    normals = _mirror_normals(main)
    geo, top, series = _xdmf(main)
    name, u_soil = _displacement(series, main)
    if name == "displacement":  # tied piles: one field on the whole mesh
        t = max(u_soil, default=None)
        if t is None:
            raise ViewDataError(f"{main.name} holds no output time")
        whole = _grid(main, geo, top, u_soil[t])
        pressure = out_dir / "results_pressure.xdmf"
        if not pressure.is_file():
            log.info("no %s: piles and cap not told from the soil", pressure.name)
            return ViewData(t, _mirrored(whole, normals), None)
        pgeo, ptop, _ = _xdmf(pressure)
        soil_centres = _centres(_grid(pressure, pgeo, ptop, None))
        is_soil = _rows_in(_centres(whole), soil_centres)
        if is_soil.sum() != len(soil_centres):
            raise ViewDataError(f"the cells of {pressure.name} are not cells of {main.name}")
        return ViewData(t, _mirrored(whole.extract_cells(np.flatnonzero(is_soil)), normals),
                        _mirrored(whole.extract_cells(np.flatnonzero(~is_soil)), normals))
    structure = out_dir / "results_structure.xdmf"
    sgeo, stop, sseries = _xdmf(structure)
    _, u_struct = _displacement(sseries, structure)
    t = max(set(u_soil) & set(u_struct), default=None)
    if t is None:
        raise ViewDataError(f"{main.name} and {structure.name} share no output time")
    return ViewData(t, _mirrored(_grid(main, geo, top, u_soil[t]), normals),
                    _mirrored(_grid(structure, sgeo, stop, u_struct[t]), normals))


def _mirror_normals(xdmf: Path) -> list[tuple[float, float, float]]:
    """Normals of the mirror planes named by a reduced model's grid (none for the full model).

    ``..._reflect_about_x0_and_y0`` names the planes x = 0 and y = 0.
    """
    grid = ET.parse(xdmf).getroot().find(".//Grid[@Name]")
    name = grid.get("Name", "") if grid is not None else ""
    _, _, planes = name.partition("_reflect_about_")
    return [n for tag, n in (("x0", (1.0, 0.0, 0.0)), ("y0", (0.0, 1.0, 0.0)))
            if tag in planes.split("_and_")]


def _mirrored(grid: pv.UnstructuredGrid, normals: list[tuple[float, float, float]]
              ) -> pv.UnstructuredGrid:
    """``grid`` and its mirror images about the planes through the origin with ``normals``."""
    for n in normals:
        axis = int(np.argmax(n))
        points = np.array(grid.points, copy=True)
        points[:, axis] *= -1.0
        # a mirror image turns the hexahedra inside out: swap their bottom and top faces
        hexes = grid.cell_connectivity.reshape(-1, 8)[:, [4, 5, 6, 7, 0, 1, 2, 3]]
        image = hex_grid(points, hexes)
        for key in grid.point_data:
            image.point_data[key] = np.asarray(grid.point_data[key])
        grid = grid.merge(image)
    return grid


def render_view3d(data: ViewData, path: Path, title: str) -> Path:
    """Draw ``data`` off screen to the PNG ``path`` (``WINDOW`` pixels, written atomically).

    The soil is clipped to the pile group's plan extent plus half the pile length on every
    side and to 1.25 pile lengths below the ground surface (all of it without piles); the
    quarter ``x > xc, y < yc`` (``xc, yc``: the group's plan centre) is cut away and the camera
    looks into it from above. Piles and cap are drawn whole, with their mesh edges. Colours:
    settlement in mm, down positive, one scale for all; the black box outlines the soil shown.
    """
    pv.OFF_SCREEN = True
    soil, struct = data.soil, data.structure
    x0, x1, y0, y1, z0, ground = soil.bounds
    xc, yc = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
    if struct is not None:
        x0, x1, y0, y1, zt, _ = struct.bounds
        length = ground - zt
        a = 0.5 * max(x1 - x0, y1 - y0) + 0.5 * length
        xc, yc = 0.5 * (x0 + x1), 0.5 * (y0 + y1)
        x0, x1, y0, y1 = xc - a, xc + a, yc - a, yc + a
        z0 = max(z0, ground - 1.25 * length)
        soil = soil.clip_box((x0, x1, y0, y1, z0, ground), invert=False)
    pad = 1.0 + (x1 - x0)
    cut = soil.clip_box((xc, x1 + pad, y0 - pad, yc, z0 - pad, ground + pad), invert=True)
    parts = [cut] + ([struct] if struct is not None else [])
    values = np.concatenate([np.asarray(m.point_data[SCALAR]) for m in parts])
    clim = (float(values.min()), float(values.max()))
    if clim[1] - clim[0] < 1e-9:
        clim = (clim[0] - 0.5, clim[1] + 0.5)

    p = pv.Plotter(off_screen=True, window_size=list(WINDOW))
    p.set_background("white")
    bar = {"title": SCALAR_TITLE, "vertical": False, "fmt": "%.1f", "color": "black",
           "position_x": 0.3, "position_y": 0.06, "width": 0.4, "height": 0.06,
           "title_font_size": 18, "label_font_size": 16}
    look = {"scalars": SCALAR, "clim": clim, "cmap": "viridis", "ambient": 0.35, "diffuse": 0.7}
    p.add_mesh(cut, scalar_bar_args=bar, **look)
    p.add_mesh(soil.outline(), color="black", line_width=1.0)
    notes = [f"max settlement: soil {float(data.soil.point_data[SCALAR].max()):.1f} mm"]
    if struct is not None:
        p.add_mesh(struct, show_edges=True, edge_color="#222222", line_width=0.6,
                   show_scalar_bar=False, **look)
        notes.append(f"piles/cap {float(struct.point_data[SCALAR].max()):.1f} mm")
    p.add_text(title, position="upper_edge", font_size=14, color="black")
    p.add_text("undeformed mesh; soil near the piles, one quarter cut away\n"
               + ", ".join(notes), position="lower_right", font_size=10, color="black")
    p.add_axes(color="black")
    p.view_vector((1.0, -1.3, 0.8), viewup=(0.0, 0.0, 1.0))
    p.reset_camera()
    try:
        with atomic_path(path) as tmp:
            p.screenshot(str(tmp))
    finally:
        p.close()
    return path


def write_view3d(out_dir: Path, name: str | None = None) -> Path | None:
    """Write ``out_dir/plots/view3d.png`` of the run in ``out_dir``; ``None`` if it cannot.

    Missing, partial or unreadable output files skip the view with a logged message. ``name``
    (the scenario) goes in the title, default the folder name.
    """
    out_dir = Path(out_dir)
    try:
        data = load_view_data(out_dir)
    except (ViewDataError, OSError, KeyError, ValueError, ET.ParseError) as exc:
        log.info("skipping %s: %s", FILE, exc)
        return None
    title = f"{name or out_dir.name}: settlement at t = {data.t_day:g} day (last output)"
    return render_view3d(data, out_dir / "plots" / FILE, title)
