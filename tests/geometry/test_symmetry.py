"""Symmetry-reduced models: the kept half or quarter against the full model with the same sizing.

The full model of a mirror-symmetric layout is made of the reduced part and its mirror images,
so the reduced mesh is the full mesh's restriction: the same vertices and cells, bit for bit
(exact mirror copies make the full mesh exactly symmetric), and every cell group holds exactly
its share of the full mesh's volume (soil and cap 1/2 or 1/4, each kept pile its meshed
fraction), every facet group its share of the area (an interface group of a cut pile: its
fraction), to 1e-9 relative: a cut pile is the exact half (quarter) of the full model's
polygonal pile, also when N / 4 is odd (Pier 667, N = 28). Specs, resolution and errors need
no mesh.
"""

import dataclasses
import importlib.util
from pathlib import Path

import dolfinx
import numpy as np
import pytest
from dolfinx.mesh import exterior_facet_indices
from mpi4py import MPI

from pilegroup.errors import ScenarioError
from pilegroup.geometry import groups
from pilegroup.geometry import spec as gs
from pilegroup.geometry.adapter import geometry_spec, resolve_geometry
from pilegroup.geometry.convert import build_mesh
from pilegroup.geometry.plan import circumferential_divisions
from pilegroup.model import load_scenario

_HERE = Path(__file__).parent
_spec = importlib.util.spec_from_file_location("meshcheck", _HERE / "meshcheck.py")
mc = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(mc)

REL = 1e-9


def _small(plan, piles, cap=None, n_circ_min=16):
    """A small spec: ``plan`` (size_x, size_y, depth) m, a 2 m layer over a deep one, d = 0.8 m."""
    return gs.GeometrySpec(
        block=gs.BlockSpec(*plan),
        layers=(gs.LayerSpec("a", 2.0), gs.LayerSpec("b", None)),
        piles=piles,
        cap=cap,
        sizing=gs.MeshSizing(h_pile=0.5, h_far=4.0, n_circ_min=n_circ_min, dz_max=3.0),
    )


def group_2x2():
    """Piles at (+-1.5, +-1.5) m under a cap: the planes run between the piles."""
    return _small((24.0, 20.0, 16.0), gs.grid_piles(2, 2, 3.0, 3.0, 0.8, 8.0, 0.5),
                  gs.CapSpec.centred(6.0, 6.0, 1.5))


def group_3x3():
    """A 3 x 3 group under a cap: the centre pile on both planes, N / 4 = 4 (even)."""
    return _small((30.0, 26.0, 18.0), gs.grid_piles(3, 3, 3.0, 2.5, 0.8, 9.0, 0.5),
                  gs.CapSpec.centred(8.4, 7.0, 1.5))


def dice():
    """Four corner piles and a centre pile, no cap, N / 4 = 3 (odd).

    The cells between the corner piles hold no pile and are cut by the planes too.
    """
    xy = ((-2.0, -2.0), (2.0, -2.0), (0.0, 0.0), (-2.0, 2.0), (2.0, 2.0))
    return _small((24.0, 24.0, 16.0), tuple(gs.PileSpec(x, y, 0.8, 8.0) for x, y in xy),
                  n_circ_min=12)


SPECS = {"pier": lambda: gs.pier667_default(1.0), "group_2x2": group_2x2,
         "group_3x3": group_3x3, "dice": dice, "single": lambda: gs.single_pile(h=0.5)}
CASES = [("pier", "quarter"), ("pier", "half_y"), ("group_2x2", "quarter"),
         ("group_2x2", "half_x"), ("group_3x3", "quarter"), ("group_3x3", "half_x"),
         ("dice", "quarter"), ("dice", "half_y"), ("single", "quarter")]


@pytest.fixture(scope="module")
def built(tmp_path_factory):
    """Build each (spec, symmetry) once: spec, MeshData and group measures."""
    cache = tmp_path_factory.mktemp("symcache")
    done = {}

    def get(name, mode):
        if (name, mode) not in done:
            spec = dataclasses.replace(SPECS[name](), symmetry=mode)
            md = build_mesh(spec, MPI.COMM_WORLD, cache_dir=cache)
            done[(name, mode)] = (spec, md, mc.group_measures(md))
        return done[(name, mode)]

    return get


@pytest.fixture(scope="module", params=CASES, ids=[f"{a}-{b}" for a, b in CASES])
def case(request, built):
    name, mode = request.param
    return built(name, "none"), built(name, mode)


def _share(spec, name):
    """Fraction of the full model's group ``name`` that the reduced ``spec`` holds."""
    i = next((k for k in (groups.pile_of(name), groups.base_of(name), groups.embed_of(name),
                          groups.head_of(name), (groups.shaft_of(name) or (None,))[0])
              if k is not None), None)
    if i is not None:
        return spec.pile_fraction(i)
    planes = spec.cut_planes()
    if name in (groups.SIDE_XMIN, groups.SIDE_XMAX):
        return 0.0 if name == groups.SIDE_XMIN and "x" in planes else 0.5 ** ("y" in planes)
    if name in (groups.SIDE_YMIN, groups.SIDE_YMAX):
        return 0.0 if name == groups.SIDE_YMIN and "y" in planes else 0.5 ** ("x" in planes)
    return 0.5 ** len(planes)


def test_groups_hold_their_share_of_the_full_model(case):
    (_, _, full), (spec, md, red) = case
    for kind in ("cells", "facets"):
        expected = {n for n in full[kind] if _share(spec, n) > 0}
        got = {n for n in red[kind] if n not in (groups.SYM_X, groups.SYM_Y)}
        assert got == expected, kind
        for name in expected:
            want = _share(spec, name) * full[kind][name][1]
            assert red[kind][name][1] == pytest.approx(want, rel=REL), name
    assert set(red["cells"]) == {*map(groups.pile, spec.kept_piles()), groups.CAP,
                                 *(groups.soil_layer(j + 1) for j in range(len(spec.layers)))
                                 } - ({groups.CAP} if spec.cap is None else set())
    assert md.info["n_circ"] == circumferential_divisions(spec)
    assert red["total_volume"] == pytest.approx(0.5 ** len(spec.cut_planes())
                                                * full["total_volume"], rel=REL)


def test_symmetry_planes_area_is_the_cross_section(case):
    _, (spec, _, red) = case
    b, c = spec.block, spec.cap
    x0, x1, y0, y1 = spec.plan_bounds()
    for axis, name, (lo, hi) in (("x", groups.SYM_X, (y0, y1)), ("y", groups.SYM_Y, (x0, x1))):
        if axis not in spec.cut_planes():
            assert name not in red["facets"]
            continue
        area = (hi - lo) * b.depth
        if c is not None:
            c_lo, c_hi = (c.y_min, c.y_max) if axis == "x" else (c.x_min, c.x_max)
            area += (c_hi - max(c_lo, lo)) * c.thickness
        assert red["facets"][name][1] == pytest.approx(area, rel=REL)
        assert groups.tag_of(name) == {"x": 10, "y": 11}[axis]


def _cell_tags(md):
    imap = md.mesh.topology.index_map(3)
    tags = np.full(imap.size_local + imap.num_ghosts, -1, dtype=np.int32)
    tags[md.cell_tags.indices] = md.cell_tags.values
    return tags


def test_plane_nodes_lie_on_the_plane_also_on_cut_piles(case):
    _, (spec, md, _) = case
    mesh = md.mesh
    mesh.topology.create_connectivity(2, 3)
    f2c = mesh.topology.connectivity(2, 3)
    cell_tag = _cell_tags(md)
    cut = [i for i in spec.kept_piles() if spec.pile_fraction(i) < 1]
    on_pile = set()
    for k, axis in enumerate(("x", "y")):
        if axis not in spec.cut_planes():
            continue
        facets = md.facet_tags.find(md.facet_names[groups.SYM_PLANES[axis]])
        x = mesh.geometry.x[dolfinx.mesh.entities_to_geometry(mesh, 2, facets)]
        assert np.all(x[..., k] == 0.0)
        owner = cell_tag[f2c.array[f2c.offsets[facets]]]
        on_pile |= {groups.pile_of(n) for n, t in md.cell_names.items() if t in set(owner)}
    assert set(cut) <= on_pile


def test_exterior_is_tagged_and_all_hexahedra(case):
    _, (spec, md, red) = case
    mesh = md.mesh
    ext = mc.owned_facets(mesh, exterior_facet_indices(mesh.topology))
    boundary = {*groups.SIDES, groups.SYM_X, groups.SYM_Y, groups.BOTTOM, groups.GROUND,
                groups.CAP_TOP, groups.CAP_SIDE, *groups.heads(md.facet_names)}
    tags = [md.facet_names[k] for k in boundary if k in md.facet_names]
    ft = md.facet_tags
    tagged = mc.owned_facets(mesh, ft.indices[np.isin(ft.values, tags)])
    assert np.array_equal(np.sort(ext), np.sort(tagged))
    assert md.info["n_hex"] == md.info["num_cells"]
    assert mc.min_scaled_jacobian(mc.cell_coords(mesh)).min() > 0.2


def test_pier_quarter_is_a_quarter_of_the_cells(built):
    _, full, _ = built("pier", "none")
    spec, quarter, _ = built("pier", "quarter")
    _, half, _ = built("pier", "half_y")
    assert spec.kept_piles() == (5, 6, 8, 9)
    n_full = full.info["num_cells"]
    assert 4 * quarter.info["num_cells"] == 2 * half.info["num_cells"] == n_full


def _kept(spec, x):
    """Rows of the points ``x`` (n, 3) on the kept side of ``spec``'s planes (on them too)."""
    keep = np.ones(len(x), dtype=bool)
    for k, axis in enumerate(("x", "y")):
        if axis in spec.cut_planes():
            keep &= x[:, k] >= 0.0
    return x[keep]


def _sorted_rows(x):
    return x[np.lexsort(x.T[::-1])]


def _cells(md):
    """Every owned cell as (its 8 corner coordinates sorted, flattened) -> its cell tag."""
    tags = _cell_tags(md)
    corners = mc.cell_coords(md.mesh)
    return {tuple(_sorted_rows(c).ravel()): int(t) for c, t in zip(corners, tags, strict=False)}


def test_reduced_mesh_is_the_full_mesh_on_its_side(case):
    """The reduced model is the full model's part and the full model the part's mirror images:
    the same vertices and cells (with their groups), bit for bit, on the kept side."""
    (_, full, _), (spec, red, _) = case
    xf, xr = full.mesh.geometry.x, red.mesh.geometry.x
    assert np.array_equal(_sorted_rows(_kept(spec, xf)), _sorted_rows(xr))
    cells_full, cells_red = _cells(full), _cells(red)
    assert len(cells_red) * 2 ** len(spec.cut_planes()) == len(cells_full)
    names_full = {t: n for n, t in full.cell_names.items()}
    names_red = {t: n for n, t in red.cell_names.items()}
    assert {k: names_red[t] for k, t in cells_red.items()} == {
        k: names_full[cells_full[k]] for k in cells_red}


def test_full_mesh_is_mirror_symmetric(case):
    (spec, full, _), _ = case
    x = full.mesh.geometry.x
    for k, axis in enumerate(("x", "y")):
        if axis in spec.symmetry_planes():
            m = x.copy()
            m[:, k] = -m[:, k] + 0.0
            assert np.array_equal(_sorted_rows(m), _sorted_rows(x)), axis


def test_pier_kept_piles_fractions_and_mirror_images():
    s = dataclasses.replace(gs.pier667_default(1.0), symmetry="quarter")
    assert s.symmetry_planes() == ("x", "y")
    assert [s.pile_fraction(i) for i in range(1, 10)] == [0, 0, 0, 0, 0.25, 0.5, 0, 0.5, 1]
    assert s.mirror_of() == {1: 9, 2: 8, 3: 9, 4: 6, 5: 5, 6: 6, 7: 9, 8: 8, 9: 9}
    h = dataclasses.replace(s, symmetry="half_x")
    assert h.kept_piles() == (2, 3, 5, 6, 8, 9)
    assert h.mirror_of() == {1: 3, 2: 2, 3: 3, 4: 6, 5: 5, 6: 6, 7: 9, 8: 8, 9: 9}
    assert gs.pier667_default(1.0).mirror_of() == {i: i for i in range(1, 10)}
    assert s.plan_bounds() == (0.0, 50.5, 0.0, 37.5)


@pytest.mark.parametrize("change, plane", [
    (lambda s: dataclasses.replace(s, piles=(*s.piles[:8], dataclasses.replace(
        s.piles[8], x=3.0))), "x"),
    (lambda s: dataclasses.replace(s, piles=(*s.piles[:8], dataclasses.replace(
        s.piles[8], diameter=0.9))), "x"),
    (lambda s: dataclasses.replace(s, cap=gs.CapSpec(-5.05, 5.05, -3.7, 3.8, 2.5)), "y"),
])
def test_asymmetric_specs_refuse_a_cut(change, plane):
    s = change(gs.pier667_default(1.0))
    assert plane not in s.symmetry_planes()
    with pytest.raises(ScenarioError) as e:
        dataclasses.replace(s, symmetry="quarter")
    assert e.value.key == "numerics.symmetry" and e.value.value == "quarter"
    assert f"{plane} = 0" in e.value.allowed
    with pytest.raises(ScenarioError) as e:
        dataclasses.replace(s, symmetry="octant")
    assert e.value.key == "numerics.symmetry"


def test_cache_key_tracks_symmetry():
    s = gs.pier667_default(1.0)
    keys = {dataclasses.replace(s, symmetry=m).cache_key() for m in
            ("none", "quarter", "half_x", "half_y")}
    assert len(keys) == 4
    assert s.to_dict()["symmetry"] == "none"


def _with_positions(sc, xy):
    piles = dataclasses.replace(sc.piles, grid=None, spacing_m=None, positions_m=tuple(xy))
    return dataclasses.replace(sc, piles=piles)


def test_auto_resolves_pier_to_quarter_and_eccentric_to_none():
    sc = load_scenario("pier667")
    assert sc.numerics.symmetry == "auto"
    mode, reason = resolve_geometry(sc).symmetry, resolve_geometry(sc).reason
    assert mode == "quarter" and "x = 0 and y = 0" in reason
    assert geometry_spec(sc).symmetry == "quarter"
    # one corner pile left out: no mirror image about x = 0 nor y = 0
    eccentric = _with_positions(sc, [(x, y) for x, y in sc.piles.xy if not (x > 0 and y > 0)])
    mode, reason = resolve_geometry(eccentric).symmetry, resolve_geometry(eccentric).reason
    assert mode == "none" and "x = 0" in reason and "y = 0" in reason
    assert geometry_spec(eccentric).symmetry == "none"
    rows = _with_positions(sc, [(x, y) for x, y in sc.piles.xy if y < 2])  # 2 rows: x only
    assert resolve_geometry(rows).symmetry == "half_x"


def test_explicit_symmetry_is_checked_against_the_scene():
    sc = load_scenario("pier667")
    for mode in ("none", "half_x", "half_y", "quarter"):
        one = dataclasses.replace(sc, numerics=dataclasses.replace(sc.numerics, symmetry=mode))
        assert resolve_geometry(one).symmetry == mode == geometry_spec(one).symmetry
    rows = _with_positions(sc, [(x, y) for x, y in sc.piles.xy if y < 2])
    bad = dataclasses.replace(rows, numerics=dataclasses.replace(rows.numerics,
                                                                 symmetry="half_y"))
    with pytest.raises(ScenarioError) as e:
        geometry_spec(bad)
    assert e.value.key == "numerics.symmetry" and "y = 0" in str(e.value)
