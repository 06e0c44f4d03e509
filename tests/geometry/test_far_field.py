"""geometry/far_field.py: the far field and the plan of a model as a part and its mirror images.

Pier 667 must mesh at every size of the paper's study (h = 1.0 / 0.8 / 0.6 / 0.3 / 0.1 m) as the
quarter model and as the full model, all hexahedra, the full model exactly four quarters; the
far field of the part is all convex quadrilaterals covering exactly the part's plan outside the
structured region (straight outlines, so the areas are exact).
"""

import dataclasses
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from pilegroup.geometry import spec as gs
from pilegroup.geometry.convert import gmsh_session
from pilegroup.geometry.far_field import far_field, mirror_signs
from pilegroup.geometry.pier import build_gmsh_model
from pilegroup.geometry.quadfix import element_quality

PAPER_SIZES = (1.0, 0.8, 0.6, 0.3, 0.1)


def _cells(spec):
    """(hexahedra, minimum scaled Jacobian) of ``spec`` built in gmsh (no DOLFINx).

    Checks that the cells fill the modelled block and cap: every face is planar, so their
    volumes add up to it exactly.
    """
    with gmsh_session() as gmsh:
        gmsh.model.add("test")
        res = build_gmsh_model(spec, "test")
        tags, xyz, _ = gmsh.model.mesh.getNodes()
        _, nodes = gmsh.model.mesh.getElementsByType(5)  # 8-node hexahedra
        gmsh.model.remove()
    x = np.zeros((int(tags.max()) + 1, 3))
    x[tags.astype(int)] = xyz.reshape(-1, 3)
    v = x[nodes.astype(int).reshape(-1, 8)]
    volume = 0.0  # six tetrahedra around the diagonal 0-6: exact for planar faces
    for a, b in ((1, 2), (2, 3), (3, 7), (7, 4), (4, 5), (5, 1)):
        volume += np.linalg.det(np.stack([v[:, a] - v[:, 0], v[:, b] - v[:, 0],
                                          v[:, 6] - v[:, 0]], axis=1)) / 6.0
    volume = abs(volume).sum()
    x0, x1, y0, y1 = spec.plan_bounds()
    want = (x1 - x0) * (y1 - y0) * spec.block.depth
    if spec.cap is not None:
        c = spec.cap
        want += ((c.x_max - max(c.x_min, x0)) * (c.y_max - max(c.y_min, y0)) * c.thickness)
    assert volume == pytest.approx(want, rel=1e-9)
    return res.n_hex, res.min_sj


def _quarter_and_full(h):
    full = gs.pier667_default(h)
    (n_q, sj_q), (n_f, sj_f) = (_cells(dataclasses.replace(full, symmetry="quarter")),
                                _cells(full))
    assert n_f == 4 * n_q
    assert min(sj_q, sj_f) > 0.2


def test_pier_meshes_at_0_1_m_as_quarter_and_full():
    _quarter_and_full(0.1)


@pytest.mark.slow
@pytest.mark.parametrize("h", PAPER_SIZES[:-1])
def test_pier_meshes_at_the_other_paper_sizes(h):
    _quarter_and_full(h)


def test_mesh_command_at_0_1_m(tmp_path):
    r = subprocess.run([str(Path(sys.executable).parent / "pilegroup"), "mesh", "pier667",
                        "--mesh-size", "0.1", "--no-png", "--out", str(tmp_path / "out")],
                       capture_output=True, text=True, timeout=600,
                       env={**os.environ, "PILEGROUP_MESH_CACHE": str(tmp_path / "cache")})
    assert r.returncode == 0, r.stderr[-2000:]
    s = json.loads((tmp_path / "out" / "mesh_summary.json").read_text())
    assert s["symmetry"] == "quarter" and s["cells"] == s["hexahedra_gmsh"] > 0


def _mini(piles, shift=0.0):
    """A 6 x 5 m cap over ``piles`` (d = 0.8 m) in a 24 x 20 x 20 m block, moved ``shift`` m
    along x."""
    return gs.GeometrySpec(
        block=gs.BlockSpec(24.0, 20.0, 20.0),
        layers=(gs.LayerSpec("a", 1.0), gs.LayerSpec("b", 6.0), gs.LayerSpec("c", None)),
        piles=tuple(gs.PileSpec(x + shift, y, 0.8, 9.0, 0.5) for x, y in piles),
        cap=gs.CapSpec(-3.0 + shift, 3.0 + shift, -2.5, 2.5, 1.5),
        sizing=gs.MeshSizing(h_pile=0.5, h_far=4.0, dz_max=2.0, dz_max_deep=4.0))


@pytest.mark.parametrize("piles, shift, planes", [
    (((-1.5, -1.25), (1.5, -1.25), (-1.5, 1.25)), 0.0, ()),  # no plane: a far field with a hole
    (((-1.5, -1.25), (1.5, -1.25), (-1.5, 1.25), (1.5, 1.25)), 0.4, ("y",)),
])
def test_asymmetric_layouts_mesh(piles, shift, planes):
    spec = _mini(piles, shift)
    assert spec.symmetry_planes() == planes
    n, sj = _cells(spec)
    assert n > 0 and sj > 0.2
    if planes:
        assert 2 * _cells(dataclasses.replace(spec, symmetry="half_y"))[0] == n


@pytest.mark.parametrize("h", [1.0, 0.1])
def test_far_field_covers_the_part_outside_the_cap(h):
    spec = dataclasses.replace(gs.pier667_default(h), symmetry="quarter")
    with gmsh_session():
        far = far_field(spec)
    assert far.quads.shape[1] == 4 and far.min_sj > 0.2
    assert min(element_quality(far.xy, q) for q in far.quads) == pytest.approx(far.min_sj)
    assert far.xy.min() >= 0.0
    b, c = spec.block, spec.cap
    area = sum(0.5 * abs(sum(far.xy[q[k], 0] * far.xy[q[(k + 1) % 4], 1]
                             - far.xy[q[(k + 1) % 4], 0] * far.xy[q[k], 1] for k in range(4)))
               for q in far.quads)
    assert area == pytest.approx(b.size_x * b.size_y / 4 - c.x_max * c.y_max, rel=1e-12)


def test_mirror_signs_make_the_model_from_the_part():
    pier = gs.pier667_default(1.0)
    assert mirror_signs(pier) == [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]
    assert mirror_signs(dataclasses.replace(pier, symmetry="quarter")) == [(1.0, 1.0)]
    assert mirror_signs(dataclasses.replace(pier, symmetry="half_x")) == [(1.0, 1.0),
                                                                           (1.0, -1.0)]
    c = pier.cap
    shifted = dataclasses.replace(  # the group and cap moved 0.4 m along x
        pier, piles=tuple(dataclasses.replace(p, x=p.x + 0.4) for p in pier.piles),
        cap=dataclasses.replace(c, x_min=c.x_min + 0.4, x_max=c.x_max + 0.4))
    assert shifted.symmetry_planes() == ("y",)
    assert mirror_signs(shifted) == [(1.0, 1.0), (1.0, -1.0)]
