"""Piles of different diameters and lengths, from a scenario's ``piles.layout`` to the mesh.

Two small layouts in the bundled single_pile site (16 x 16 x 20 m, a 8 m layer over a deeper
one), coarse (``size_m = 1``, far field 8 m, 16 edges around every pile):

* ``two``: d = 1.0 m, 12 m at x = -2 and d = 0.6 m, 6 m at x = +2 (no cap): mirror-symmetric
  about y = 0 only (the piles at mirror positions about x = 0 differ) -> ``half_y``;
* ``row3``: d = 1.0 m, 12 m at x = -+2.5 and d = 0.6 m, 6 m at x = 0, under a 7.5 x 3 m cap with
  0.5 m embedment -> ``quarter`` (the thin pile cut in four).

Every circle has the same N = 16 edges (the o-grid cells share their sides), so every meshed
pile is N-gon area x (length in soil + embedment) to round-off (1e-9), and lies below the
circle's pi d^2/4 x length by the N-gon's deficit 1 - N sin(2 pi / N) / (2 pi) = 2.55 %,
whatever its diameter. Each pile's cells end at its own toe, and the reduced model holds each
kept pile's fraction of the full model's volume.
"""

import dataclasses
import importlib.util
import math
import tomllib
from pathlib import Path

import dolfinx
import numpy as np
import pytest
from mpi4py import MPI

from pilegroup.errors import ScenarioError
from pilegroup.geometry import groups, ring
from pilegroup.geometry import spec as gs
from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.plan import cell_grid, polygon_radius
from pilegroup.model import bundled_text, scenario_from_dict

_HERE = Path(__file__).parent
_spec = importlib.util.spec_from_file_location("meshcheck", _HERE / "meshcheck.py")
mc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mc)

REL = 1e-9
N = 16
#: The N-gon's area deficit against its circle (measured below: the same for every pile).
NGON_DEFICIT = 0.0  # the meshed N-gon has the circle's area (plan.polygon_radius)

LAYOUTS = {
    "two": ([{"x_m": -2.0, "y_m": 0.0, "diameter_m": 1.0, "length_in_soil_m": 12.0},
             {"x_m": 2.0, "y_m": 0.0, "diameter_m": 0.6, "length_in_soil_m": 6.0}], None),
    "row3": ([{"x_m": -2.5, "y_m": 0.0}, {"x_m": 0.0, "y_m": 0.0, "diameter_m": 0.6,
                                          "length_in_soil_m": 6.0},
              {"x_m": 2.5, "y_m": 0.0}], {"size_x_m": 7.5, "size_y_m": 3.0, "thickness_m": 1.0}),
}
EXPECTED = {"two": "half_y", "row3": "quarter"}


def scenario(name):
    layout, cap = LAYOUTS[name]
    d = tomllib.loads(bundled_text("single_pile"))
    d["piles"] = {"diameter_m": 1.0, "length_in_soil_m": 12.0, "layout": layout}
    if cap is not None:
        d["cap"], d["piles"]["embedment_m"] = cap, 0.5
        d["interface"]["mode"] = "tied"  # a cap bonded to the ground
    d["outputs"].pop("gauge_depths_m")
    d["numerics"] = {"element": "Q1Q1", "mesh": {
        "size_m": 1.0, "far_field_size_m": 8.0, "n_circ_min": N, "growth": 1.3,
        "dz_surface_m": 2.0, "dz_toe_m": 1.0, "dz_max_m": 4.0, "dz_max_deep_m": 8.0,
        "dz_growth": 1.2, "dz_cap_m": 0.5}}
    return scenario_from_dict(d)


@pytest.fixture(scope="module")
def meshed():
    """Each layout's resolved geometry, and its full and reduced meshes with group measures."""
    out = {}
    for name in LAYOUTS:
        geo = resolve_geometry(scenario(name))
        full = dataclasses.replace(geo.spec, symmetry="none")
        models = {}
        for spec in (full, geo.spec):
            md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=False)
            models[spec.symmetry] = (spec, md, mc.group_measures(md))
        out[name] = (geo, models)
    return out


def poly_area(r):
    """The meshed N-gon's area (its corners on ``polygon_radius``): the circle's."""
    big = polygon_radius(r, N)
    return 0.5 * N * big * big * math.sin(2 * math.pi / N)


def test_auto_symmetry_of_mixed_layouts(meshed):
    two, _ = meshed["two"]
    assert two.symmetry == "half_y"
    assert ("not about x = 0 (pile 1 and its mirror image, pile 2, differ in diameter (1 vs"
            " 0.6 m))") in two.reason
    row3, _ = meshed["row3"]
    assert row3.symmetry == "quarter" and "x = 0 and y = 0" in row3.reason
    assert row3.spec.pile_fraction(2) == 0.25 and row3.spec.mirror_of() == {1: 3, 2: 2, 3: 3}


@pytest.mark.parametrize("name", LAYOUTS)
def test_every_pile_has_its_own_volume(meshed, name):
    _, models = meshed[name]
    spec, md, meas = models["none"]
    assert md.info["n_circ"] == N and md.info["min_sj"] > 0.2
    assert {p.diameter for p in spec.piles} == {1.0, 0.6}
    assert {p.length_in_soil for p in spec.piles} == {12.0, 6.0}
    for i, p in enumerate(spec.piles, start=1):
        length = p.length_in_soil + p.embedment
        v = meas["cells"][groups.pile(i)][1]
        assert v == pytest.approx(poly_area(p.radius) * length, rel=REL)
        circle = math.pi * p.diameter ** 2 / 4 * length
        assert 1.0 - v / circle == pytest.approx(NGON_DEFICIT, abs=1e-12)


@pytest.mark.parametrize("name", LAYOUTS)
def test_each_pile_ends_at_its_own_toe(meshed, name):
    _, models = meshed[name]
    spec, md, meas = models["none"]
    x, dofs = md.mesh.geometry.x, md.mesh.geometry.dofmaps[0]
    ct = md.cell_tags
    for i, p in enumerate(spec.piles, start=1):
        z = x[dofs[ct.indices[ct.values == md.cell_names[groups.pile(i)]]], 2]
        assert z.min() == pytest.approx(-p.length_in_soil, abs=1e-9)
        assert z.max() == pytest.approx(p.embedment, abs=1e-9)
        base = md.facet_tags.indices[md.facet_tags.values == md.facet_names[groups.base(i)]]
        zb = md.mesh.geometry.x[dolfinx.mesh.entities_to_geometry(md.mesh, 2, base)][..., 2]
        assert np.allclose(zb, -p.length_in_soil, rtol=0, atol=1e-9)
        assert meas["facets"][groups.base(i)][1] == pytest.approx(poly_area(p.radius), rel=REL)
        # the 6 m piles end in the first layer (8 m): no shaft in the second
        layers = {j for j in (1, 2) if groups.shaft(i, j) in meas["facets"]}
        assert layers == ({1} if p.length_in_soil < 8.0 else {1, 2})
    # the soil of each layer is the block minus the piles' parts in it
    a_block = spec.block.size_x * spec.block.size_y
    for j, (top, bottom) in enumerate(((0.0, -8.0), (-8.0, -20.0)), start=1):
        piles = sum(poly_area(p.radius) * max(0.0, top - max(bottom, -p.length_in_soil))
                    for p in spec.piles)
        v = meas["cells"][groups.soil_layer(j)][1]
        assert v == pytest.approx(a_block * (top - bottom) - piles, rel=REL)


@pytest.mark.parametrize("name", LAYOUTS)
def test_reduced_model_holds_each_piles_share(meshed, name):
    geo, models = meshed[name]
    full, _, m_full = models["none"]
    spec, _, meas = models[EXPECTED[name]]
    assert spec.symmetry == geo.symmetry == EXPECTED[name]
    assert meas["total_volume"] == pytest.approx(m_full["total_volume"] / 2 ** len(
        spec.cut_planes()), rel=REL)
    kept = spec.kept_piles()
    assert {groups.pile_of(k) for k in meas["cells"] if groups.pile_of(k)} == set(kept)
    for i in kept:
        v = meas["cells"][groups.pile(i)][1]
        assert v == pytest.approx(spec.pile_fraction(i) * m_full["cells"][groups.pile(i)][1],
                                  rel=REL)


def _pair(gap_centres, d1=1.0, d2=0.6):
    return gs.GeometrySpec(
        block=gs.BlockSpec(16.0, 16.0, 20.0), layers=(gs.LayerSpec("a", 8.0),
                                                      gs.LayerSpec("b", None)),
        piles=(gs.PileSpec(-gap_centres / 2, 0.0, d1, 12.0),
               gs.PileSpec(gap_centres / 2, 0.0, d2, 6.0)),
        sizing=gs.MeshSizing(h_pile=1.0, h_far=8.0, n_circ_min=N, dz_surface=2.0, dz_toe=1.0,
                             dz_max=4.0, dz_max_deep=8.0))


def test_cell_edge_shares_the_gap_in_proportion_to_the_radii():
    """Equal piles: half-way. A 1.0 m and a 0.6 m pile 1.1 m apart (a 0.3 m gap): half-way
    would leave the thick pile 0.05 m < 0.2 x 0.5 m; the edge at 3/8 and 5/8 of the gap leaves
    each pile 0.375 x its radius."""
    xb, _, _ = cell_grid(_pair(3.0, 0.8, 0.8))
    assert xb[1] == 0.0
    xb, _, _ = cell_grid(_pair(1.1))
    assert xb[1] == pytest.approx(-0.55 + 0.5 + 0.3 * 0.5 / 0.8, abs=1e-12)
    md = build_mesh(_pair(1.1), MPI.COMM_WORLD, cache_dir=False)
    assert md.info["min_sj"] > 0.2
    with pytest.raises(ScenarioError, match="structured cell edge"):
        cell_grid(_pair(0.85))  # a 0.05 m gap: less than 0.2 x the radii


def test_off_centre_pile_gets_its_cell_side_graded_where_the_ring_folds():
    """A pile 1.05 m from its cell's left side and 3.05 m from its top, one radial layer, two
    edges a side: evenly divided, the left side's middle node lies 1 m above the pile's arc
    node facing it across a 0.35 m ring (a fold); graded, that node faces the pile. A pile in
    the middle of its cell is left alone (its sides stay even)."""
    centre, r = (0.0, 0.0), 0.7
    top_left, bottom_left = (-1.05, 3.05), (-1.05, -1.05)  # side k = 1, corner 1 to corner 2
    pile = ((*centre, r), 1)
    assert ring.ring_folds(*pile, (top_left, bottom_left, 2, 1.0), (1, 1.0))
    c = ring.side_grading(centre, top_left, bottom_left, 2)
    middle = ring.fractions(2, c)[1]
    assert top_left[1] + middle * (bottom_left[1] - top_left[1]) == pytest.approx(0.0, abs=1e-12)
    assert not ring.ring_folds(*pile, (top_left, bottom_left, 2, c), (1, 1.0))
    assert not ring.ring_folds(*pile, ((-2.0, 2.0), (-2.0, -2.0), 2, 1.0), (1, 1.0))
