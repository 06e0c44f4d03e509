"""The piles of a run named by their place in the group, and the piles a figure shows.

A pile is named by its number and its place: the row and column of a rectangular group (rows
along y, counted from the smallest y; columns along x, counted from the smallest x: the
numbering of a scenario's ``grid``), else its plan coordinates. Its role in a rectangular group
of at least 2 x 2 piles is ``corner``, ``edge`` or ``inner``; in a single row ``end`` or
``inner``; a pile on the group's plan centre is the ``centre`` pile (a group with an even
number of rows or columns has none). A lone pile is ``single``.

The piles a figure shows (:func:`key_piles`): one of each role (the most loaded of it), then
the most and the least loaded pile of the group, each once; load = the head force at the last
output time, compression positive. Pure: no files, no dolfinx.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping, Sequence

import numpy as np

#: Plan coordinates closer than this (m) are the same row or column.
_TOL = 1e-6
#: Roles in the order a figure shows them.
ROLES = ("single", "corner", "edge", "end", "centre", "inner")


@dataclasses.dataclass(frozen=True)
class PileInfo:
    """One pile: number (from 1), plan position (m), length in soil (m, if known), place."""

    number: int
    x: float
    y: float
    length: float | None = None
    row: int | None = None
    """Row (from 1, along y) in a rectangular group, else None."""
    column: int | None = None
    """Column (from 1, along x) in a rectangular group, else None."""
    role: str = ""
    """``single``, ``corner``, ``edge``, ``end``, ``inner``, ``centre`` or ``""`` (a layout
    that is not rectangular, off its centre)."""

    @property
    def place(self) -> str:
        """Where the pile stands: ``row 1, column 2, edge`` or ``x = 1.5 m, y = -2 m``."""
        where = (f"row {self.row}, column {self.column}" if self.row is not None
                 else f"x = {self.x:g} m, y = {self.y:g} m")
        return f"{where}, {self.role}" if self.role and self.role != "single" else where

    @property
    def name(self) -> str:
        """``pile 5 (row 2, column 2, centre)``; a lone pile is ``the pile``."""
        return "the pile" if self.role == "single" else f"pile {self.number} ({self.place})"

    @property
    def short(self) -> str:
        """A legend's name: ``pile 5, r2 c2``, ``pile 3, (1.5, -2)`` or ``the pile``."""
        if self.role == "single":
            return "the pile"
        if self.row is not None:
            return f"pile {self.number}, r{self.row} c{self.column}"
        return f"pile {self.number}, ({self.x:g}, {self.y:g})"


def _roles(n: int, ix: np.ndarray, iy: np.ndarray, nx: int, ny: int) -> list[str]:
    """The role of each pile of a full ``nx`` x ``ny`` grid (indices from 0)."""
    if n == 1:
        return ["single"]
    out = []
    for i, j in zip(ix, iy, strict=True):
        on_x, on_y = i in (0, nx - 1), j in (0, ny - 1)
        if nx == 1 or ny == 1:
            out.append("end" if (on_x if ny == 1 else on_y) else "inner")
        else:
            out.append("corner" if on_x and on_y else "edge" if on_x or on_y else "inner")
    return out


def name_piles(xy: Sequence[tuple[float, float]],
               lengths: Sequence[float] | None = None) -> tuple[PileInfo, ...]:
    """Every pile named by its place (module docstring); pile ``i`` at index ``i - 1``."""
    p = np.asarray(xy, dtype=float).reshape(-1, 2)
    n = len(p)
    xs, ix = np.unique(np.round(p[:, 0] / _TOL).astype(np.int64), return_inverse=True)
    ys, iy = np.unique(np.round(p[:, 1] / _TOL).astype(np.int64), return_inverse=True)
    ix, iy = ix.ravel(), iy.ravel()
    grid = len(xs) * len(ys) == n and len(set(zip(ix, iy, strict=True))) == n
    roles = _roles(n, ix, iy, len(xs), len(ys)) if grid else [""] * n
    centre = p.mean(axis=0)
    at_centre = np.linalg.norm(p - centre, axis=1) < 1e3 * _TOL
    out = []
    for k in range(n):
        role = "centre" if at_centre[k] and n > 1 else roles[k]
        out.append(PileInfo(k + 1, float(p[k, 0]), float(p[k, 1]),
                            None if lengths is None else float(lengths[k]),
                            int(iy[k]) + 1 if grid else None, int(ix[k]) + 1 if grid else None,
                            role))
    return tuple(out)


def _pick(numbers: Sequence[int], loads: Mapping[int, float], largest: bool) -> int:
    """The most (``largest``) or least loaded of ``numbers``; ties: the lowest number."""
    known = [i for i in numbers if i in loads]
    if not known:
        return min(numbers)
    values = np.array([loads[i] for i in known])
    best = values.max() if largest else values.min()
    tol = 1e-6 * max(float(np.abs(values).max()), 1e-9)
    return min(i for i, v in zip(known, values, strict=True) if abs(v - best) <= tol)


def key_piles(piles: Sequence[PileInfo], loads: Mapping[int, float] | None = None
              ) -> list[tuple[PileInfo, str]]:
    """The piles a figure shows and why: one per role, then the most and least loaded.

    ``loads``: head force per pile number (kN, compression positive); without it no pile is
    chosen for its load. Each pile once, its reasons joined (``corner, most loaded``).
    """
    loads = loads or {}
    why: dict[int, list[str]] = {}
    for role in ROLES:
        of_role = [p.number for p in piles if p.role == role]
        if of_role:
            why.setdefault(_pick(of_role, loads, True), []).append(role)
    if len(piles) > 1 and any(p.number in loads for p in piles):
        numbers = [p.number for p in piles]
        why.setdefault(_pick(numbers, loads, True), []).append("most loaded")
        why.setdefault(_pick(numbers, loads, False), []).append("least loaded")
    if not why and piles:
        why[piles[0].number] = ["first"]
    by_number = {p.number: p for p in piles}
    return [(by_number[i], ", ".join(r)) for i, r in sorted(why.items())]


__all__ = ["ROLES", "PileInfo", "key_piles", "name_piles"]
