"""The cap actions: six components per load stage, about a stated point (pure data).

A load stage gives the actions on the foundation at its end in global axes (x, y horizontal,
z up; moments by the right-hand rule), kN and kN m: ``Fx_kN``, ``Fy_kN``, the vertical load
(``cap_load_kN`` down or ``Fz_kN`` up), ``Mx_kNm``, ``My_kNm``, ``Mz_kNm``. They act about the
point ``[actions] point_m`` (default: the centre of the loaded face, the cap's top face or
the single pile's head). A component a stage omits keeps its value from the stage before (0
before the first); every action is ramped linearly over its stage's duration.

The solver loads the loaded face with tractions statically equivalent to the actions about
the face's centroid C, so the moments given about a point P are moved there first:
``M_C = M_P + (P - C) x F`` (docs/model.md, "Cap actions").
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from pilegroup.validate import require_finite

#: Component names in order (the columns of the action vectors).
COMPONENTS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
#: The components other than the vertical force: horizontal forces, moments, torque.
LATERAL = (0, 1, 3, 4, 5)
#: Components that change sign under the mirror about the plane ``axis`` = 0 (a force normal
#: to the plane; the moments about the two axes in it): a load symmetric about the plane has
#: them zero.
ANTISYMMETRIC = {"x": (0, 4, 5), "y": (1, 3, 5)}


@dataclass(frozen=True)
class Actions:
    """Where the cap actions act: ``point_m = [x, y, z]`` (m).

    ``None``: the loaded face's centre (the cap's top face, or the pile heads without a cap).
    """

    point_m: tuple[float, float, float] | None = field(default=None, metadata={
        "allowed": "above the loaded face's centre in plan with a capacity stage"})
    """The point ``[x, y, z]`` the load stages' moments are given about, m; not set: the
    centre of the loaded face (the cap's top, or the single pile's head)."""

    def __post_init__(self) -> None:
        if self.point_m is not None:
            for i, v in enumerate(self.point_m):
                require_finite(f"point_m[{i}]", v, "m")


def transfer(actions: np.ndarray, point: Sequence[float], centre: Sequence[float]) -> np.ndarray:
    """Actions ``[F, M_P]`` about ``point`` -> the same actions about ``centre`` (a copy)."""
    out = np.array(actions, dtype=float)
    out[3:] += np.cross(np.asarray(point, float) - np.asarray(centre, float), out[:3])
    return out


def held_actions(stage_values: Sequence[Sequence[float | None]]) -> list[np.ndarray]:
    """Each load stage's six actions at its end: the given ones, the others held from before."""
    cur = np.zeros(6)
    out = []
    for vals in stage_values:
        cur = np.array([cur[k] if v is None else float(v) for k, v in enumerate(vals)])
        out.append(cur.copy())
    return out


__all__ = ["ANTISYMMETRIC", "COMPONENTS", "LATERAL", "Actions", "held_actions", "transfer"]
