"""A 5 x 5 group of 1 m piles at 3 m under a 14 m cap: the far-field repair must not collapse.

The user's layout (Pier 667's site and piles, ``grid = [5, 5]``, ``spacing_m = [3, 3]``, a
14.0 x 14.0 m cap: the cap edge 0.5 m from the outer piles' surfaces) with 28 edges around a
pile: gmsh's recombination of the far field leaves pairs of triangles there, and
:func:`~pilegroup.geometry.quadfix.all_quads` placed a new node 3e-7 m from a boundary node
(its pattern search maximised the scaled Jacobian alone, which an edge shrinking to nothing
does not lower). gmsh then merged the two points: "Point 280 does not exist" on embedding, or
a cell with a repeated vertex that aborted DOLFINx. The plan only depends on the block's plan
size, the cap, the piles and the plan sizing, so the tests keep the site's 101 x 75 m plan
but only two layers, 12 m piles in a 30 m deep block and coarse vertical sizes (fast).

Checked: the far field's quadrilaterals keep their shortest edge >= 5 % of their longest; the
full and the automatic (quarter) model mesh; every pile (or its kept fraction) has the N-gon's
volume (the N-gon 0.84 % below pi d^2/4 x length for N = 28); every cell has a positive
volume; no two vertices coincide; and a sweep of caps and spacings around the critical ones.
"""

import dataclasses
import importlib.util
import math
import tomllib
from pathlib import Path

import pytest
from mpi4py import MPI
from scipy.spatial import cKDTree

from pilegroup.geometry import groups
from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.geometry.convert import build_mesh, gmsh_session
from pilegroup.geometry.far_field import far_field
from pilegroup.geometry.pier import GMSH_OPTIONS
from pilegroup.geometry.plan import polygon_radius
from pilegroup.geometry.quadfix import edge_ratio
from pilegroup.model import bundled_text, scenario_from_dict

_HERE = Path(__file__).parent
_spec = importlib.util.spec_from_file_location("meshcheck", _HERE / "meshcheck.py")
mc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mc)

REL = 1e-9
N = 28
NGON_DEFICIT = 0.0  # the meshed N-gon has the circle's area (plan.polygon_radius)
#: The plan sizing of the failing run (``size_m = 2`` with 28 edges around a pile), with
#: coarse vertical sizes.
MESH = {"size_m": 2.0, "n_circ_min": N, "far_field_size_m": 64.0, "growth": 1.6,
        "dz_surface_m": 6.0, "dz_toe_m": 6.0, "dz_max_m": 12.0, "dz_max_deep_m": 18.0,
        "dz_growth": 1.4, "dz_cap_m": 2.5, "min_layer_divisions": 1}


def scenario(cap=14.0, spacing=3.0, symmetry="auto"):
    d = tomllib.loads(bundled_text("pier667"))
    d["piles"].update(grid=[5, 5], spacing_m=[spacing, spacing], length_in_soil_m=12.0)
    d["cap"].update(size_x_m=cap, size_y_m=cap)
    d["site"]["depth_m"] = 30.0
    d["layers"] = d["layers"][:2]
    d["layers"][1].pop("thickness_m")  # to the bottom
    d["outputs"].pop("gauge_depths_m", None)
    d.pop("reference")  # the paper's values name layers and gauges this layout has not
    d["numerics"] = {"element": "Q1Q1", "symmetry": symmetry, "mesh": dict(MESH)}
    return scenario_from_dict(d)


def poly_area(r):
    """The meshed N-gon's area (its corners on ``polygon_radius``): the circle's."""
    big = polygon_radius(r, N)
    return 0.5 * N * big * big * math.sin(2 * math.pi / N)


def check_mesh_data(spec, md):
    """Pile volumes, positive cell volumes, no coincident vertices (serial)."""
    assert md.info["n_circ"] == N and md.info["min_sj"] > 0.2
    meas = mc.group_measures(md)
    kept = spec.kept_piles()
    assert len(kept) == (25 if spec.symmetry == "none" else 9)
    for i in kept:
        p = spec.piles[i - 1]
        length = p.length_in_soil + p.embedment
        v = meas["cells"][groups.pile(i)][1] / spec.pile_fraction(i)
        assert v == pytest.approx(poly_area(p.radius) * length, rel=REL)
        assert 1.0 - v / (math.pi * p.diameter ** 2 / 4 * length) == pytest.approx(
            NGON_DEFICIT, abs=1e-12)
    vols = mc.hex_volumes(mc.cell_coords(md.mesh))
    assert vols.min() > 0.0
    x = md.mesh.geometry.x
    assert len(cKDTree(x).query_pairs(1e-6)) == 0
    assert meas["total_volume"] == pytest.approx(vols.sum(), rel=REL)


def test_far_field_repair_keeps_its_nodes_apart():
    spec = resolve_geometry(scenario()).spec
    assert spec.symmetry == "quarter"
    with gmsh_session() as gmsh:
        for key, val in GMSH_OPTIONS.items():
            gmsh.option.setNumber(key, val)
        far = far_field(spec)
    assert far.min_sj > 0.3
    assert min(edge_ratio(far.xy, q) for q in far.quads) > 0.05  # was 2.5e-7
    assert len(cKDTree(far.xy).query_pairs(1e-3)) == 0


@pytest.fixture(scope="module")
def meshes():
    """The layout's full and automatic (quarter) models: symmetry -> (spec, MeshData)."""
    geo = resolve_geometry(scenario())
    assert geo.symmetry == "quarter"
    full = dataclasses.replace(geo.spec, symmetry="none")
    return {s.symmetry: (s, build_mesh(s, MPI.COMM_WORLD, cache_dir=False))
            for s in (full, geo.spec)}


@pytest.mark.parametrize("symmetry", ["none", "quarter"])
def test_group5x5_under_14m_cap_meshes(meshes, symmetry):
    check_mesh_data(*meshes[symmetry])


def test_quarter_is_a_quarter_of_the_full_model(meshes):
    assert meshes["none"][1].info["num_cells"] == 4 * meshes["quarter"][1].info["num_cells"]


@pytest.mark.parametrize(("cap", "spacing"), [
    (13.9, 3.0), (14.05, 3.0), (14.1, 3.0), (14.01, 3.05),
    (14.0, 2.9), (14.0, 2.95), (14.0, 3.05), (14.0, 3.1)])
def test_caps_and_spacings_near_the_critical_ones_mesh(cap, spacing):
    spec = resolve_geometry(scenario(cap, spacing)).spec
    assert spec.symmetry == "quarter"
    md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=False)
    check_mesh_data(spec, md)
