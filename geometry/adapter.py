"""Scenario -> :class:`~pilegroup.geometry.spec.GeometrySpec` (the one place that maps them).

``numerics.symmetry`` is resolved here. A scenario's layers are horizontal and its block is
centred with the same supports on opposite sides, so the model is mirror-symmetric about a
plane exactly when its pile layout, cap and loads are (:func:`GeometrySpec.symmetry_planes
<pilegroup.geometry.spec.GeometrySpec.symmetry_planes>` and
:func:`pilegroup.model.mirror.load_asymmetry`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, replace

from pilegroup.errors import ScenarioError, entry_name
from pilegroup.geometry import spec
from pilegroup.geometry import symmetry as sym
from pilegroup.geometry.plan import cell_grid
from pilegroup.model import Scenario
from pilegroup.model.mirror import load_asymmetry


def _full_spec(sc: Scenario, mesh_size: float | None) -> spec.GeometrySpec:
    """The whole model of scenario ``sc`` (``mesh_size`` overrides h, m).

    Every pile keeps its own diameter and length in soil (``sc.piles.diameters``,
    ``sc.piles.lengths``) and the scenario's numbering; the embedment is the same for all. A
    water table below the ground surface is a mesh surface (``levels``): the unit weight and
    the drained boundary change there (docs/model.md, "The ground at rest").
    """
    m = sc.numerics.mesh
    sizing = spec.MeshSizing(
        h_pile=m.size_m if mesh_size is None else mesh_size,
        n_circ_min=m.n_circ_min,
        h_far=max(m.far_field_size_m, m.size_m if mesh_size is None else mesh_size),
        growth=m.growth,
        dz_surface=m.dz_surface_m,
        dz_toe=m.dz_toe_m,
        dz_max=m.dz_max_m,
        dz_max_deep=m.dz_max_deep_m,
        dz_growth=m.dz_growth,
        dz_cap=m.dz_cap_m,
        min_layer_divisions=m.min_layer_divisions,
    )
    p = sc.piles
    cap = None if sc.cap is None else spec.CapSpec.centred(sc.cap.size_x_m, sc.cap.size_y_m,
                                                            sc.cap.thickness_m)
    return spec.GeometrySpec(
        block=spec.BlockSpec(sc.site.size_x_m, sc.site.size_y_m, sc.site.depth_m),
        layers=tuple(spec.LayerSpec(lay.name, lay.thickness_m) for lay in sc.layers),
        piles=tuple(spec.PileSpec(x, y, d, length, p.embedment_m)
                    for (x, y), d, length in zip(p.xy, p.diameters, p.lengths, strict=True)),
        cap=cap,
        sizing=sizing,
        levels=(wt,) if (wt := sc.site.water_table_depth_m) > 0.0 else (),
    )


def _resolve(sc: Scenario, full: spec.GeometrySpec) -> tuple[sym.Symmetry, str]:
    """(mode, reason) of ``numerics.symmetry`` for the whole model ``full`` and its loads.

    Raises :class:`~pilegroup.errors.ScenarioError` naming ``numerics.symmetry`` when an
    explicit mode cuts at a plane the model or its loads are not symmetric about.
    """
    asked = sc.numerics.symmetry
    why = {a: sym.asymmetry(full.piles, full.cap, a) or load_asymmetry(sc, a)
           for a in ("x", "y")}
    planes = tuple(a for a in ("x", "y") if why[a] is None)
    whys = [f"{a} = 0 ({why[a]})" for a in ("x", "y") if a not in planes]
    if asked == "auto":
        mode = sym.mode_of(planes)
        if not planes:
            return mode, "auto: the full model, not mirror-symmetric about " + " nor ".join(whys)
        reason = (f"auto: pile layout, cap, block and load mirror-symmetric about "
                  f"{sym.describe_planes(planes)}")
        return mode, reason + "".join(f"; not about {w}" for w in whys)
    replace(full, symmetry=asked)  # validates the geometry: the error names numerics.symmetry
    for a in sym.PLANES[asked]:
        if why[a] is not None:
            raise ScenarioError("numerics.symmetry", asked,
                                f"cuts at {a} = 0, but the load is not mirror-symmetric about "
                                f"it: {why[a]}; allowed: 'auto' or a mode cutting only at "
                                "planes of symmetry")
    if asked == "none":
        return "none", "numerics.symmetry = 'none': the full model"
    return asked, (f"numerics.symmetry = '{asked}': pile layout, cap, block and load "
                   f"mirror-symmetric about {sym.describe_planes(sym.PLANES[asked])}")


@dataclass(frozen=True)
class ResolvedGeometry:
    """A scenario's geometry, resolved once per run and handed to every layer below.

    ``spec`` is the geometry with the model part ``numerics.symmetry`` resolves to (its
    ``symmetry``), ``reason`` says why in words (for the run summary), e.g. ``"auto: pile
    layout, cap, block and load mirror-symmetric about x = 0 and y = 0"``.
    """

    spec: spec.GeometrySpec
    reason: str

    @property
    def symmetry(self) -> str:
        """The model part: ``none``, ``quarter``, ``half_x`` or ``half_y``."""
        return self.spec.symmetry

    @property
    def kept_fraction(self) -> float:
        """Fraction of the whole model the mesh holds: 1, 1/2 or 1/4."""
        return 0.5 ** len(self.spec.cut_planes())


def resolve_geometry(sc: Scenario, mesh_size: float | None = None) -> ResolvedGeometry:
    """Scenario ``sc``'s geometry with its symmetry resolved (``mesh_size`` overrides h, m).

    ``numerics.symmetry = "auto"`` picks ``quarter`` when the scenario is mirror-symmetric about
    x = 0 and y = 0, ``half_x`` / ``half_y`` when about one of them, else ``none``; an explicit
    value must be one the scenario allows (else :class:`~pilegroup.errors.ScenarioError` naming
    ``numerics.symmetry``).

    Every rule of the geometry that needs no mesh is checked here, so that ``pilegroup scenario
    validate`` and a run refuse a layout alike before meshing: the
    :class:`~pilegroup.geometry.spec.GeometrySpec` rules and the structured cells of the plan
    (:func:`pilegroup.geometry.plan.cell_grid`: a pile too close to a neighbouring pile row or
    column). A refusal names the scenario key that places the pile (:func:`_scenario_key`).
    """
    try:
        full = _full_spec(sc, mesh_size)
        mode, reason = _resolve(sc, full)
        cell_grid(full)
    except ScenarioError as exc:
        raise _scenario_key(sc, exc) from None
    return ResolvedGeometry(full if mode == "none" else replace(full, symmetry=mode), reason)


_SPEC_PILE = re.compile(r"piles\[(\d+)\](\.length_in_soil|\.embedment)?")


def _scenario_key(sc: Scenario, exc: ScenarioError) -> ScenarioError:
    """A geometry error about ``piles[i]`` (the spec's index) or the block, by its scenario key.

    ``block`` is ``site``; ``piles[i]`` is the pile's position
    (:meth:`~pilegroup.model.piles.Piles.position_key`), ``piles[i].length_in_soil`` its
    length; a key that names no pile of its own (``piles.grid``, ``piles.embedment_m``) gets the
    pile, counted from 1, in front of the reason.
    """
    if exc.key == "block":
        why = "" if sc.cap is not None else (
            f" (without a cap: the piles' circles widened by {spec.MeshSizing.near_field_margin:g}"
            " m, the structured mesh around them)")
        return ScenarioError("site", [sc.site.size_x_m, sc.site.size_y_m], exc.allowed + why,
                             exc.unit)
    m = _SPEC_PILE.fullmatch(exc.key)
    if m is None:
        return exc
    n = int(m.group(1)) + 1
    key = {None: sc.piles.position_key(n), ".embedment": "piles.embedment_m",
           ".length_in_soil": sc.piles.key_of(n, "length_in_soil_m")}[m.group(2)]
    allowed = exc.allowed if entry_name(key) else f"pile {n}: {exc.allowed}"
    return ScenarioError(key, exc.value, allowed, exc.unit)


def geometry_spec(sc: Scenario, mesh_size: float | None = None) -> spec.GeometrySpec:
    """The geometry of scenario ``sc`` alone (:func:`resolve_geometry`), e.g. to mesh it."""
    return resolve_geometry(sc, mesh_size).spec
