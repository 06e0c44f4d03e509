"""The gmsh builders end to end: tags, volumes, areas, conformity, quality, cache, MPI.

References are exact where the geometry makes them exact: a pile cross-section is the regular
N-gon with its circle's area (N = circumferential divisions), every facet is a planar quad and
every cell a straight prism, so volumes and areas must match to round-off (1e-9 relative). The
1 % bounds against the true circle are checked as well.
"""

import importlib.util
import json
import math
import subprocess
import sys
from pathlib import Path

import dolfinx
import numpy as np
import pytest
from dolfinx.io import XDMFFile
from dolfinx.mesh import CellType, exterior_facet_indices
from mpi4py import MPI

from pilegroup.geometry import groups
from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.output import mesh_command
from pilegroup.geometry.plan import polygon_radius
from pilegroup.geometry.spec import pier667_default, single_pile

_HERE = Path(__file__).parent
_spec = importlib.util.spec_from_file_location("meshcheck", _HERE / "meshcheck.py")
mc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mc)

REL = 1e-9
PAPER_SIZES = (1.0, 0.8, 0.6, 0.3, 0.1)


def poly_area(n, r):
    """The meshed n-gon's area: the circle's (its corners on ``polygon_radius``)."""
    big = polygon_radius(r, n)
    return 0.5 * n * big * big * math.sin(2 * math.pi / n)


def poly_perimeter(n, r):
    return 2 * n * polygon_radius(r, n) * math.sin(math.pi / n)


def overlap(a0, a1, b0, b1):
    return max(0.0, min(a1, b1) - max(a0, b0))


@pytest.fixture(scope="module")
def cache(tmp_path_factory):
    return tmp_path_factory.mktemp("meshcache")


@pytest.fixture(scope="module", params=["single", "pier"])
def case(request, cache):
    spec = single_pile(h=0.5) if request.param == "single" else pier667_default(1.0)
    md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=cache)
    return spec, md, mc.group_measures(md)


def test_every_cell_has_exactly_one_tag(case):
    _, md, meas = case
    imap = md.mesh.topology.index_map(3)
    n_local = imap.size_local + imap.num_ghosts
    idx = md.cell_tags.indices
    assert idx.size == n_local and np.unique(idx).size == n_local
    assert set(np.unique(md.cell_tags.values)) == set(md.cell_names.values())
    assert sum(c for c, _ in meas["cells"].values()) == meas["num_cells"]


def test_only_hexahedra_and_scaled_jacobian(case):
    _, md, _ = case
    assert md.mesh.topology.cell_type == CellType.hexahedron
    assert md.info["n_hex"] == md.info["num_cells"]
    sj = mc.min_scaled_jacobian(mc.cell_coords(md.mesh))
    assert sj.min() > 0.2
    assert md.info["min_sj"] > 0.2


def test_volumes(case):
    spec, md, meas = case
    n = md.info["n_circ"]
    b = spec.block
    a_block = b.size_x * b.size_y
    vol_cap = 0.0
    if spec.cap is not None:
        c = spec.cap
        a_cap = (c.x_max - c.x_min) * (c.y_max - c.y_min)
        vol_cap = a_cap * c.thickness
    total = a_block * b.depth + vol_cap
    assert meas["total_volume"] == pytest.approx(total, rel=REL)
    assert sum(v for _, v in meas["cells"].values()) == pytest.approx(total, rel=REL)
    errs = []
    for i, p in enumerate(spec.piles, start=1):
        length = p.length_in_soil + p.embedment
        v = meas["cells"][groups.pile(i)][1]
        assert v == pytest.approx(poly_area(n, p.radius) * length, rel=REL)
        exact = math.pi * p.diameter**2 / 4 * length
        errs.append(abs(v - exact) / exact)
    assert max(errs) < 0.01
    tops = (0.0, *spec.layer_bottoms()[:-1])
    for j, (zt, zb) in enumerate(zip(tops, spec.layer_bottoms(), strict=True), start=1):
        piles = sum(poly_area(n, p.radius) * overlap(-p.length_in_soil, 0.0, zb, zt)
                    for p in spec.piles)
        expect = a_block * (zt - zb) - piles
        assert meas["cells"][groups.soil_layer(j)][1] == pytest.approx(expect, rel=REL)
    if spec.cap is not None:
        expect = vol_cap - sum(poly_area(n, p.radius) * p.embedment for p in spec.piles)
        assert meas["cells"][groups.CAP][1] == pytest.approx(expect, rel=REL)


def test_shaft_and_boundary_areas(case):
    spec, md, meas = case
    n = md.info["n_circ"]
    b = spec.block
    f = meas["facets"]
    tops = (0.0, *spec.layer_bottoms()[:-1])
    expected_shafts = set()
    for i, p in enumerate(spec.piles, start=1):
        for j, (zt, zb) in enumerate(zip(tops, spec.layer_bottoms(), strict=True), start=1):
            li = overlap(-p.length_in_soil, 0.0, zb, zt)
            if li == 0.0:
                continue
            name = groups.shaft(i, j)
            expected_shafts.add(name)
            assert f[name][1] == pytest.approx(poly_perimeter(n, p.radius) * li, rel=REL)
            assert abs(f[name][1] / (math.pi * p.diameter * li) - 1) < 0.01
        assert f[groups.base(i)][1] == pytest.approx(poly_area(n, p.radius), rel=REL)
    assert {k for k in f if groups.shaft_of(k)} == expected_shafts
    xmin, xmax, ymin, ymax = groups.SIDES
    assert f[xmin][1] == pytest.approx(b.size_y * b.depth, rel=REL)
    assert f[xmax][1] == pytest.approx(b.size_y * b.depth, rel=REL)
    assert f[ymin][1] == pytest.approx(b.size_x * b.depth, rel=REL)
    assert f[ymax][1] == pytest.approx(b.size_x * b.depth, rel=REL)
    assert f[groups.BOTTOM][1] == pytest.approx(b.size_x * b.size_y, rel=REL)
    a_piles = sum(poly_area(n, p.radius) for p in spec.piles)
    if spec.cap is None:
        assert f[groups.GROUND][1] == pytest.approx(b.size_x * b.size_y - a_piles, rel=REL)
    else:
        c = spec.cap
        a_cap = (c.x_max - c.x_min) * (c.y_max - c.y_min)
        assert f[groups.GROUND][1] == pytest.approx(b.size_x * b.size_y - a_cap, rel=REL)
        assert f[groups.CAP_BOTTOM][1] == pytest.approx(a_cap - a_piles, rel=REL)
        assert f[groups.CAP_TOP][1] == pytest.approx(a_cap, rel=REL)
        per = 2 * (c.x_max - c.x_min + c.y_max - c.y_min)
        assert f[groups.CAP_SIDE][1] == pytest.approx(per * c.thickness, rel=REL)


def _facet_cells(md):
    mesh = md.mesh
    mesh.topology.create_connectivity(2, 3)
    f2c = mesh.topology.connectivity(2, 3)
    counts = np.diff(f2c.offsets)
    return f2c, counts


def test_conforming_and_boundary_is_the_outer_surface(case):
    """No hanging nodes: each facet has <= 2 cells and the exterior facets are exactly the
    tagged outer-boundary facets whose area is the outer surface of block + cap."""
    spec, md, meas = case
    mesh = md.mesh
    _, counts = _facet_cells(md)
    assert counts.max() <= 2
    ext = mc.owned_facets(mesh, exterior_facet_indices(mesh.topology))
    boundary_groups = {*groups.SIDES, groups.BOTTOM, groups.GROUND, groups.CAP_TOP,
                       groups.CAP_SIDE, *groups.heads(md.facet_names)}
    tags = [md.facet_names[k] for k in boundary_groups if k in md.facet_names]
    ft = md.facet_tags
    tagged = mc.owned_facets(mesh, ft.indices[np.isin(ft.values, tags)])
    assert np.array_equal(np.sort(ext), np.sort(tagged))
    b = spec.block
    surface = 2 * b.size_x * b.size_y + 2 * (b.size_x + b.size_y) * b.depth
    if spec.cap is not None:
        c = spec.cap
        surface += 2 * (c.x_max - c.x_min + c.y_max - c.y_min) * c.thickness
    area = mesh.comm.allreduce(float(mc.facet_areas(mesh, ext).sum()))
    assert area == pytest.approx(surface, rel=REL)


def test_layer_boundaries_planar_and_complete(case):
    spec, md, _ = case
    mesh = md.mesh
    f2c, counts = _facet_cells(md)
    tag_of_cell = np.empty(mesh.topology.index_map(3).size_local
                           + mesh.topology.index_map(3).num_ghosts, dtype=np.int32)
    tag_of_cell[md.cell_tags.indices] = md.cell_tags.values
    n_own = mesh.topology.index_map(2).size_local
    inner = np.flatnonzero(counts[:n_own] == 2)
    c2 = f2c.array[f2c.offsets[inner][:, None] + np.arange(2)]
    t2 = tag_of_cell[c2]
    n_layers = len(spec.layers)
    n = md.info["n_circ"]
    for j in range(1, n_layers):
        between = inner[(t2.min(axis=1) == j) & (t2.max(axis=1) == j + 1)]
        z = mesh.geometry.x[dolfinx.mesh.entities_to_geometry(mesh, 2, between)][..., 2]
        zb = spec.layer_bottoms()[j - 1]
        assert np.allclose(z, zb, rtol=0, atol=1e-9 * spec.block.depth)
        area = mesh.comm.allreduce(float(mc.facet_areas(mesh, between).sum()))
        piles = sum(poly_area(n, p.radius) for p in spec.piles if -p.length_in_soil < zb)
        assert area == pytest.approx(spec.block.size_x * spec.block.size_y - piles, rel=REL)


def test_shaft_facets_join_pile_and_layer(case):
    spec, md, _ = case
    f2c, counts = _facet_cells(md)
    tag_of_cell = np.full(md.mesh.topology.index_map(3).size_local
                          + md.mesh.topology.index_map(3).num_ghosts, -1, dtype=np.int32)
    tag_of_cell[md.cell_tags.indices] = md.cell_tags.values
    ft = md.facet_tags
    for name, tag in md.facet_names.items():
        if groups.shaft_of(name) is None:
            continue
        i, j = groups.shaft_of(name)
        facets = ft.indices[ft.values == tag]
        assert np.all(counts[facets] == 2)
        pairs = np.sort(tag_of_cell[f2c.array[f2c.offsets[facets][:, None] + np.arange(2)]],
                        axis=1)
        assert np.all(pairs == [md.cell_names[groups.soil_layer(j)],
                                md.cell_names[groups.pile(i)]])


def test_cache_reuses_the_mesh(tmp_path):
    spec = single_pile(h=0.5)
    a = build_mesh(spec, MPI.COMM_WORLD, cache_dir=tmp_path)
    b = build_mesh(spec, MPI.COMM_WORLD, cache_dir=tmp_path)
    c = build_mesh(spec.with_h(0.4), MPI.COMM_WORLD, cache_dir=tmp_path)
    assert not a.info["cache_hit"] and b.info["cache_hit"] and not c.info["cache_hit"]
    assert a.info["cache_key"] == b.info["cache_key"] != c.info["cache_key"]
    assert (a.info["num_cells"], a.info["num_vertices"]) == (b.info["num_cells"],
                                                             b.info["num_vertices"])
    assert len(list(tmp_path.glob("*.msh"))) == 2
    d = build_mesh(spec, MPI.COMM_WORLD, cache_dir=False)
    assert d.info["num_cells"] == a.info["num_cells"]


def test_pile_volume_is_the_cylinders_at_every_h():
    """8, 32 and 64 edges around the pile: the meshed volume is the circle's times the length."""
    for h in (0.5, 0.1, 0.05):
        spec = single_pile(h=h, size_x=10.0, depth=12.0, length_in_soil=6.0)
        md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=False)
        v = mc.group_measures(md)["cells"][groups.pile(1)][1]
        assert v == pytest.approx(math.pi / 4 * 6.0, rel=1e-9), h


def test_other_layouts_mesh(tmp_path):
    spec = mc.mini_pier(0.4)
    md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=False)
    meas = mc.group_measures(md)
    assert len([k for k in meas["facets"] if groups.shaft_of(k)]) == 4 * 3
    assert md.info["min_sj"] > 0.2


def test_mesh_command_writes_xdmf_and_png(tmp_path):
    s = mesh_command(single_pile(h=0.5), 0.4, tmp_path / "out", MPI.COMM_WORLD,
                     cache_dir=tmp_path / "cache")
    out = tmp_path / "out"
    assert s["h_m"] == 0.4 and s["cells"] > 0 and s["min_scaled_jacobian"] > 0.2
    for name in ("mesh.xdmf", "mesh.h5", "mesh.tags.json", "mesh_summary.json", "plan.png",
                 "cutaway.png"):
        assert (out / name).stat().st_size > 0, name
    names = json.loads((out / "mesh.tags.json").read_text())
    assert "shaft_p1_l01" in names["facet_tags"] and "pile_1" in names["cell_tags"]
    with XDMFFile(MPI.COMM_WORLD, str(out / "mesh.xdmf"), "r") as f:
        mesh = f.read_mesh()
        mesh.topology.create_connectivity(2, 3)
        ft = f.read_meshtags(mesh, "facet_tags")
    assert mesh.topology.index_map(3).size_global == s["cells"]
    assert ft.values.size > 0


@pytest.mark.mpi
def test_same_mesh_serial_and_mpirun_2(tmp_path):
    serial = mc.group_measures(build_mesh(mc.mini_pier(0.5), MPI.COMM_WORLD, cache_dir=False))
    mpirun = Path(sys.executable).parent / "mpirun"
    r = subprocess.run([str(mpirun), "-n", "2", sys.executable, str(_HERE / "meshcheck.py"),
                        "mini", "0.5"], capture_output=True, text=True, timeout=600)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]
    line = next(ln for ln in r.stdout.splitlines() if ln.startswith("RESULT "))
    par = json.loads(line[len("RESULT "):])
    for key in ("num_cells", "num_vertices", "num_facets", "cell_tag_sum", "facet_tag_sum"):
        assert par[key] == serial[key], key
    for kind in ("cells", "facets"):
        assert set(par[kind]) == set(serial[kind])
        for name, (count, measure) in serial[kind].items():
            assert par[kind][name][0] == count, name
            assert par[kind][name][1] == pytest.approx(measure, rel=1e-12), name


@pytest.mark.slow
@pytest.mark.parametrize("h", PAPER_SIZES)
def test_paper_sizes(h, cache):
    spec = pier667_default(h)
    md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=cache)
    meas = mc.group_measures(md)
    assert md.info["min_sj"] > 0.2
    assert mc.min_scaled_jacobian(mc.cell_coords(md.mesh)).min() > 0.2
    for i, p in enumerate(spec.piles, start=1):
        exact = math.pi / 4 * p.diameter**2 * (p.length_in_soil + p.embedment)
        assert abs(meas["cells"][groups.pile(i)][1] / exact - 1) < 0.01
    assert len([k for k in meas["facets"] if groups.shaft_of(k)]) == 81


@pytest.mark.slow
def test_paper_sizes_refine_monotonically(cache):
    cells, errs = [], []
    for h in PAPER_SIZES:
        md = build_mesh(pier667_default(h), MPI.COMM_WORLD, cache_dir=cache)
        meas = mc.group_measures(md)
        cells.append(md.info["num_cells"])
        exact = math.pi / 4 * 64.5
        errs.append(max(abs(meas["cells"][groups.pile(i)][1] / exact - 1) for i in range(1, 10)))
    assert all(a < b for a, b in zip(cells[:-1], cells[1:], strict=True))
    assert all(b <= a * (1 + 1e-12) for a, b in zip(errs[:-1], errs[1:], strict=True))


def test_a_stop_signal_after_gmsh_is_still_a_stop_request():
    # gmsh replaces the C-level actions when it starts and ends; the run's handlers must come
    # back. In a subprocess: without them the signal would end the process.
    code = """
import os, signal
import pilegroup
from pilegroup.geometry.convert import gmsh_session
from pilegroup.studies.run.interrupt import STOP_SIGNALS, requested, stop_on_signals
for sig in STOP_SIGNALS:
    with stop_on_signals():
        with gmsh_session():
            pass
        os.kill(os.getpid(), sig)
        print(sig.name, requested() == sig)
"""
    r = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr[-2000:]
    assert r.stdout.split() == ["SIGTERM", "True", "SIGINT", "True", "SIGUSR1", "True"]
