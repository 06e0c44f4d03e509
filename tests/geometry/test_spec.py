"""GeometrySpec validation and the vertical division (no gmsh, milliseconds)."""

import math

import numpy as np
import pytest

from pilegroup.errors import ScenarioError
from pilegroup.geometry.spec import (
    BlockSpec,
    CapSpec,
    GeometrySpec,
    LayerSpec,
    MeshSizing,
    PileSpec,
    pier667_default,
    single_pile,
)
from pilegroup.geometry.vertical import vertical_segments


def test_pier667_default_dimensions():
    s = pier667_default()
    assert (s.block.size_x, s.block.size_y, s.block.depth) == (101.0, 75.0, 128.0)
    assert len(s.layers) == 10 and s.layers[-1].thickness is None
    assert s.layer_bottoms()[-2] == pytest.approx(-64.3)
    assert len(s.piles) == 9
    assert {p.diameter for p in s.piles} == {1.0}
    assert {(p.length_in_soil, p.embedment) for p in s.piles} == {(63.5, 1.0)}
    c = s.cap
    assert (c.x_max - c.x_min, c.y_max - c.y_min, c.thickness) == pytest.approx((10.1, 7.4, 2.5))
    # >= 1 d from every pile centre to the cap edge
    for p in s.piles:
        assert min(p.x - c.x_min, c.x_max - p.x, p.y - c.y_min, c.y_max - p.y) >= p.diameter
    assert s.layer_of_depth(-63.5) == 9  # the toe lies in layer 9


@pytest.mark.parametrize("build, key, entry", [
    (lambda: BlockSpec(-1.0, 1.0, 1.0), "block.size_x", ""),
    (lambda: PileSpec(0.0, 0.0, 0.0, 1.0), "pile.diameter", ""),
    (lambda: CapSpec(1.0, 0.0, 0.0, 1.0, 1.0), "cap.x_max", ""),
    (lambda: MeshSizing(n_circ_min=30), "sizing.n_circ_min", ""),
    (lambda: MeshSizing(growth=1.0), "sizing.growth", ""),
    (lambda: MeshSizing(h_pile=2.0, h_far=1.0), "sizing.h_far", ""),
    (lambda: GeometrySpec(BlockSpec(10, 10, 10), (LayerSpec("a", 4.0), LayerSpec("b", 4.0)),
                          (PileSpec(0, 0, 1, 5),)), "layers[1].thickness", "layer 2"),
    (lambda: GeometrySpec(BlockSpec(10, 10, 10), (LayerSpec("a", None), LayerSpec("b", None)),
                          (PileSpec(0, 0, 1, 5),)), "layers[0].thickness", "layer 1"),
    (lambda: GeometrySpec(BlockSpec(10, 10, 10), (LayerSpec("a", None),),
                          (PileSpec(0, 0, 1, 10),)), "piles[0].length_in_soil", "pile 1"),
    (lambda: GeometrySpec(BlockSpec(10, 10, 10), (LayerSpec("a", None),),
                          (PileSpec(0, 0, 1, 5, 0.5),)), "piles[0].embedment", "pile 1"),
    (lambda: GeometrySpec(BlockSpec(10, 10, 10), (LayerSpec("a", None),),
                          (PileSpec(0, 0, 1, 5), PileSpec(0.8, 0, 1, 5))), "piles[1]", "pile 2"),
    (lambda: GeometrySpec(BlockSpec(10, 10, 10), (LayerSpec("a", None),),
                          (PileSpec(0, 0, 1, 5, 0.5),), CapSpec(-0.4, 2, -2, 2, 1.0)),
     "piles[0]", "pile 1"),
])
def test_validation_names_the_field(build, key, entry):
    """The message starts with the key path (0-based, as --set takes it) and, for an entry of
    a list of layers or piles, that entry counted from 1."""
    with pytest.raises(ScenarioError) as e:
        build()
    assert e.value.key == key
    head = f"{key} ({entry}) = " if entry else f"{key} = "
    assert str(e.value).startswith(head)


def test_spec_is_hashable_data_and_key_tracks_h():
    a, b = pier667_default(1.0), pier667_default(1.0)
    assert a == b and a.cache_key() == b.cache_key()
    assert a.cache_key() != a.with_h(0.8).cache_key()
    assert a.with_h(0.8).sizing.h_pile == 0.8


def test_vertical_segments_cut_at_layers_toes_and_cap():
    s = pier667_default()
    soil, cap = vertical_segments(s)
    starts = [seg.z_start for seg in soil] + [soil[-1].z_end]
    for z in (0.0, *s.layer_bottoms(), -63.5):
        assert min(abs(z - v) for v in starts) < 1e-12
    assert starts[-1] == -128.0
    assert [(c.z_start, c.z_end) for c in cap] == [(0.0, 1.0), (1.0, 2.5)]
    for seg in soil:
        f = np.asarray(seg.heights)
        assert np.all(np.diff(np.concatenate([[0.0], f])) > 0) and f[-1] == 1.0
        assert seg.n >= s.sizing.min_layer_divisions
        dz = np.diff(np.concatenate([[seg.z_start], seg.levels()]))
        assert np.all(np.abs(dz) <= s.sizing.dz_max_deep * (1 + 1e-9))
        if seg.z_end >= -63.5:
            assert np.all(np.abs(dz) <= s.sizing.dz_max * (1 + 1e-9))
    # finer at the ground surface and at the toe than mid-shaft
    first = abs(soil[0].levels()[0])
    toe_seg = next(seg for seg in soil if abs(seg.z_end + 63.5) < 1e-12)
    toe_dz = abs(toe_seg.levels()[-1] - toe_seg.levels()[-2])
    mid_seg = next(seg for seg in soil if seg.z_start >= -30 >= seg.z_end)
    mid_dz = np.max(np.abs(np.diff(mid_seg.levels())))
    assert first <= s.sizing.dz_surface and toe_dz <= s.sizing.dz_toe * 1.05
    assert mid_dz > 3 * max(first, toe_dz)


def test_single_pile_helper():
    s = single_pile(diameter=0.6, length_in_soil=8.0, h=0.2)
    assert len(s.piles) == 1 and s.cap is None and len(s.layers) == 1
    x0, x1, y0, y1 = s.structured_region()
    assert x1 - x0 == pytest.approx(0.6 + 2 * s.sizing.near_field_margin)
    assert math.isclose(s.sizing.h_pile, 0.2)
