"""The ground at rest, as the scenario states it: water table, pore pressure, unit weights.

Depths in m below the ground surface (positive down), stresses in kPa, compression positive.
Above the water table (``site.water_table_depth_m``) a layer weighs its unit weight above the
water table (``gamma_unsat_kN_per_m3``, total) and its pore water carries nothing; below it the
layer weighs ``gamma_kN_per_m3`` (saturated) and the pore pressure is hydrostatic,
``GAMMA_WATER (depth - water table depth)`` (docs/model.md, "The ground at rest"), unless
layers with a piezometric level of their own make the water seep (:func:`seepage`). The solver
builds the same state from the mesh (``pilegroup.solver.geostatic``); here it serves the rules
that need a stress before any mesh exists, and the seepage profile the run starts from.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from pilegroup.errors import ScenarioError
from pilegroup.model.site import Layer, Site
from pilegroup.model.stages import Stage
from pilegroup.model.units import GAMMA_WATER


def _bounds(layers: Sequence[Layer], depth_m: float) -> list[tuple[float, float]]:
    """(top, bottom) depth (m) of every layer; the last reaches ``depth_m``."""
    out, top = [], 0.0
    for j, lay in enumerate(layers):
        bottom = depth_m if j == len(layers) - 1 else top + (lay.thickness_m or 0.0)
        out.append((top, bottom))
        top = bottom
    return out


def total_vertical_stress(site: Site, layers: Sequence[Layer], depth: float) -> float:
    """Total vertical stress (kPa, compression positive) at ``depth`` (m): the weight above.

    Each layer weighs ``gamma_unsat`` above the water table and ``gamma_kN_per_m3`` below it.
    """
    wt, s = site.water_table_depth_m, 0.0
    for lay, (top, bottom) in zip(layers, _bounds(layers, site.depth_m), strict=True):
        bottom = min(bottom, depth)
        if bottom <= top:
            continue
        dry = max(min(bottom, wt) - top, 0.0)
        s += lay.gamma_unsat * dry + lay.gamma_kN_per_m3 * (bottom - top - dry)
    return s


def pore_pressure(site: Site, depth: float) -> float:
    """Hydrostatic pore pressure (kPa) at ``depth`` (m): 0 above the water table."""
    return GAMMA_WATER * max(depth - site.water_table_depth_m, 0.0)


def vertical_effective_stress(site: Site, layers: Sequence[Layer], depth: float) -> float:
    """In-situ vertical effective stress (kPa, compression positive) at ``depth`` (m).

    Total stress less the hydrostatic pore pressure; the layers' initial excess pore pressure
    is not taken off.
    """
    return total_vertical_stress(site, layers, depth) - pore_pressure(site, depth)


def _held(site: Site, lay: Layer) -> float | None:
    """The pore pressure (kPa) above the water table's hydrostatic one a layer is held at.

    Its own piezometric level's, 0 for a drained layer (at the water table's), else None.
    """
    if lay.piezometric_depth_m is not None:
        return GAMMA_WATER * (site.water_table_depth_m - lay.piezometric_depth_m)
    return 0.0 if lay.drained else None


def own_levels(site: Site, layers: Sequence[Layer]) -> list[tuple[int, float]]:
    """``(index, kPa)`` of every layer held at a piezometric level of its own.

    The kPa are the pore pressure above the water table's hydrostatic one it is held at.
    """
    return [(j, _held(site, lay)) for j, lay in enumerate(layers)  # type: ignore[misc]
            if lay.piezometric_depth_m is not None]


def seepage(site: Site, layers: Sequence[Layer]) -> tuple[tuple[float, float], ...]:
    """The pore pressure at rest above the hydrostatic one: breakpoints ``(depth m, kPa)``.

    The layers with a piezometric level of their own are held at its hydrostatic pressure, the
    water table and the drained layers at the water table's; between two of them the water seeps
    steadily: the pressure is linear in each layer, its gradient inversely as the layer's
    vertical conductivity (the same flow through each); below the last, down to the impermeable
    bottom, it is that one's. Empty when no layer has a level of its own. Raises
    :class:`ScenarioError` where two held pressures would meet without a layer between them.
    """
    if all(lay.piezometric_depth_m is None for lay in layers):
        return ()
    wt = site.water_table_depth_m
    points, free, last, key = [(wt, 0.0)], [], 0.0, "site.water_table_depth_m"
    for j, (lay, (top, bottom)) in enumerate(zip(layers, _bounds(layers, site.depth_m),
                                                 strict=True)):
        if bottom <= wt:
            if lay.piezometric_depth_m is not None:
                raise ScenarioError(f"layers[{j}].piezometric_depth_m", lay.piezometric_depth_m,
                                    f"the layer lies above the water table (site."
                                    f"water_table_depth_m = {wt:g} m): its soil is dry", "m")
            continue
        top, held = max(top, wt), _held(site, lay)
        if held is None:
            free.append((top, bottom, lay.k_m_per_day))
            continue
        if not free and abs(held - last) > 1e-9:
            name = "piezometric_depth_m" if lay.piezometric_depth_m is not None else "drained"
            raise ScenarioError(f"layers[{j}].{name}", getattr(lay, name),
                                f"holds {held:.4g} kPa above the hydrostatic pressure right"
                                f" below {key}'s {last:.4g} kPa: a layer through which the"
                                " water seeps must lie between them")
        resistance = [(b - t) / k for t, b, k in free]
        total, acc = sum(resistance), 0.0
        for (_, b, _), r in zip(free, resistance, strict=True):
            acc += r
            points.append((b, last + (held - last) * acc / total))
        points += [(top, held), (bottom, held)]
        free, last = [], held
        key = f"layers[{j}]"
    points += [(b, last) for _, b, _ in free]
    return tuple(points)


def seepage_at(points: Sequence[tuple[float, float]], depth: float) -> float:
    """The pore pressure at rest above the hydrostatic one (kPa) at ``depth`` (m).

    ``points`` are :func:`seepage`'s breakpoints: linear between them, their end values beyond
    (as the solver interpolates them, ``pilegroup.solver.geostatic.SoilColumn``); 0 without any.
    """
    if not points:
        return 0.0
    return float(np.interp(depth, [d for d, _ in points], [u for _, u in points]))


def check_groundwater(site: Site, layers: Sequence[Layer], stages: Sequence[Stage]) -> None:
    """The pore pressure keys agree with the water table.

    A layer wholly above the water table is dry: it cannot start with an excess pore pressure
    or a piezometric level. The seepage at rest (:func:`seepage`) leaves the soil's vertical
    effective stress compressive. With the water table below the ground surface the groundwater
    stages may lower it and raise it again, but not above where it starts: the soil above starts
    dry and is not wetted (docs/model.md, "The ground at rest").
    """
    wt = site.water_table_depth_m
    for depth, u in seepage(site, layers):
        sv = vertical_effective_stress(site, layers, depth)
        if u > 0.0 and u >= sv:  # blame the highest level
            levels = [(lay.piezometric_depth_m, j) for j, lay in enumerate(layers)
                      if lay.piezometric_depth_m is not None]
            j = min(levels)[1]
            lay = layers[j]
            raise ScenarioError(f"layers[{j}].piezometric_depth_m", lay.piezometric_depth_m,
                                f"the pore pressure would reach {u:.4g} kPa above the"
                                f" hydrostatic at {depth:g} m, where the vertical effective"
                                f" stress is {sv:.4g} kPa: the ground would heave; allowed: a"
                                " deeper level", "m")
    for j, (lay, (_, bottom)) in enumerate(zip(layers, _bounds(layers, site.depth_m),
                                               strict=True)):
        if bottom <= wt:
            for key in ("excess_pore_pressure_ratio", "excess_pore_pressure_kPa"):
                if getattr(lay, key) > 0.0:
                    raise ScenarioError(f"layers[{j}].{key}", getattr(lay, key),
                                        f"must be 0: the layer lies above the water table"
                                        f" (site.water_table_depth_m = {wt:g} m), its soil is"
                                        " dry")
    if wt == 0.0:
        return
    lowered = 0.0
    for i, st in enumerate(stages):
        if st.kind == "groundwater":
            lowered += st.drawdown_m or 0.0
            if lowered < -1e-9:
                raise ScenarioError(f"stages[{i}].drawdown_m", st.drawdown_m,
                                    f"raises the water table {-lowered:g} m above its start at"
                                    f" site.water_table_depth_m = {wt:g} m into soil that starts"
                                    " dry, which the model does not wet; allowed: the"
                                    " drawdowns so far add up to >= 0", "m")


__all__ = ["check_groundwater", "own_levels", "pore_pressure", "seepage", "seepage_at",
           "total_vertical_stress", "vertical_effective_stress"]
