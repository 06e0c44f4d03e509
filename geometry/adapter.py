"""Scenario -> :class:`~pilegroup.geometry.spec.GeometrySpec` (the one place that maps them)."""

from __future__ import annotations

from pilegroup.geometry import spec
from pilegroup.model import Scenario


def geometry_spec(sc: Scenario, mesh_size: float | None = None) -> spec.GeometrySpec:
    """The geometry and mesh sizing of scenario ``sc`` (``mesh_size`` overrides h, m)."""
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
