"""Mirror symmetry of a pile group about the planes x = 0 and y = 0 (pure data, no gmsh).

A geometry is mirror-symmetric about x = 0 when its block (always centred on the plan origin)
and its cap are centred on the plane and the pile layout maps onto itself: for every pile there
is one at (-x, y) with the same diameter, length in soil and embedment, all to :data:`TOL`.
The scenario's loads are uniform on the cap top (or on the pile heads), the layers horizontal
and the boundary conditions the same on opposite sides, so loads, soil and supports are
symmetric whenever the geometry is.

A reduced model keeps ``x >= 0`` (``half_x``, plane x = 0), ``y >= 0`` (``half_y``, plane
y = 0) or both (``quarter``). Piles keep their full-model numbers: a pile is *kept* when its
centre lies in the kept part (on a plane counts), a kept pile on a plane is meshed in half, one
on both planes in quarter, and every pile of the full model has a kept mirror image (itself
when kept).
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Literal, Protocol

from pilegroup.model.mirror import PLANES as MODEL_PLANES
from pilegroup.model.mirror import TOL, layout_asymmetry

__all__ = ["MODES", "PLANES", "TOL", "Symmetry", "asymmetry", "describe_planes", "find_pile",
           "is_kept", "meshed_fraction", "mode_of", "mirror_map"]

#: What a model keeps of the full geometry; "none" is the full model.
Symmetry = Literal["none", "quarter", "half_x", "half_y"]
MODES: tuple[Symmetry, ...] = ("none", "quarter", "half_x", "half_y")
#: The mirror planes each mode cuts at, by the axis normal to them ("x": the plane x = 0), and
#: the absolute tolerance (m) of every symmetry comparison: the scenario's
#: (:mod:`pilegroup.model.mirror`).
PLANES: dict[str, tuple[str, ...]] = MODEL_PLANES


class PlanPile(Protocol):
    """A pile as the symmetry checks see it (``geometry.spec.PileSpec`` follows it); m."""

    @property
    def x(self) -> float: ...  # noqa: D102
    @property
    def y(self) -> float: ...  # noqa: D102
    @property
    def diameter(self) -> float: ...  # noqa: D102
    @property
    def length_in_soil(self) -> float: ...  # noqa: D102
    @property
    def embedment(self) -> float: ...  # noqa: D102


class PlanRectangle(Protocol):
    """A rectangle in plan (``geometry.spec.CapSpec`` follows it); m."""

    @property
    def x_min(self) -> float: ...  # noqa: D102
    @property
    def x_max(self) -> float: ...  # noqa: D102
    @property
    def y_min(self) -> float: ...  # noqa: D102
    @property
    def y_max(self) -> float: ...  # noqa: D102


def mode_of(planes: Sequence[str]) -> Symmetry:
    """The reduction that cuts at exactly ``planes`` (a subset of ``("x", "y")``)."""
    wanted = set(planes)
    return next(m for m in MODES if set(PLANES[m]) == wanted)


def describe_planes(planes: Sequence[str]) -> str:
    """``("x", "y")`` -> ``"x = 0 and y = 0"``."""
    return " and ".join(f"{a} = 0" for a in planes)


def _coord(p: PlanPile, axis: str) -> float:
    return p.x if axis == "x" else p.y


def find_pile(piles: Sequence[PlanPile], x: float, y: float) -> int | None:
    """Number (1-based) of the pile centred at (x, y) m to :data:`TOL`, else ``None``."""
    for i, p in enumerate(piles, start=1):
        if abs(p.x - x) <= TOL and abs(p.y - y) <= TOL:
            return i
    return None


def asymmetry(piles: Sequence[PlanPile], cap: PlanRectangle | None, axis: str) -> str | None:
    """Why the geometry is not mirror-symmetric about the plane ``axis`` = 0; ``None`` if it is.

    The cap must be centred on the plane; the piles compare as the scenario's do
    (:func:`pilegroup.model.mirror.layout_asymmetry`), with their embedment too.
    """
    if cap is not None:
        lo, hi = (cap.x_min, cap.x_max) if axis == "x" else (cap.y_min, cap.y_max)
        if abs(lo + hi) > TOL:
            return f"the cap spans {axis} = {lo:g} .. {hi:g} m, not centred on {axis} = 0"
    props = {key: [getattr(p, key) for p in piles]
             for key in ("diameter", "length_in_soil", "embedment")}
    return layout_asymmetry([(p.x, p.y) for p in piles], props, axis)


def is_kept(p: PlanPile, planes: Sequence[str]) -> bool:
    """Whether pile ``p``'s centre lies in the part a model cut at ``planes`` keeps."""
    return all(_coord(p, a) >= -TOL for a in planes)


def meshed_fraction(p: PlanPile, planes: Sequence[str]) -> float:
    """Fraction of pile ``p`` in a model cut at ``planes``: 1, 1/2, 1/4, or 0 if not kept."""
    if not is_kept(p, planes):
        return 0.0
    return 0.5 ** sum(1 for a in planes if abs(_coord(p, a)) <= TOL)


def mirror_map(piles: Sequence[PlanPile], planes: Sequence[str]) -> dict[int, int]:
    """Every pile number -> the number of its mirror image among the kept piles.

    The piles must be symmetric about ``planes`` (:func:`asymmetry`); kept piles map to
    themselves.
    """
    out = {}
    for i, p in enumerate(piles, start=1):
        x = abs(p.x) if "x" in planes else p.x
        y = abs(p.y) if "y" in planes else p.y
        j = find_pile(piles, x, y)
        if j is None:
            raise ValueError(f"pile {i} has no mirror image at ({x:g}, {y:g}) m")
        out[i] = j
    return out
