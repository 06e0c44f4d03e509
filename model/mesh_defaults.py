"""The automatic discretisation: every ``numerics`` key a scenario leaves out, from the scenario.

Most scenarios never write ``[numerics]``; what they get is this module's choice, and the
bundled scenarios use it too (docs/model.md, "The default discretisation").

Element pair (``numerics.element = "auto"``): ``Q2Q1`` (Taylor–Hood, stabilised) wherever the
Q2Q1 model fits :data:`UNKNOWN_BUDGET` at its automatic sizes; else the stabilised equal-order
pair ``Q1Q1``. Trilinear hexahedra are too stiff next to piles: they lock where the piles bend
(the scenario's ``locking_reason``: ``verify lateral-single-pile`` 18-44 % too stiff; a capacity
stage drives a plastic soil to isochoric flow), and under vertical load alone ``pier667``
settles 2.9 % less than on Q2Q1 (docs/benchmarks.md, "Vertical actions only").

Mesh sizes (``numerics.mesh``), for the largest pile diameter ``d``, the longest pile ``L``, the
block's smaller plan side ``W`` and depth ``D`` (the rules reproduce the sizes the Pier 667 mesh
study validated, docs/results.md):

* ``size_m = d`` next to the piles, at most the clear gap between two piles;
* ``n_circ_min = 28`` edges around a pile (meshed area 99.2 % of the circle's);
* ``far_field_size_m = min(W / 4, 16 d)``, ``growth = 1.6`` in plan;
* ``dz_surface_m = dz_toe_m = max(d, L / 80)``, ``dz_max_m = min(max(6 d, L / 20), L / 10)``
  along the piles,
  ``dz_max_deep_m = min(15 d, (D - L) / 4, W / 4)`` below the toes, ``dz_growth = 1.4``;
* ``dz_cap_m = min(1.5 d, cap thickness)``; ``min_layer_divisions = 2`` (every layer at least
  two elements thick, so thin layers set their own sizes);
* with ``Q2Q1``: ``size_m = min(2 d, clear gap)``, twice every vertical length (the cap's at
  most its thickness), ``n_circ_min = 16`` and ``min_layer_divisions = 1`` (:data:`Q2_LENGTH`)
  where the piles bend; with vertical actions only every length twice that again and 8 edges
  around a pile (:data:`AXIAL_LENGTH`).

Memory budget: when the estimated unknowns (:func:`estimated_unknowns`) of the part the run
models (the whole block, or the half or quarter its mirror symmetry allows,
:func:`pilegroup.model.mirror.kept_fraction`) exceed :data:`UNKNOWN_BUDGET`, the automatic
sizes coarsen step by step (:data:`STEPS`: longer
elements, fewer edges around a pile, one element layer across a thin layer) until they fit: a
default run fits a 2-core, 24 GB machine for groups up to 6 x 6 of any diameter
(``tests/model/test_mesh_defaults.py``). Keys the scenario gives are kept as given.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping
from dataclasses import replace

from pilegroup.model.analysis import MeshOptions, Numerics
from pilegroup.model.mesh_estimate import EstimatedScenario, estimated_unknowns

#: Why Taylor–Hood is the default where nothing bends.
AXIAL_REASON = "auto: every action is vertical (Q2Q1 at the axial sizes)"

#: Unknowns a default mesh may have in the part the run models: the full Pier 667 at h = 0.1 m
#: (623,988 unknowns) ran in 14.6 GB on 2 ranks with the kept LU.
UNKNOWN_BUDGET = 600_000
#: Edges around a pile.
N_CIRC = 28
#: Taylor–Hood's sizes: the vertical lengths (:data:`Q2_LENGTHS`) and the size next to the
#: piles (at most the clear gap) times ``Q2_LENGTH``, and :data:`N_CIRC_Q2` edges around a
#: pile: a quadratic element spans what two trilinear ones do. On ``verify
#: lateral-single-pile`` (docs/benchmarks.md, "The default discretisation: the options
#: measured") Q2Q1 at these sizes is 4.3 % from Randolph's head deflection (133,311
#: unknowns in its 160 m block), 2.4 % with the cells halved at the pile.
Q2_LENGTH, N_CIRC_Q2 = 2.0, 16
#: With vertical actions only nothing bends: Taylor–Hood's lengths times ``AXIAL_LENGTH`` and
#: :data:`N_CIRC_AXIAL` edges around a pile (the polygon of the circle's area, its shaft's
#: shear scaled to the circle's perimeter). On ``pier667`` (docs/benchmarks.md, "Vertical
#: actions only") settlement and largest moment converge from these sizes (docs/results.md).
AXIAL_LENGTH, N_CIRC_AXIAL = 2.0, 8
Q2_LENGTHS = ("dz_surface_m", "dz_toe_m", "dz_max_m", "dz_max_deep_m", "dz_cap_m")
#: Growth ratios in plan and in depth.
GROWTH, DZ_GROWTH = 1.6, 1.4
#: Coarsening steps tried in order until the estimate fits: (factor on the automatic lengths,
#: at most this many edges around a pile and element layers across a layer). The first is the
#: nominal mesh itself (``None``: the nominal edges and layers, refined by a scale below 1).
STEPS = ((1.0, None, None), (1.25, 24, 2), (1.5, 20, 2), (2.0, 16, 2), (2.0, 16, 1),
         (2.5, 12, 1), (3.0, 12, 1), (4.0, 12, 1))
#: Largest automatic sizes (m): the validator's bounds (size_m also <= 5 x the thinnest pile).
SIZE_MAX, FAR_MAX, DZ_MAX = 10.0, 200.0, 100.0

#: The length keys the budget scales.
LENGTHS = ("size_m", "far_field_size_m", "dz_surface_m", "dz_toe_m", "dz_max_m",
           "dz_max_deep_m", "dz_cap_m")


def nominal_sizes(sc: EstimatedScenario, scale: float = 1.0, element: str = "Q1Q1",
                  bending: bool = True) -> dict[str, float | int]:
    """The automatic sizes of every ``numerics.mesh`` key before the memory budget (m, -).

    ``element``: ``Q2Q1`` takes :data:`Q2_LENGTH` times the lengths next to and along the
    piles, :data:`N_CIRC_Q2` edges around a pile and one element across a thin layer (a
    quadratic element spans what two trilinear ones do: three nodes across the layer); without
    ``bending`` (vertical actions only) every length :data:`AXIAL_LENGTH` times that again and
    :data:`N_CIRC_AXIAL` edges around a pile.
    ``scale`` (``numerics.mesh.scale``) multiplies every length and divides the edges around a
    pile (to the nearest multiple of 4, at least 8): a refinement study's one knob.
    """
    out = _nominal(sc)
    n_circ = N_CIRC
    if element == "Q2Q1":
        n_circ = N_CIRC_Q2
        for k in Q2_LENGTHS:
            out[k] = out[k] * Q2_LENGTH
        out["size_m"] = min(out["size_m"] * Q2_LENGTH, _clear_gap(sc))
        out["far_field_size_m"] = max(out["far_field_size_m"], out["size_m"])
        if not bending:
            n_circ = N_CIRC_AXIAL
            for k in (*Q2_LENGTHS, "size_m", "far_field_size_m"):
                out[k] = out[k] * AXIAL_LENGTH
        if sc.cap is not None:
            out["dz_cap_m"] = min(out["dz_cap_m"], sc.cap.thickness_m)
        out["min_layer_divisions"] = 1
    for k in LENGTHS:
        out[k] = out[k] * scale
    out["n_circ_min"] = max(8, 4 * round(n_circ / scale / 4))
    return out


def _clear_gap(sc: EstimatedScenario) -> float:
    """The least clear gap between two piles (m; infinite for a single pile)."""
    gap = math.inf
    for (i, a), (j, b) in itertools.combinations(enumerate(sc.piles.xy), 2):
        g = math.dist(a, b) - (sc.piles.diameters[i] + sc.piles.diameters[j]) / 2
        if g > 0:
            gap = min(gap, g)
    return gap


def _nominal(sc: EstimatedScenario) -> dict[str, float | int]:
    d = max(sc.piles.diameters)
    length = max(sc.piles.lengths)
    width = min(sc.site.size_x_m, sc.site.size_y_m)
    size = min(d, _clear_gap(sc))
    far = max(size, min(width / 4, 16 * d))
    dz = max(d, length / 80)  # a slender pile needs no elements as short as its diameter
    out: dict[str, float | int] = {
        "size_m": size, "far_field_size_m": far, "growth": GROWTH, "n_circ_min": N_CIRC,
        "dz_surface_m": dz, "dz_toe_m": dz, "dz_max_m": max(dz, min(max(6 * d, length / 20),
                                                                    length / 10)),
        "dz_max_deep_m": max(d, min(15 * d, (sc.site.depth_m - length) / 4, width / 4)),
        "dz_growth": DZ_GROWTH, "min_layer_divisions": 2,
        "dz_cap_m": d if sc.cap is None else min(1.5 * d, sc.cap.thickness_m),
    }
    return out


def resolve_mesh(sc: EstimatedScenario, given: Mapping[str, float | int], element: str,
                 fraction: float = 1.0, bending: bool = True
                 ) -> tuple[dict[str, float | int], int]:
    """Every ``numerics.mesh`` key: ``given`` ones kept, the others automatic within budget.

    ``fraction``: the part of the whole block the run models (the budget is on its unknowns);
    ``bending``: as in :func:`nominal_sizes`.

    Returns the sizes and the index of the :data:`STEPS` entry they come from (0: the nominal
    sizes fit :data:`UNKNOWN_BUDGET`; the last one when nothing fits, which the memory check
    then reports).
    """
    nominal = nominal_sizes(sc, float(given.get("scale", 1.0)), element, bending)
    if max(sc.piles.lengths) >= sc.site.depth_m:  # the scenario refuses it, with its reason
        return {**nominal, **given}, 0
    size_max = min(SIZE_MAX, 5.0 * min(sc.piles.diameters))
    step = 0
    for step, (factor, n_circ, divisions) in enumerate(STEPS):  # noqa: B007 - returned
        sizes = dict(nominal)
        if n_circ is not None:
            sizes["n_circ_min"] = min(n_circ, nominal["n_circ_min"])
            sizes["min_layer_divisions"] = min(divisions, nominal["min_layer_divisions"])
        for k in LENGTHS:
            sizes[k] = min(nominal[k] * factor, DZ_MAX)
        sizes["size_m"] = min(sizes["size_m"], size_max)
        sizes["far_field_size_m"] = min(sizes["far_field_size_m"], FAR_MAX)
        sizes.update(given)
        # automatic sizes keep the given ones valid: h next to the piles <= the far field's
        if "size_m" not in given:
            sizes["size_m"] = min(sizes["size_m"], sizes["far_field_size_m"])
        sizes["far_field_size_m"] = max(sizes["far_field_size_m"], sizes["size_m"])
        if estimated_unknowns(_with_mesh(sc, sizes, element), fraction) <= UNKNOWN_BUDGET:
            break
    return sizes, step


class _Sized:
    """A view of a scenario with other numerics (what the estimate reads)."""

    def __init__(self, sc: EstimatedScenario, numerics: Numerics) -> None:
        self.site, self.layers, self.piles, self.cap = sc.site, sc.layers, sc.piles, sc.cap
        self.numerics = numerics


def _with_mesh(sc: EstimatedScenario, sizes: Mapping[str, float | int], element: str
               ) -> _Sized:
    mesh = MeshOptions(**sizes)  # type: ignore[arg-type]
    return _Sized(sc, replace(sc.numerics, mesh=mesh, element=element))


def resolve_numerics(sc: EstimatedScenario, locking: str | None, fraction: float = 1.0
                     ) -> Numerics:
    """``sc.numerics`` with its element pair and every mesh size resolved.

    ``fraction``: the part of the whole block the run models
    (:func:`pilegroup.model.mirror.kept_fraction`), whose unknowns the budget bounds.

    ``numerics.element = "auto"``: Q2Q1 where it fits :data:`UNKNOWN_BUDGET` at its automatic
    sizes (the bending sizes where trilinear hexahedra lock, ``locking`` being the scenario's
    reason, or None; else the axial sizes); else Q1Q1. A scenario made from a resolved one
    (``dataclasses.replace``) chooses its automatic keys and an automatic element again, for
    what it now holds.
    """
    num = sc.numerics
    given = {k: v for k, v in num.mesh.given().items() if k not in num.mesh.automatic}
    element, reason = num.element, "numerics.element"
    bending = locking is not None
    sizes = None
    if element == "auto" or num.element_reason.startswith("auto"):
        q2, step = resolve_mesh(sc, given, "Q2Q1", fraction, bending)
        why = f"auto: {locking}" if bending else AXIAL_REASON
        if step == 0:
            element, reason, sizes = "Q2Q1", why, q2
        else:
            element, reason = "Q1Q1", (f"{why}, but Q2Q1 exceeds the memory budget "
                                       f"({UNKNOWN_BUDGET:,} unknowns in the part modelled) at "
                                       "the automatic mesh sizes")
    if sizes is None:
        sizes, _ = resolve_mesh(sc, given, element, fraction, bending)
    automatic = tuple(k for k in sizes if k not in given)
    mesh = MeshOptions(**sizes, automatic=automatic)  # type: ignore[arg-type]
    return replace(num, element=element, mesh=mesh, element_reason=reason)


def describe(num: Numerics) -> str:
    """The element pair and mesh sizes in one line (automatic sizes marked ``*``)."""
    m = num.mesh
    sizes = ", ".join(f"{k} = {v:.4g}{'*' if k in m.automatic else ''}"
                      for k, v in m.given().items())
    return f"element {num.element} ({num.element_reason}); mesh {sizes} (* automatic)"


def locking_warning(num: Numerics, locking: str | None) -> str | None:
    """One line when Q1Q1 is used where trilinear hexahedra lock (``locking``: why)."""
    if num.element != "Q1Q1" or locking is None:
        return None
    return (f"numerics.element = 'Q1Q1' where {locking}: trilinear hexahedra lock (too stiff: "
            "head deflection 18-44 % too small in verify lateral-single-pile; a "
            "load-settlement curve that never plunges); 'Q2Q1' is accurate where it fits the "
            f"machine ({num.element_reason})")


__all__ = ["AXIAL_REASON", "LENGTHS", "STEPS", "UNKNOWN_BUDGET", "describe", "locking_warning",
           "nominal_sizes", "resolve_mesh", "resolve_numerics"]
