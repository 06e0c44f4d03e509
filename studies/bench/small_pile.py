"""The small scenario: the bundled ``single_pile`` coarsened, same physics, about 1,400 unknowns.

What the fast tests and the stress suite (``pilegroup bench stability``) run: one pile in two
soft layers, a 0.5-day load stage and consolidation to 2 days, on a mesh of about 200 cells
(``numerics.mesh`` coarsened, the output times moved to the shorter run).
"""

from __future__ import annotations

import tomllib

from pilegroup.model import Scenario, bundled_text
from pilegroup.model.loader import scenario_from_dict

#: (line of the bundled single_pile scenario, its replacement).
COARSENING = (
    ("size_m = 0.5", "size_m = 1.0\nn_circ_min = 8"),
    ("far_field_size_m = 4.0", "far_field_size_m = 8.0"),
    ("dz_max_m = 2.0", "dz_max_m = 4.0\ndz_surface_m = 2.0\ndz_toe_m = 2.0"),
    ("dz_max_deep_m = 4.0", "dz_max_deep_m = 8.0"),
    ("end_day = 10.0", "end_day = 2.0"),
    ("output_days = [0.0, 0.5, 10.0]", "output_days = [0.0, 0.5, 2.0]"),
)


def small_pile_text() -> str:
    """The TOML text of the small scenario (the bundled single_pile with :data:`COARSENING`).

    Raises:
        ValueError: the bundled scenario no longer has a line that is replaced.
    """
    text = bundled_text("single_pile")
    for old, new in COARSENING:
        if old not in text:
            raise ValueError(f"the bundled single_pile scenario has no line {old!r} to coarsen")
        text = text.replace(old, new)
    return text


def small_pile_scenario() -> Scenario:
    """The small scenario, validated."""
    return scenario_from_dict(tomllib.loads(small_pile_text()))


__all__ = ["COARSENING", "small_pile_scenario", "small_pile_text"]
