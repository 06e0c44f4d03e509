"""The small scenario: the bundled ``single_pile`` coarsened, same physics, about 1,400 unknowns.

What the fast tests and the stress suite (``pilegroup bench stability``) run: one pile in two
soft layers, a 0.5-day load stage and consolidation to 2 days, on a mesh of about 200 cells
(a coarse ``[numerics]`` added, the output times moved to the shorter run).
"""

from __future__ import annotations

import tomllib

from pilegroup.model import Scenario, bundled_text
from pilegroup.model.loader import scenario_from_dict

#: The coarse discretisation, a table added to the bundled scenario (which has none).
NUMERICS = """
[numerics]
element = "Q1Q1"

[numerics.mesh]
size_m = 1.0
n_circ_min = 8
far_field_size_m = 8.0
growth = 1.3
dz_surface_m = 2.0
dz_toe_m = 2.0
dz_max_m = 4.0
dz_max_deep_m = 8.0
dz_growth = 1.2
dz_cap_m = 0.5
min_layer_divisions = 2
"""
#: (line of the bundled single_pile scenario, its replacement).
COARSENING = (
    ("end_day = 10.0", "end_day = 2.0"),
    ("output_days = [0.0, 0.5, 10.0]", "output_days = [0.0, 0.5, 2.0]"),
    ("\n[outputs]\n", NUMERICS + "\n[outputs]\n"),
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
