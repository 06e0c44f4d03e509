"""The piles: their layout (a grid, positions or a list of piles), sizes and installation.

Field names are the TOML keys of ``[piles]``, ``[[piles.layout]]`` and ``[piles.installation]``,
with their unit. Plan coordinates: x, y horizontal, centred on the plan origin (the cap's
centre); piles are vertical and numbered from 1 in the order :attr:`Piles.xy` lists them.
Errors are :class:`~pilegroup.errors.ScenarioError` naming the key, value, unit and what is
allowed.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field

from pilegroup.errors import ScenarioError
from pilegroup.model.bounds import check_bound
from pilegroup.validate import require_finite, require_non_negative, require_positive

#: At most this many piles: the mesh names its pile groups ``pile_1`` .. ``pile_99``
#: (``pilegroup.geometry.groups``), and the overlap check is quadratic in the count.
MAX_PILES = 99


@dataclass(frozen=True)
class Installation:
    """Excess pore pressure the piles' installation leaves in the soil around each shaft.

    Cylindrical cavity expansion (docs/model.md, "Installation pore pressures"): at a distance
    ``r`` from a pile's axis, ``u = u_s ln(R/r) / ln(R/r0)`` for ``r0 <= r <= R`` (``r0`` the
    pile radius, ``R = radius_ratio r0``), 0 beyond and below the toe; the fields of the piles
    add up. At the shaft ``u_s = excess_pore_pressure_ratio x sigma'_v``: the undrained
    strength of a normally consolidated clay, and with it the cavity pressure, grows with the
    vertical effective stress.
    """

    excess_pore_pressure_ratio: float
    """``u_s / sigma'_v`` at the shaft, in (0, 1)."""
    radius_ratio: float
    """``R / r0``: the radius of the disturbed zone over the pile radius (> 1)."""

    def __post_init__(self) -> None:
        require_positive("excess_pore_pressure_ratio", self.excess_pore_pressure_ratio, "-")
        check_bound("piles.installation.excess_pore_pressure_ratio",
                    self.excess_pore_pressure_ratio)
        require_finite("radius_ratio", self.radius_ratio, "-")
        check_bound("piles.installation.radius_ratio", self.radius_ratio)


#: The range of a coordinate: any finite number (the block and the cap bound it).
_ANY = {"allowed": "inside the block and the cap"}

#: Words that mark a key of a layout entry as a rake (batter) of the pile: rejected with their
#: own message, since every pile of the model is vertical.
RAKE_WORDS = ("rake", "batter", "inclin", "tilt", "angle", "azimuth")


def _check_pile_size(table: str, diameter: float | None, length: float | None) -> None:
    """A pile's ``diameter_m`` and ``length_in_soil_m``, where given: positive, in bounds."""
    for key, value in (("diameter_m", diameter), ("length_in_soil_m", length)):
        if value is not None:
            require_positive(key, value, "m")
            check_bound(f"{table}.{key}", value)


@dataclass(frozen=True)
class LayoutPile:
    """One entry of ``piles.layout``: a vertical pile at ``(x_m, y_m)`` (m, plan coordinates).

    ``diameter_m`` and ``length_in_soil_m`` (m) are the pile's own; an omitted one is the
    ``[piles]``-level value of the same name. Raked (battered) piles are not modelled: a key
    giving a rake is rejected (:meth:`unknown_key_message`).
    """

    x_m: float = field(metadata=_ANY)
    """Plan position of the pile's axis along x, m."""
    y_m: float = field(metadata=_ANY)
    """Plan position of the pile's axis along y, m."""
    diameter_m: float | None = None
    """The pile's diameter, m; not set: ``piles.diameter_m``."""
    length_in_soil_m: float | None = None
    """The pile's length below the ground surface, m; not set: ``piles.length_in_soil_m``."""

    def __post_init__(self) -> None:
        require_finite("x_m", self.x_m, "m")
        require_finite("y_m", self.y_m, "m")
        _check_pile_size("piles.layout", self.diameter_m, self.length_in_soil_m)

    @classmethod
    def unknown_key_message(cls, key: str) -> str:
        """What the loader says of an unknown key ``key`` in a layout entry.

        A key naming a rake or batter (:data:`RAKE_WORDS`, e.g. ``rake_deg``, ``batter``,
        ``inclination_deg``) says that raked piles are not supported; any other says so too,
        after the allowed keys, so that nobody reads a silently dropped key as a raked pile.
        """
        allowed = "allowed keys: " + ", ".join(f.name for f in dataclasses.fields(cls))
        if any(w in key.lower() for w in RAKE_WORDS):
            return (f"raked piles are not supported: every pile is vertical (no rake or batter"
                    f" can be given); {allowed}")
        return f"unknown key; {allowed} (vertical piles only: raked piles are not supported)"


@dataclass(frozen=True)
class Piles:
    """The piles: a regular grid centred on the cap, explicit positions, or an explicit layout.

    Exactly one of: ``grid`` [nx, ny] with ``spacing_m`` [sx, sy]; ``positions_m`` [[x, y],
    ...] (m, plan coordinates); ``layout``, a list of :class:`LayoutPile` tables, each pile
    with its own position and, optionally, its own diameter and length in soil. With ``grid``
    or ``positions_m`` every pile has ``diameter_m`` and ``length_in_soil_m``; with ``layout``
    these are the defaults of the entries that omit them (and may be left out when every entry
    gives its own). The embedment in the cap is one for all piles.

    Piles are numbered from 1 in the order :attr:`xy` lists them; :attr:`diameters` and
    :attr:`lengths` are aligned with it. Two piles must not overlap: the distance between their
    centres is at least the mean of their two diameters. The mesh needs more room between pile
    rows and columns, which :func:`pilegroup.geometry.adapter.resolve_geometry` checks.
    """

    diameter_m: float | None = field(default=None, metadata={
        "allowed": "required with grid or positions_m"})
    """Diameter of every pile (with ``layout``: of the entries that give none), m."""
    length_in_soil_m: float | None = field(default=None, metadata={
        "allowed": "required with grid or positions_m; < site.depth_m"})
    """Length of every pile below the ground surface (with ``layout``: of the entries that
    give none), m."""
    embedment_m: float = field(default=0.0, metadata={"allowed": ">= 0, < cap.thickness_m"})
    """Length of every pile inside the cap above the ground surface, m (0 without a cap)."""
    grid: tuple[int, int] | None = field(default=None, metadata={
        "allowed": "each >= 1; exactly one of grid, positions_m, layout"})
    """A grid of ``[nx, ny]`` piles centred on the plan origin, numbered row by row (x
    fastest)."""
    spacing_m: tuple[float, float] | None = field(default=None, metadata={
        "allowed": "each > 0; required with a grid of more than one pile"})
    """Centre-to-centre spacing ``[sx, sy]`` of a grid, m."""
    positions_m: tuple[tuple[float, float], ...] | None = field(default=None, metadata={
        "allowed": "at least one pile, inside the block and the cap"})
    """Plan positions ``[[x, y], ...]`` of the piles, m, every pile of the same size."""
    layout: tuple[LayoutPile, ...] | None = None
    installation: Installation | None = None
    """Installation pore pressures present at the start (None: wished in place, no excess)."""

    def __post_init__(self) -> None:
        _check_pile_size("piles", self.diameter_m, self.length_in_soil_m)
        require_non_negative("embedment_m", self.embedment_m, "m")
        self._check_layout()
        self._check_sizes()
        self._check_overlap()

    def _layout_key(self) -> str:
        """The key that places the piles: ``layout``, ``positions_m`` or ``grid``."""
        if self.layout is not None:
            return "layout"
        return "positions_m" if self.positions_m is not None else "grid"

    def _check_layout(self) -> None:
        """Exactly one of grid, positions_m and layout; finite positions; at most MAX_PILES."""
        given = [k for k, v in (("grid", self.grid), ("positions_m", self.positions_m),
                                ("layout", self.layout)) if v is not None]
        if len(given) > 1:
            later = given[-1]
            n = len(getattr(self, later))
            raise ScenarioError(later, f"{n} entries", "give exactly one of grid (with"
                                " spacing_m), positions_m or layout; here also "
                                + " and ".join(given[:-1]))
        if self.spacing_m is not None and self.grid is None and given:
            raise ScenarioError("spacing_m", list(self.spacing_m),
                                f"goes with grid only: leave it out with {given[0]}", "m")
        if self.layout is not None:
            if len(self.layout) == 0:
                raise ScenarioError("layout", [], "must list at least one pile")
        elif self.positions_m is not None:
            if len(self.positions_m) == 0:
                raise ScenarioError("positions_m", [], "must list at least one pile", "m")
            for i, xy in enumerate(self.positions_m):
                for j, v in enumerate(xy):
                    require_finite(f"positions_m[{i}][{j}]", v, "m")
        else:
            if self.grid is None:
                raise ScenarioError("grid", None, "missing: give grid = [nx, ny] with spacing_m,"
                                    " positions_m or layout")
            for i, v in enumerate(self.grid):
                if v < 1:
                    raise ScenarioError(f"grid[{i}]", v, "must be an integer >= 1")
            if self.spacing_m is None:
                if any(v > 1 for v in self.grid):
                    raise ScenarioError("spacing_m", None, "missing: required when grid > 1x1",
                                        "m")
            else:
                for i, v in enumerate(self.spacing_m):
                    require_positive(f"spacing_m[{i}]", v, "m")
        n = self.count
        if n > MAX_PILES:
            raise ScenarioError(self._layout_key(), n,
                                f"at most {MAX_PILES} piles (the mesh names pile_1 .. "
                                f"pile_{MAX_PILES})", "-")

    def _check_sizes(self) -> None:
        """Every pile has a diameter and a length: its own (layout) or the ``[piles]`` one."""
        for key in ("diameter_m", "length_in_soil_m"):
            if getattr(self, key) is not None:
                continue
            if self.layout is None:
                raise ScenarioError(key, None, f"missing key; expected a number (with"
                                    f" {self._layout_key()} every pile has this {key}; a layout"
                                    " may give each pile its own)", "m")
            for i, entry in enumerate(self.layout):
                if getattr(entry, key) is None:
                    raise ScenarioError(f"layout[{i}].{key}", None,
                                        f"missing: give {key} in this entry, or piles.{key} as"
                                        " the value of every entry that omits it", "m")

    def _check_overlap(self) -> None:
        """No two pile cross-sections overlap: centre distance >= the mean of the diameters."""
        xy, d = self.xy, self.diameters
        for i in range(len(xy)):
            for j in range(i):
                dist = math.dist(xy[i], xy[j])
                least = 0.5 * (d[i] + d[j])
                if dist < least:
                    key = {"layout": f"layout[{i}]", "positions_m": "positions_m",
                           "grid": "spacing_m"}[self._layout_key()]
                    raise ScenarioError(
                        key, [list(xy[j]), list(xy[i])],
                        f"piles {j + 1} and {i + 1} overlap: centre distance {dist:g} m must be"
                        f" >= the mean of their diameters ({d[j]:g} + {d[i]:g}) / 2 ="
                        f" {least:g} m", "m")

    @property
    def xy(self) -> tuple[tuple[float, float], ...]:
        """Plan positions (m) of every pile, numbered from 1.

        In the order of ``layout`` or ``positions_m``; a grid row by row (x fastest).
        """
        if self.layout is not None:
            return tuple((float(e.x_m), float(e.y_m)) for e in self.layout)
        if self.positions_m is not None:
            return tuple((float(x), float(y)) for x, y in self.positions_m)
        nx, ny = self.grid  # type: ignore[misc]
        sx, sy = self.spacing_m if self.spacing_m is not None else (0.0, 0.0)
        return tuple(((i - (nx - 1) / 2) * sx, (j - (ny - 1) / 2) * sy)
                     for j in range(ny) for i in range(nx))

    def _per_pile(self, key: str) -> tuple[float, ...]:
        default = getattr(self, key)
        if self.layout is None:
            return (float(default),) * self.count
        return tuple(float(default if getattr(e, key) is None else getattr(e, key))
                     for e in self.layout)

    @property
    def diameters(self) -> tuple[float, ...]:
        """Diameter (m) of every pile, aligned with :attr:`xy` (pile ``i`` at index ``i - 1``)."""
        return self._per_pile("diameter_m")

    @property
    def lengths(self) -> tuple[float, ...]:
        """Length in soil (m) of every pile, aligned with :attr:`xy`."""
        return self._per_pile("length_in_soil_m")

    def key_of(self, i: int, key: str) -> str:
        """The scenario key that sets ``key`` of pile ``i`` (1-based), for messages.

        ``key`` is ``diameter_m`` or ``length_in_soil_m``; the answer is
        ``piles.layout[i - 1].<key>`` when that entry gives it, else ``piles.<key>``.
        """
        if self.layout is not None and getattr(self.layout[i - 1], key) is not None:
            return f"piles.layout[{i - 1}].{key}"
        return f"piles.{key}"

    def position_key(self, i: int) -> str:
        """The scenario key that places pile ``i`` (1-based), for messages.

        ``piles.layout[i - 1]`` or ``piles.positions_m[i - 1]`` (a message counts the pile
        from 1 beside it, :func:`pilegroup.errors.entry_name`); ``piles.grid`` for a grid,
        whose piles have no key of their own.
        """
        if self.layout is not None:
            return f"piles.layout[{i - 1}]"
        return f"piles.positions_m[{i - 1}]" if self.positions_m is not None else "piles.grid"

    @property
    def count(self) -> int:
        """Number of piles."""
        if self.layout is not None:
            return len(self.layout)
        if self.positions_m is not None:
            return len(self.positions_m)
        return math.prod(self.grid)  # type: ignore[arg-type]
