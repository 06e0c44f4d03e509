"""Geometry specification: frozen, typed, validated data that the gmsh builders consume.

A spec is cheap, picklable data (no gmsh, no DOLFINx). Coordinates and lengths are in metres.
Conventions: the plan view is centred at x = y = 0, the ground surface is the plane z = 0, z
points up, the soil occupies ``-depth <= z <= 0`` and the cap sits on the ground surface
(``0 <= z <= cap.thickness``). A pile with ``length_in_soil = L`` and ``embedment = e`` spans
``-L <= z <= e`` (its top ``e`` metres lie inside the cap).

:func:`pilegroup.geometry.adapter.geometry_spec` turns a scenario into a :class:`GeometrySpec`;
:func:`pier667_default` and :func:`single_pile` build specs directly for tests and benchmarks.
"""

from __future__ import annotations

import hashlib
import json
import math
from dataclasses import asdict, dataclass, field, replace
from typing import Any

from pilegroup.errors import ScenarioError
from pilegroup.geometry import symmetry as sym
from pilegroup.geometry.groups import MAX_LAYERS, MAX_PILES
from pilegroup.validate import (
    require_finite,
    require_in_range,
    require_non_negative,
    require_one_of,
    require_positive,
)

__all__ = [
    "BlockSpec",
    "CapSpec",
    "GeometrySpec",
    "LayerSpec",
    "MeshSizing",
    "PileSpec",
    "grid_piles",
    "pier667_default",
    "single_pile",
]

#: Paper Table 1 (Li et al. 2019): layer names and thicknesses (m); layer 10 goes to the bottom.
PIER667_LAYERS: tuple[tuple[str, float | None], ...] = (
    ("Clay", 0.4),
    ("Mud", 19.3),
    ("Mucky clay", 12.4),
    ("Silty clay", 5.0),
    ("Silt", 4.8),
    ("Silty clay", 2.7),
    ("Silty clay", 7.2),
    ("Gravel soil", 8.2),
    ("Silty clay", 4.3),
    ("Silty clay", None),
)

_REL = 1e-9  # relative tolerance for geometric coincidence checks


@dataclass(frozen=True)
class BlockSpec:
    """The soil block: ``size_x`` x ``size_y`` in plan (m, centred at x = y = 0), ``depth`` (m)."""

    size_x: float
    size_y: float
    depth: float

    def __post_init__(self) -> None:
        require_positive("block.size_x", self.size_x, "m")
        require_positive("block.size_y", self.size_y, "m")
        require_positive("block.depth", self.depth, "m")


@dataclass(frozen=True)
class LayerSpec:
    """A horizontal soil layer, listed from the ground surface down.

    Attributes:
        name: free text (e.g. ``"Mud"``); the cell group is :func:`~.groups.soil_layer` of the
            layer's 1-based index.
        thickness: m; ``None`` only for the last layer, which then extends to the block bottom.
        dz_max: optional cap (m) on the vertical element size inside this layer.
    """

    name: str
    thickness: float | None
    dz_max: float | None = None

    def __post_init__(self) -> None:
        if not isinstance(self.name, str) or not self.name.strip():
            raise ScenarioError("layer.name", self.name, "must be a non-empty string")
        if self.thickness is not None:
            require_positive(f"layer[{self.name}].thickness", self.thickness, "m")
        if self.dz_max is not None:
            require_positive(f"layer[{self.name}].dz_max", self.dz_max, "m")


@dataclass(frozen=True)
class PileSpec:
    """A vertical circular pile: centre ``(x, y)`` (m), ``diameter`` (m).

    ``length_in_soil`` (m) below the ground surface, ``embedment`` (m) above it inside the cap.
    """

    x: float
    y: float
    diameter: float
    length_in_soil: float
    embedment: float = 0.0

    def __post_init__(self) -> None:
        require_finite("pile.x", self.x, "m")
        require_finite("pile.y", self.y, "m")
        require_positive("pile.diameter", self.diameter, "m")
        require_positive("pile.length_in_soil", self.length_in_soil, "m")
        require_non_negative("pile.embedment", self.embedment, "m")

    @property
    def radius(self) -> float:
        """Radius (m)."""
        return 0.5 * self.diameter


@dataclass(frozen=True)
class CapSpec:
    """Rectangular cap ``[x_min, x_max] x [y_min, y_max]`` (m), bottom on z = 0, ``thickness`` m."""

    x_min: float
    x_max: float
    y_min: float
    y_max: float
    thickness: float

    def __post_init__(self) -> None:
        for key in ("x_min", "x_max", "y_min", "y_max"):
            require_finite(f"cap.{key}", getattr(self, key), "m")
        if self.x_max <= self.x_min:
            raise ScenarioError("cap.x_max", self.x_max, f"must be > cap.x_min = {self.x_min:g}",
                                "m")
        if self.y_max <= self.y_min:
            raise ScenarioError("cap.y_max", self.y_max, f"must be > cap.y_min = {self.y_min:g}",
                                "m")
        require_positive("cap.thickness", self.thickness, "m")

    @classmethod
    def centred(cls, size_x: float, size_y: float, thickness: float) -> CapSpec:
        """A cap of ``size_x`` x ``size_y`` (m) centred on the plan origin."""
        return cls(-size_x / 2, size_x / 2, -size_y / 2, size_y / 2, thickness)


@dataclass(frozen=True)
class MeshSizing:
    """Mesh-size controls (all in m unless stated).

    Plan view:
        h_pile: ``h``, the paper's mesh-study parameter: size of the first soil element next to
            each pile surface (radial), and the circumferential size wherever it is finer than
            the ``n_circ_min`` limit.
        n_circ_min: minimum number of element edges around a pile circumference (multiple of 4,
            -); 32 keeps the polygonal cross-section within 0.65 % of pi d^2 / 4 (28: 0.84 %).
        near_field_margin: half-width of the structured block around a pile when there is no
            cap (the cap outline bounds the structured block otherwise).
        h_far: far-field size reached away from the piles.
        growth: plan size growth ratio per element in the far field (-), > 1.

    Vertical (extrusion):
        dz_surface: vertical size at the ground surface; dz_toe: at each pile toe.
        dz_max: largest vertical size between the ground and the deepest toe.
        dz_max_deep: largest vertical size below the deepest toe.
        dz_growth: growth ratio of vertical sizes away from the surface and toes (-), > 1.
        dz_cap: vertical size inside the cap.
        min_layer_divisions: at least this many elements across every vertical segment (-).
    """

    h_pile: float = 1.0
    n_circ_min: int = 32
    near_field_margin: float = 1.5
    h_far: float = 8.0
    growth: float = 1.3
    dz_surface: float = 0.5
    dz_toe: float = 0.5
    dz_max: float = 2.0
    dz_max_deep: float = 4.0
    dz_growth: float = 1.2
    dz_cap: float = 0.5
    min_layer_divisions: int = 2

    def __post_init__(self) -> None:
        for key in ("h_pile", "near_field_margin", "h_far", "dz_surface", "dz_toe", "dz_max",
                    "dz_max_deep", "dz_cap"):
            require_positive(f"sizing.{key}", getattr(self, key), "m")
        if self.h_far < self.h_pile:
            raise ScenarioError("sizing.h_far", self.h_far,
                                f"must be >= sizing.h_pile = {self.h_pile:g}", "m")
        for key in ("growth", "dz_growth"):
            require_in_range(f"sizing.{key}", getattr(self, key), 1.0, 2.0, "-", lo_open=True)
        if (not isinstance(self.n_circ_min, int) or self.n_circ_min < 8
                or self.n_circ_min % 4 != 0):
            raise ScenarioError("sizing.n_circ_min", self.n_circ_min,
                                "must be an integer multiple of 4, >= 8", "-")
        if not isinstance(self.min_layer_divisions, int) or self.min_layer_divisions < 1:
            raise ScenarioError("sizing.min_layer_divisions", self.min_layer_divisions,
                                "must be an integer >= 1", "-")


@dataclass(frozen=True)
class GeometrySpec:
    """Everything the gmsh builder needs: block, layers (top down), piles, optional cap, sizing.

    Piles are numbered 1..n in the order given (physical groups ``pile_{i}``). Without a cap,
    every pile must have ``embedment == 0`` (its head is on the ground surface).

    ``levels``: depths (m, positive down) of horizontal mesh surfaces in the soil besides the
    layer boundaries and pile toes (the water table: its cells above and below keep their
    layer's group).

    ``symmetry`` reduces the model to the part with ``x >= 0`` (``half_x``), ``y >= 0``
    (``half_y``) or both (``quarter``); the geometry must be mirror-symmetric about each plane
    it cuts at (:mod:`pilegroup.geometry.symmetry`). ``piles`` always lists the full model's
    piles: the mesh holds the kept ones (:meth:`kept_piles`) under their full-model numbers,
    a pile on a plane cut to :meth:`pile_fraction` of it; :meth:`mirror_of` maps every pile to
    its kept mirror image.
    """

    block: BlockSpec
    layers: tuple[LayerSpec, ...]
    piles: tuple[PileSpec, ...]
    cap: CapSpec | None = None
    sizing: MeshSizing = field(default_factory=MeshSizing)
    symmetry: sym.Symmetry = "none"
    levels: tuple[float, ...] = ()

    def __post_init__(self) -> None:
        object.__setattr__(self, "layers", tuple(self.layers))
        object.__setattr__(self, "piles", tuple(self.piles))
        object.__setattr__(self, "levels", tuple(float(v) for v in self.levels))
        for i, v in enumerate(self.levels):
            require_in_range(f"levels[{i}]", v, 0.0, self.block.depth, "m", lo_open=True,
                             hi_open=True)
        for check in (self._check_layers, self._check_piles, self._check_symmetry):
            check()

    # -- validation ---------------------------------------------------------------------------
    def _check_layers(self) -> None:
        if not self.layers:
            raise ScenarioError("layers", [], "must list at least one layer")
        if len(self.layers) > MAX_LAYERS:
            raise ScenarioError("layers", len(self.layers), f"at most {MAX_LAYERS} layers", "-")
        for j, lay in enumerate(self.layers[:-1]):
            if lay.thickness is None:
                raise ScenarioError(f"layers[{j}].thickness", None,
                                    "only the last layer may omit its thickness", "m")
        depth = self.block.depth
        z = 0.0
        for j, lay in enumerate(self.layers):
            if lay.thickness is not None:
                z += lay.thickness
                if z > depth * (1 + _REL) or (j < len(self.layers) - 1
                                              and z >= depth * (1 - _REL)):
                    raise ScenarioError(f"layers[{j}].thickness", lay.thickness,
                                        f"layers reach {z:g} m, deeper than block.depth = "
                                        f"{depth:g} m (the last layer must reach the bottom)",
                                        "m")
        last = self.layers[-1]
        if last.thickness is not None and abs(z - depth) > _REL * depth:
            raise ScenarioError(f"layers[{len(self.layers) - 1}].thickness", last.thickness,
                                f"thicknesses sum to {z:g} m, must equal block.depth = "
                                f"{depth:g} m (or omit the last thickness)", "m")

    def _check_piles(self) -> None:
        b = self.block
        if not self.piles:
            raise ScenarioError("piles", [], "must list at least one pile")
        if len(self.piles) > MAX_PILES:
            raise ScenarioError("piles", len(self.piles), f"at most {MAX_PILES} piles", "-")
        for i, p in enumerate(self.piles):
            if p.length_in_soil >= b.depth * (1 - _REL):
                raise ScenarioError(f"piles[{i}].length_in_soil", p.length_in_soil,
                                    f"must be < block.depth = {b.depth:g}", "m")
            if self.cap is None:
                if p.embedment != 0.0:
                    raise ScenarioError(f"piles[{i}].embedment", p.embedment,
                                        "must be 0 without a cap", "m")
            else:
                c = self.cap
                if p.embedment >= c.thickness * (1 - _REL):
                    raise ScenarioError(f"piles[{i}].embedment", p.embedment,
                                        f"must be < cap.thickness = {c.thickness:g}", "m")
                if not (c.x_min < p.x - p.radius and p.x + p.radius < c.x_max
                        and c.y_min < p.y - p.radius and p.y + p.radius < c.y_max):
                    raise ScenarioError(f"piles[{i}]", (p.x, p.y),
                                        "pile cross-section must lie strictly inside the cap", "m")
            for k in range(i):
                q = self.piles[k]
                dist = math.hypot(p.x - q.x, p.y - q.y)
                if dist <= 0.5 * (p.diameter + q.diameter):
                    raise ScenarioError(f"piles[{i}]", (p.x, p.y),
                                        f"overlaps pile {k + 1}: centre distance {dist:g} m must"
                                        " exceed the mean of their diameters,"
                                        f" {0.5 * (p.diameter + q.diameter):g} m", "m")
        x0, x1, y0, y1 = self.structured_region()
        if not (-b.size_x / 2 < x0 and x1 < b.size_x / 2 and -b.size_y / 2 < y0
                and y1 < b.size_y / 2):
            raise ScenarioError("block", (b.size_x, b.size_y),
                                f"the cap / pile region [{x0:g}, {x1:g}] x [{y0:g}, {y1:g}] m "
                                "must lie strictly inside the block plan", "m")

    def _check_symmetry(self) -> None:
        require_one_of("numerics.symmetry", self.symmetry, sym.MODES)
        for axis in self.cut_planes():
            why = sym.asymmetry(self.piles, self.cap, axis)
            if why is not None:
                raise ScenarioError("numerics.symmetry", self.symmetry,
                                    f"cuts at {axis} = 0, but the geometry is not mirror-"
                                    f"symmetric about it: {why}; use 'none' or a plane the "
                                    "geometry is symmetric about")

    # -- symmetry -------------------------------------------------------------------------------
    def symmetry_planes(self) -> tuple[str, ...]:
        """Planes the geometry is mirror-symmetric about: ``"x"`` (x = 0), ``"y"`` (y = 0)."""
        return tuple(a for a in ("x", "y") if sym.asymmetry(self.piles, self.cap, a) is None)

    def cut_planes(self) -> tuple[str, ...]:
        """Planes the model is cut at by ``symmetry`` (``()`` for the full model)."""
        return sym.PLANES[self.symmetry]

    def plan_bounds(self) -> tuple[float, float, float, float]:
        """Plan rectangle (x0, x1, y0, y1) m of the modelled block: all, a half or a quarter."""
        bx, by = self.block.size_x / 2, self.block.size_y / 2
        planes = self.cut_planes()
        return (0.0 if "x" in planes else -bx, bx, 0.0 if "y" in planes else -by, by)

    def pile_fraction(self, i: int) -> float:
        """Fraction of pile ``i`` (1-based, full-model number) in the mesh: 1, 1/2, 1/4 or 0."""
        return sym.meshed_fraction(self.piles[i - 1], self.cut_planes())

    def kept_piles(self) -> tuple[int, ...]:
        """Numbers (1-based, full model) of the piles in the mesh, whole or cut."""
        return tuple(i for i, p in enumerate(self.piles, start=1)
                     if sym.is_kept(p, self.cut_planes()))

    def mirror_of(self) -> dict[int, int]:
        """Every pile number of the full model -> its mirror image among :meth:`kept_piles`.

        Kept piles map to themselves; with ``symmetry = "none"`` every pile does.
        """
        return sym.mirror_map(self.piles, self.cut_planes())

    # -- derived data ---------------------------------------------------------------------------
    def structured_region(self) -> tuple[float, float, float, float]:
        """Plan rectangle (m) meshed with structured blocks (x0, x1, y0, y1).

        The cap outline, or without a cap the bounding box of the pile circles widened by
        ``sizing.near_field_margin``.
        """
        if self.cap is not None:
            c = self.cap
            return (c.x_min, c.x_max, c.y_min, c.y_max)
        m = self.sizing.near_field_margin
        return (min(p.x - p.radius for p in self.piles) - m,
                max(p.x + p.radius for p in self.piles) + m,
                min(p.y - p.radius for p in self.piles) - m,
                max(p.y + p.radius for p in self.piles) + m)

    def layer_bottoms(self) -> tuple[float, ...]:
        """Levels z (m, negative) of the bottom of every layer, top down; the last is ``-depth``."""
        z, out = 0.0, []
        for lay in self.layers[:-1]:
            z -= float(lay.thickness)  # type: ignore[arg-type]
            out.append(z)
        out.append(-self.block.depth)
        return tuple(out)

    def layer_of_depth(self, z: float) -> int:
        """1-based index of the layer that contains the level z (m); boundaries go up."""
        for j, zb in enumerate(self.layer_bottoms()):
            if z > zb + 1e-12:
                return j + 1
        return len(self.layers)

    def with_h(self, h: float) -> GeometrySpec:
        """The same geometry with ``sizing.h_pile = h`` (m)."""
        return replace(self, sizing=replace(self.sizing, h_pile=h))

    def to_dict(self) -> dict[str, Any]:
        """Plain-data form (JSON-ready)."""
        return asdict(self)

    def cache_key(self, extra: str = "") -> str:
        """Hex digest identifying the geometry and mesh parameters (plus ``extra``).

        ``symmetry`` enters the key only when it reduces the model: the full model's key is that
        of its geometry and sizing alone; ``levels`` only when there are any.
        """
        data = self.to_dict()
        if self.symmetry == "none":
            del data["symmetry"]
        if not self.levels:
            del data["levels"]
        payload = json.dumps(data, sort_keys=True, default=repr) + "|" + extra
        return hashlib.sha256(payload.encode()).hexdigest()[:20]

    @classmethod
    def pier667_default(cls, h: float = 1.0, **sizing: float) -> GeometrySpec:
        """Shorthand for :func:`pier667_default`."""
        return pier667_default(h, **sizing)


def grid_piles(nx: int, ny: int, sx: float, sy: float, diameter: float, length_in_soil: float,
               embedment: float = 0.0) -> tuple[PileSpec, ...]:
    """An ``nx`` x ``ny`` grid of piles centred on the origin, spacing ``sx``, ``sy`` (m).

    Numbered row by row, x fastest, from 1 (the scenario model's convention).
    """
    return tuple(PileSpec((i - (nx - 1) / 2) * sx, (j - (ny - 1) / 2) * sy, diameter,
                          length_in_soil, embedment)
                 for j in range(ny) for i in range(nx))


def pier667_default(h: float = 1.0, **sizing: float) -> GeometrySpec:
    """Pier 667 (paper Section 5, Table 1): 101 x 75 x 128 m block, Table-1 layers, 3 x 3 piles.

    Piles: d = 1.0 m, 63.5 m in soil, 1.0 m embedded in a 10.1 x 7.4 x 2.5 m cap. ASSUMPTION
    (Figure 9 is not in the text; same as the bundled scenario): spacing 3.5 m in x and 2.5 m in
    y, so pile centre to cap edge is 1.55 m (x) and 1.2 m (y), i.e. >= 1 d.
    ``h`` (m) is the pile-surface size; ``sizing`` overrides :data:`PIER667_SIZING` and the
    other :class:`MeshSizing` fields.
    """
    return GeometrySpec(
        block=BlockSpec(101.0, 75.0, 128.0),
        layers=tuple(LayerSpec(n, t) for n, t in PIER667_LAYERS),
        piles=grid_piles(3, 3, 3.5, 2.5, 1.0, 63.5, 1.0),
        cap=CapSpec.centred(10.1, 7.4, 2.5),
        sizing=MeshSizing(h_pile=h, **{**PIER667_SIZING, **sizing}),
    )


#: The pier's default sizing (also in model/scenarios/pier667.toml): 28 edges around a pile
#: (cross-section area within 0.84 % of pi d^2/4), far field growing to 16 m, element layers
#: from 1 m at the surface and the toes to 6 m (15 m below the toes): 73,064 hexahedra at
#: h = 1 m, 18,266 in the quarter model (the paper's coarsest mesh: 57,108), so that the
#: 317-day run fits the time budget.
PIER667_SIZING: dict[str, float] = {
    "n_circ_min": 28, "h_far": 16.0, "growth": 1.6, "dz_surface": 1.0, "dz_toe": 1.0,
    "dz_max": 6.0, "dz_max_deep": 15.0, "dz_growth": 1.4, "dz_cap": 1.5,
}


def single_pile(diameter: float = 1.0, length_in_soil: float = 10.0, size_x: float = 20.0,
                size_y: float | None = None, depth: float = 20.0, h: float = 0.5,
                layer_name: str = "soil", **sizing: float) -> GeometrySpec:
    """One pile at the origin in one homogeneous layer, no cap (head on the ground surface).

    Lengths in m; ``sizing`` overrides :class:`MeshSizing` fields (e.g. ``h_far``).
    """
    sizing.setdefault("h_far", max(h, min(4.0, size_x / 5)))
    return GeometrySpec(
        block=BlockSpec(size_x, size_x if size_y is None else size_y, depth),
        layers=(LayerSpec(layer_name, None),),
        piles=(PileSpec(0.0, 0.0, diameter, length_in_soil, 0.0),),
        cap=None,
        sizing=MeshSizing(h_pile=h, **sizing),
    )
