"""gmsh builder: cap, piles and layered soil block as an all-hexahedral, tagged mesh.

Construction (gmsh built-in "geo" kernel, lengths in m):

1. **Plan view (z = 0), all quadrilaterals** (:mod:`pilegroup.geometry.far_field`): o-grid
   cells around the piles in the structured region (the cap outline, or the piles plus a
   margin), an unstructured far field around it meshed once into quadrilaterals; a model of a
   mirror-symmetric layout is one part and its mirror images.
2. **Extrusion.** The whole plan is extruded down through every layer boundary, the pile toes
   and the bottom; the structured region is extruded up through the pile tops and the cap top.
   Each slab carries graded element heights (``vertical.py``) and ``recombine=True`` so quads
   become hexahedra. Node sharing at every slab and block interface makes the mesh conforming.

Physical groups: the names and fixed tag values of :mod:`pilegroup.geometry.groups` (as
``dolfinx.io.gmsh.model_to_mesh`` returns them). Shaft groups exist only for the layers a pile
reaches (Pier 667: toe at 63.5 m in layer 9, so 9 x 9 = 81 shaft groups). Interior facets
between two soil cells, two pile cells or two cap cells carry no tag.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable
from dataclasses import dataclass, field
from typing import Any

import gmsh
import numpy as np

from pilegroup.geometry.far_field import build_plan
from pilegroup.geometry.groups import (
    BOTTOM,
    CAP,
    CAP_BOTTOM,
    CAP_SIDE,
    CAP_TOP,
    GROUND,
    SIDES,
    SYM_PLANES,
    base,
    embed,
    head,
    layer_of,
    pile,
    pile_of,
    shaft,
    soil_layer,
    tag_of,
)
from pilegroup.geometry.plan import PlanSurface, circumferential_divisions
from pilegroup.geometry.spec import GeometrySpec
from pilegroup.geometry.vertical import Segment, vertical_segments

__all__ = ["GMSH_OPTIONS", "BuildResult", "build_gmsh_model"]

#: gmsh options the builder sets (single thread: the machines are shared).
GMSH_OPTIONS = {
    "General.NumThreads": 1,
    "Mesh.RecombinationAlgorithm": 1,
    "Mesh.MeshSizeExtendFromBoundary": 0,
    "Mesh.MeshSizeFromPoints": 0,
    "Mesh.MeshSizeFromCurvature": 0,
    "Mesh.ElementOrder": 1,
    # duplicates of the extruded entities are removed once, after all extrusions (much faster
    # than after every extrusion)
    "Geometry.AutoCoherence": 0,
}

#: gmsh volume tag -> cell group name (:mod:`pilegroup.geometry.groups`).
VolumeGroups = dict[int, str]


@dataclass
class BuildResult:
    """What :func:`build_gmsh_model` made (the mesh itself stays in the gmsh model).

    Attributes:
        cell_groups / facet_groups: physical name -> tag.
        n_hex: number of hexahedra; n_nodes: number of mesh nodes.
        min_sj: minimum scaled Jacobian over all hexahedra (gmsh "minSJ", -).
        n_plan_quads: quadrilaterals of the plan view (z = 0, soil side).
        n_vertical_soil / n_vertical_cap: element layers in the soil column / cap.
        timings: seconds for geometry, meshing, quality evaluation.
    """

    cell_groups: dict[str, int]
    facet_groups: dict[str, int]
    n_hex: int = 0
    n_nodes: int = 0
    min_sj: float = float("nan")
    n_plan_quads: int = 0
    n_circ: int = 0
    n_vertical_soil: int = 0
    n_vertical_cap: int = 0
    far_field_algorithm: int = 0
    far_field_min_sj: float = float("nan")
    far_field_pairs: int = 0
    timings: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready form."""
        return dict(self.__dict__)


# ------------------------------------------------------------------------------------------------
# extrusion
# ------------------------------------------------------------------------------------------------
def _extrude(surfaces: list[PlanSurface], seg: Segment, vol_group: VolumeGroups,
             group_of: Callable[[PlanSurface, Segment], str]) -> list[PlanSurface]:
    """Extrude ``surfaces`` through slab ``seg``; record each new volume's cell group."""
    dz = seg.z_end - seg.z_start
    out = gmsh.model.geo.extrude([(2, s.tag) for s in surfaces], 0.0, 0.0, dz,
                                 numElements=[1] * seg.n, heights=list(seg.heights),
                                 recombine=True)
    tops: list[PlanSurface] = []
    k = 0
    for s in surfaces:
        top, vol = out[k], out[k + 1]
        if top[0] != 2 or vol[0] != 3:
            raise RuntimeError("unexpected gmsh extrude output layout")
        vol_group[vol[1]] = group_of(s, seg)
        tops.append(PlanSurface(top[1], s.n_curves, s.pile, s.in_region))
        k += 2 + s.n_curves
    if k != len(out):
        raise RuntimeError(f"gmsh extrude returned {len(out)} entities, expected {k}")
    return tops


def _extrude_all(spec: GeometrySpec, surfaces: list[PlanSurface]
                 ) -> tuple[VolumeGroups, list[Segment], list[Segment]]:
    """Extrude the plan down through the soil and, in the structured region, up into the cap.

    Returns the cell group of every volume and the soil and cap slabs.
    """
    soil_segs, cap_segs = vertical_segments(spec)
    vol_group: VolumeGroups = {}
    tol_soil = 1e-9 * spec.block.depth
    tol_cap = 1e-9 * (spec.cap.thickness if spec.cap is not None else 0.0)

    def soil_group(s: PlanSurface, seg: Segment) -> str:
        if s.pile is not None and seg.z_end >= -spec.piles[s.pile - 1].length_in_soil - tol_soil:
            return pile(s.pile)
        return soil_layer(seg.layer)

    def cap_group(s: PlanSurface, seg: Segment) -> str:
        if s.pile is not None and seg.z_end <= spec.piles[s.pile - 1].embedment + tol_cap:
            return pile(s.pile)
        return CAP

    current = surfaces
    for seg in soil_segs:
        current = _extrude(current, seg, vol_group, soil_group)
    current = [s for s in surfaces if s.in_region]
    for seg in cap_segs:
        current = _extrude(current, seg, vol_group, cap_group)
    return vol_group, soil_segs, cap_segs


# ------------------------------------------------------------------------------------------------
# mesh
# ------------------------------------------------------------------------------------------------
def build_gmsh_model(spec: GeometrySpec, name: str = "pilegroup") -> BuildResult:
    """Build geometry, mesh and physical groups of ``spec`` in a new gmsh model ``name``.

    gmsh must be initialised by the caller; the model stays current so that it can be written or
    converted. Lengths in m. Raises ``RuntimeError`` if anything but hexahedra is produced.
    """
    t0 = time.perf_counter()
    for key, val in GMSH_OPTIONS.items():
        gmsh.option.setNumber(key, val)
    gmsh.model.add(name)
    plan = build_plan(spec)
    surfaces, far = plan.surfaces, plan.far
    vol_group, soil_segs, cap_segs = _extrude_all(spec, surfaces)
    gmsh.model.geo.removeAllDuplicates()
    gmsh.model.geo.synchronize()
    plan.embed()
    cell_groups, facet_groups = _physical_groups(spec, vol_group)
    t1 = time.perf_counter()

    res = BuildResult(cell_groups, facet_groups)
    res.far_field_algorithm, res.far_field_min_sj = far.algorithm, far.min_sj
    res.far_field_pairs = far.pairs
    gmsh.model.mesh.generate(3)
    plan.check()
    t2 = time.perf_counter()
    res.n_circ = circumferential_divisions(spec)
    res.n_vertical_soil = sum(s.n for s in soil_segs)
    res.n_vertical_cap = sum(s.n for s in cap_segs)
    _measure(res, surfaces)
    t3 = time.perf_counter()
    res.timings = {"geometry_s": t1 - t0, "mesh_s": t2 - t1, "quality_s": t3 - t2}
    return res


def _measure(res: BuildResult, surfaces: list[PlanSurface]) -> None:
    """Counts and minimum scaled Jacobian of the meshed model into ``res``.

    Raises ``RuntimeError`` if the 3D mesh holds anything but hexahedra.
    """
    etypes, etags, _ = gmsh.model.mesh.getElements(3)
    bad = [gmsh.model.mesh.getElementProperties(t)[0] for t in etypes if t != 5]
    if bad:
        counts = {gmsh.model.mesh.getElementProperties(t)[0]: len(e)
                  for t, e in zip(etypes, etags, strict=True)}
        raise RuntimeError(f"mesh is not all-hexahedral: {counts}")
    hexes = np.concatenate(etags) if len(etags) else np.zeros(0, dtype=np.uint64)
    res.n_hex = int(hexes.size)
    res.n_nodes = int(gmsh.model.mesh.getNodes()[0].size)
    q = gmsh.model.mesh.getElementQualities(hexes, "minSJ")
    res.min_sj = float(np.min(q))
    res.n_plan_quads = sum(len(t) for s in surfaces
                           for t in gmsh.model.mesh.getElements(2, s.tag)[1])


# ------------------------------------------------------------------------------------------------
# physical groups
# ------------------------------------------------------------------------------------------------
def _face_volumes(volumes: Iterable[int]) -> dict[int, list[int]]:
    """Every boundary surface of ``volumes`` -> the volumes it bounds."""
    face_vols: dict[int, list[int]] = {}
    for v in volumes:
        for _, f in gmsh.model.getBoundary([(3, v)], combined=False, oriented=False):
            face_vols.setdefault(abs(f), []).append(v)
    return face_vols


def _between(a: str, b: str, vertical: bool) -> str | None:
    """Facet group of a surface between cells of groups ``a`` and ``b``; ``None`` in a body."""
    piles = [i for i in (pile_of(a), pile_of(b)) if i is not None]
    layers = [j for j in (layer_of(a), layer_of(b)) if j is not None]
    if piles and layers:
        return shaft(piles[0], layers[0]) if vertical else base(piles[0])
    if CAP in (a, b) and layers:
        return CAP_BOTTOM
    if CAP in (a, b) and piles:
        return embed(piles[0])
    return None


def _boundary(spec: GeometrySpec, name: str, f: int, bbox: tuple[float, ...],
              tol: float) -> str:
    """Facet group of the outer surface ``f`` (bounding box ``bbox``) of a cell of ``name``."""
    b = spec.block
    xmin, ymin, zmin, xmax, ymax, zmax = bbox
    if zmax - zmin > tol:  # vertical
        for axis, lo, hi in (("x", xmin, xmax), ("y", ymin, ymax)):
            if axis in spec.cut_planes() and abs(lo) < tol and abs(hi) < tol:
                return SYM_PLANES[axis]
        if name == CAP:
            return CAP_SIDE
        offsets = (xmax + b.size_x / 2, xmin - b.size_x / 2, ymax + b.size_y / 2,
                   ymin - b.size_y / 2)
        for side, off in zip(SIDES, offsets, strict=True):
            if abs(off) < tol:
                return side
        raise RuntimeError(f"unclassified vertical boundary surface {f} ({name})")
    if abs(zmin + b.depth) < tol:
        return BOTTOM
    if name == CAP:
        return CAP_TOP
    if abs(zmax) < tol and layer_of(name) is not None:
        return GROUND
    i = pile_of(name)
    if abs(zmax) < tol and i is not None:
        return head(i)
    raise RuntimeError(f"unclassified horizontal boundary surface {f} ({name}, z={zmax})")


def _physical_groups(spec: GeometrySpec, vol_group: VolumeGroups
                     ) -> tuple[dict[str, int], dict[str, int]]:
    """Add the cell and facet physical groups; return their name -> tag tables."""
    b = spec.block
    tol = 1e-7 * max(b.size_x, b.size_y, b.depth)
    facets: dict[str, list[int]] = {}
    for f, vols in _face_volumes(vol_group).items():
        if len(vols) > 2:
            raise RuntimeError(f"surface {f} bounds {len(vols)} volumes")
        bbox = gmsh.model.getBoundingBox(2, f)
        names = [vol_group[v] for v in vols]
        group = (_between(*names, vertical=bbox[5] - bbox[2] > tol) if len(vols) == 2
                 else _boundary(spec, names[0], f, bbox, tol))
        if group is not None:
            facets.setdefault(group, []).append(f)
    cells: dict[str, list[int]] = {}
    for v, nm in vol_group.items():
        cells.setdefault(nm, []).append(v)
    cell_tags = {nm: tag_of(nm) for nm in cells}
    facet_tags = {nm: tag_of(nm) for nm in facets}
    for dim, groups, tags in ((3, cells, cell_tags), (2, facets, facet_tags)):
        for nm in sorted(groups, key=tags.__getitem__):
            gmsh.model.addPhysicalGroup(dim, sorted(groups[nm]), tags[nm], nm)
    return cell_tags, facet_tags
