"""Mesh-group names: every formatter's name parses back to its numbers, and nothing else does."""

import pytest

from pilegroup.geometry import groups


@pytest.mark.parametrize("i, j", [(1, 1), (9, 10), (12, 3)])
def test_names_round_trip(i, j):
    assert groups.layer_of(groups.soil_layer(j)) == j
    assert groups.pile_of(groups.pile(i)) == i
    assert groups.shaft_of(groups.shaft(i, j)) == (i, j)
    assert groups.base_of(groups.base(i)) == i
    assert groups.head_of(groups.head(i)) == i
    assert groups.is_structure(groups.pile(i)) and groups.is_structure(groups.CAP)
    assert not groups.is_structure(groups.soil_layer(j))
    assert groups.is_interface(groups.shaft(i, j)) and groups.is_interface(groups.base(i))
    assert groups.shaft_tag(i, j) == 1000 * i + j and groups.pile_tag(i) == 100 + i


@pytest.mark.parametrize("name", ["base_1", "pile", "soil_layer_", "shaft_p1", "head_p",
                                  "cap_top", "pile_1x", "xsoil_layer_01"])
def test_other_names_do_not_parse(name):
    parsed = (groups.layer_of(name), groups.pile_of(name), groups.shaft_of(name),
              groups.base_of(name), groups.head_of(name))
    assert parsed == (None,) * 5
    assert not groups.is_interface(name)


def test_heads_keeps_order():
    assert groups.heads(["cap_top", "head_p2", "bottom", "head_p1"]) == ["head_p2", "head_p1"]
