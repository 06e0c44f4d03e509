"""The cell estimate before meshing (model/mesh_estimate.py) against the mesher itself.

The element layers follow the mesher's vertical rule exactly (``geometry/vertical.py``, pure
numpy: no gmsh); the plan quads are estimated within 0.8-1.1 times the meshed count on small
bundled meshes (docs/benchmarks.md, "Memory estimate before meshing", gives the wider table).
"""

import pytest

from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.geometry.convert import ensure_msh
from pilegroup.geometry.vertical import vertical_segments
from pilegroup.model import BUNDLED, load_scenario
from pilegroup.model.mesh_estimate import element_layers, plan_quads
from pilegroup.model.mirror import kept_fraction

VARIANTS = [(name, {}) for name in sorted(BUNDLED)] + [
    ("pier667", {"numerics.element": "Q1Q1"}),
    ("pier667", {"numerics.mesh.scale": 0.667}),
    ("pier667", {"site.water_table_depth_m": 2.0}),
    ("single_pile", {"numerics.element": "Q1Q1"}),
]


@pytest.mark.parametrize(("name", "sets"), VARIANTS)
def test_element_layers_are_the_meshers(name, sets):
    sc = load_scenario(name, sets)
    soil, cap = vertical_segments(resolve_geometry(sc).spec)
    assert element_layers(sc) == sum(seg.n for seg in soil + cap)


@pytest.mark.parametrize(("name", "sets"), [
    ("single_pile", {}), ("group3x3_downdrag", {}), ("pier667", {}),
    ("single_pile", {"numerics.element": "Q1Q1"})])
def test_plan_quads_near_the_meshed_count(name, sets, tmp_path):
    """Measured 0.91 / 1.03 / 1.02 / 0.90 (2026-11-29)."""
    sc = load_scenario(name, sets)
    _, info = ensure_msh(resolve_geometry(sc).spec, tmp_path)
    ratio = plan_quads(sc) * kept_fraction(sc) / info["n_plan_quads"]
    assert 0.8 <= ratio <= 1.1, ratio
