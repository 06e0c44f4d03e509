"""Mirror symmetry of a scenario about the planes x = 0 and y = 0, from its keys (no geometry).

The block and the cap are centred on the plan origin by construction, the layers horizontal and
the supports the same on opposite sides. So a scenario is mirror-symmetric about x = 0 when
its pile layout maps onto itself (every pile has one at (-x, y) with the same diameter and
length in soil, to :data:`TOL`) and its loads do (:func:`load_asymmetry`); the same about
y = 0. ``numerics.symmetry = "auto"`` models the part those planes cut off
(:func:`pilegroup.geometry.adapter.resolve_geometry`, which checks the meshed geometry too),
and the automatic mesh sizes are budgeted on that part (:func:`kept_fraction`,
:mod:`pilegroup.model.mesh_defaults`).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

from pilegroup.model.actions import ANTISYMMETRIC, COMPONENTS

#: Absolute tolerance (m) of every symmetry comparison.
TOL = 1e-9
#: The mirror planes each ``numerics.symmetry`` mode cuts at, by the axis normal to them.
PLANES: dict[str, tuple[str, ...]] = {"none": (), "half_x": ("x",), "half_y": ("y",),
                                      "quarter": ("x", "y")}


def layout_asymmetry(xy: Sequence[tuple[float, float]], props: Mapping[str, Sequence[float]],
                     axis: str) -> str | None:
    """Why piles at ``xy`` (m) are not mirror-symmetric about ``axis`` = 0; ``None`` if they are.

    ``props``: per-pile values (m) a pile and its mirror image must share, by name (e.g.
    ``diameter``, ``length_in_soil``).
    """
    for i, (px, py) in enumerate(xy):
        x, y = (-px, py) if axis == "x" else (px, -py)
        j = next((k for k, (qx, qy) in enumerate(xy)
                  if abs(qx - x) <= TOL and abs(qy - y) <= TOL), None)
        if j is None:
            return f"pile {i + 1} at ({px:g}, {py:g}) m has no mirror image at ({x:g}, {y:g}) m"
        for key, values in props.items():
            a, b = values[i], values[j]
            if abs(a - b) > TOL:
                return (f"pile {i + 1} and its mirror image, pile {j + 1}, differ in {key} "
                        f"({a:g} vs {b:g} m)")
    return None


def load_asymmetry(sc: Any, axis: str) -> str | None:
    """Why scenario ``sc``'s loads are not mirror-symmetric about ``axis`` = 0; ``None`` if not.

    The vertical cap load is uniform on the cap top or the pile heads (symmetric with the
    geometry); a horizontal force normal to the plane and a moment about an axis in it are not
    (:data:`~pilegroup.model.actions.ANTISYMMETRIC`): a force along x keeps the plane y = 0. A
    surcharge is symmetric when its rectangle is centred on the plane (the whole surface is).
    """
    if sc.outputs.cap_stiffness:
        return "outputs.cap_stiffness: the stiffness matrix loads the face in every component"
    for i, a in sc.cap_actions():
        for k in ANTISYMMETRIC[axis]:
            if abs(a[k]) > 0.0:
                unit = "kN" if k < 3 else "kN m"
                return (f"load stage {sc.stages[i].name!r} has {COMPONENTS[k]} = {a[k]:g} {unit}"
                        " about the cap centre")
    for st in sc.stages:
        if st.kind == "surcharge" and st.area_m is not None:
            lo, hi = st.area_m[:2] if axis == "x" else st.area_m[2:]
            if abs(lo + hi) > TOL:
                return (f"surcharge stage {st.name!r} spans {axis} = {lo:g} .. {hi:g} m, not "
                        f"centred on {axis} = 0")
    return None


def asymmetry(sc: Any, axis: str) -> str | None:
    """Why scenario ``sc`` (layout or loads) is not mirror-symmetric about ``axis`` = 0."""
    piles = sc.piles
    return (layout_asymmetry(piles.xy, {"diameter": piles.diameters,
                                        "length_in_soil": piles.lengths}, axis)
            or load_asymmetry(sc, axis))


def kept_fraction(sc: Any) -> float:
    """Fraction of the whole block the run models: 1, 1/2 or 1/4.

    ``numerics.symmetry``'s own planes, or with ``auto`` the planes the scenario is
    mirror-symmetric about.
    """
    mode = sc.numerics.symmetry
    planes = (tuple(a for a in ("x", "y") if asymmetry(sc, a) is None) if mode == "auto"
              else PLANES[mode])
    return 0.5 ** len(planes)


__all__ = ["PLANES", "TOL", "asymmetry", "kept_fraction", "layout_asymmetry", "load_asymmetry"]
