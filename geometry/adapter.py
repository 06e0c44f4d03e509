"""Scenario -> :class:`~pilegroup.geometry.spec.GeometrySpec` (the one place that maps them).

``numerics.symmetry`` is resolved here. A scenario's loads are always uniform (a pressure on the
cap top, or on the pile heads without a cap), its layers horizontal and its block centred with
the same supports on opposite sides, so the model is mirror-symmetric about a plane exactly
when its pile layout and cap are (:func:`GeometrySpec.symmetry_planes
<pilegroup.geometry.spec.GeometrySpec.symmetry_planes>`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from pilegroup.geometry import spec
from pilegroup.geometry import symmetry as sym
from pilegroup.model import Scenario


def _full_spec(sc: Scenario, mesh_size: float | None) -> spec.GeometrySpec:
    """The whole model of scenario ``sc`` (``mesh_size`` overrides h, m)."""
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
        piles=tuple(spec.PileSpec(x, y, p.diameter_m, p.length_in_soil_m, p.embedment_m)
                    for x, y in p.xy),
        cap=cap,
        sizing=sizing,
    )


def _resolve(sc: Scenario, full: spec.GeometrySpec) -> tuple[sym.Symmetry, str]:
    """(mode, reason) of ``numerics.symmetry`` for the whole model ``full``.

    Raises :class:`~pilegroup.errors.ScenarioError` naming ``numerics.symmetry`` when an
    explicit mode cuts at a plane the model is not symmetric about.
    """
    asked = sc.numerics.symmetry
    planes = full.symmetry_planes()
    whys = [f"{a} = 0 ({sym.asymmetry(full.piles, full.cap, a)})"
            for a in ("x", "y") if a not in planes]
    if asked == "auto":
        mode = sym.mode_of(planes)
        if not planes:
            return mode, "auto: the full model, not mirror-symmetric about " + " nor ".join(whys)
        reason = (f"auto: pile layout, cap, block and load mirror-symmetric about "
                  f"{sym.describe_planes(planes)}")
        return mode, reason + "".join(f"; not about {w}" for w in whys)
    replace(full, symmetry=asked)  # validates: the error names numerics.symmetry
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
    """
    full = _full_spec(sc, mesh_size)
    mode, reason = _resolve(sc, full)
    return ResolvedGeometry(full if mode == "none" else replace(full, symmetry=mode), reason)


def geometry_spec(sc: Scenario, mesh_size: float | None = None) -> spec.GeometrySpec:
    """The geometry of scenario ``sc`` alone (:func:`resolve_geometry`), e.g. to mesh it."""
    return resolve_geometry(sc, mesh_size).spec
