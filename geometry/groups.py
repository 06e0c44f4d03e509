"""Mesh physical groups: the one module that formats and parses their names and tag values.

Every builder names its groups through these functions and every reader (solver inputs built by
the studies, outputs, reports) parses them here, so the string contract lives in one place.

====================  =====  ===========  ==============================================
name                  dim    tag          what
====================  =====  ===========  ==============================================
soil_layer_{jj:02d}   3      jj           soil of layer jj (1-based, top down)
pile_{i}              3      100 + i      pile i (1-based, spec order), incl. embedded part
cap                   3      300          the cap (minus the embedded pile heads)
side_xmin/xmax        2      1 / 2        block sides x = min, max
side_ymin/ymax        2      3 / 4        block sides y = min, max
bottom                2      5            z = -depth
ground_surface        2      6            soil top (z = 0) not under the cap or a pile
cap_bottom            2      7            cap bottom facets touching soil (z = 0)
cap_top               2      8            cap top, z = cap thickness
cap_side              2      9            cap vertical sides
sym_x                 2      10           symmetry plane x = 0 of a reduced model (all cells)
sym_y                 2      11           symmetry plane y = 0 of a reduced model (all cells)
base_p{i}             2      100 + i      pile toe facets (pile / soil), z = -L_i
head_p{i}             2      400 + i      pile head on the ground (only without a cap)
embed_p{i}            2      700 + i      pile / cap facets (embedded part: sides and top)
shaft_p{i}_l{jj:02d}  2      1000 i + jj  pile i shaft in layer jj (pile / soil facets)
====================  =====  ===========  ==============================================
"""

from __future__ import annotations

import re
from collections.abc import Iterable

CAP = "cap"
CAP_TAG = 300
SIDE_XMIN, SIDE_XMAX, SIDE_YMIN, SIDE_YMAX = "side_xmin", "side_xmax", "side_ymin", "side_ymax"
SIDES = (SIDE_XMIN, SIDE_XMAX, SIDE_YMIN, SIDE_YMAX)
BOTTOM = "bottom"
GROUND = "ground_surface"
CAP_BOTTOM, CAP_TOP, CAP_SIDE = "cap_bottom", "cap_top", "cap_side"
#: Symmetry planes of a reduced model (``GeometrySpec.symmetry``): x = 0 and y = 0. A reduced
#: model keeps x >= 0 (y >= 0); the plane replaces ``side_xmin`` (``side_ymin``).
SYM_X, SYM_Y = "sym_x", "sym_y"
#: Facet group of the symmetry plane normal to axis "x" (the plane x = 0) or "y" (y = 0).
SYM_PLANES = {"x": SYM_X, "y": SYM_Y}
#: Fixed facet tags of the named block, cap and symmetry-plane faces.
FACET_TAGS = {SIDES[0]: 1, SIDES[1]: 2, SIDES[2]: 3, SIDES[3]: 4, BOTTOM: 5,
              GROUND: 6, CAP_BOTTOM: 7, CAP_TOP: 8, CAP_SIDE: 9, SYM_X: 10, SYM_Y: 11}
#: Most soil layers and most piles a mesh may have: up to these counts every tag of the table
#: above is distinct (pile cells 101..199 lie between the layers and the cap, and so on).
MAX_LAYERS = MAX_PILES = 99

_SOIL = re.compile(r"soil_layer_(\d+)$")
_PILE = re.compile(r"pile_(\d+)$")
_SHAFT = re.compile(r"shaft_p(\d+)_l(\d+)$")
_BASE = re.compile(r"base_p(\d+)$")
_HEAD = re.compile(r"head_p(\d+)$")
_EMBED = re.compile(r"embed_p(\d+)$")


def soil_layer(j: int) -> str:
    """Cell group of soil layer ``j`` (1-based, top down)."""
    return f"soil_layer_{j:02d}"


def soil_layer_tag(j: int) -> int:
    """Cell tag of soil layer ``j`` (1-based)."""
    return j


def pile(i: int) -> str:
    """Cell group of pile ``i`` (1-based)."""
    return f"pile_{i}"


def pile_tag(i: int) -> int:
    """Cell tag of pile ``i`` (1-based)."""
    return 100 + i


#: Cell tags of piles 1 .. MAX_PILES.
PILE_TAGS = range(pile_tag(1), pile_tag(MAX_PILES) + 1)


def shaft(i: int, j: int) -> str:
    """Facet group of pile ``i``'s shaft in soil layer ``j`` (both 1-based)."""
    return f"shaft_p{i}_l{j:02d}"


def shaft_tag(i: int, j: int) -> int:
    """Facet tag of :func:`shaft`."""
    return 1000 * i + j


def base(i: int) -> str:
    """Facet group of pile ``i``'s toe (pile / soil facets)."""
    return f"base_p{i}"


def base_tag(i: int) -> int:
    """Facet tag of :func:`base`."""
    return 100 + i


def head(i: int) -> str:
    """Facet group of pile ``i``'s head on the ground (no cap)."""
    return f"head_p{i}"


def head_tag(i: int) -> int:
    """Facet tag of :func:`head`."""
    return 400 + i


def embed(i: int) -> str:
    """Facet group of pile ``i``'s facets embedded in the cap."""
    return f"embed_p{i}"


def embed_tag(i: int) -> int:
    """Facet tag of :func:`embed`."""
    return 700 + i


def _number(pattern: re.Pattern[str], name: str) -> int | None:
    """The number a one-number group-name ``pattern`` reads from ``name``, else ``None``."""
    m = pattern.match(name)
    return int(m.group(1)) if m else None


def layer_of(name: str) -> int | None:
    """Soil layer (1-based) of a ``soil_layer_NN`` cell group, else ``None``."""
    return _number(_SOIL, name)


def pile_of(name: str) -> int | None:
    """Pile number of a ``pile_i`` cell group, else ``None``."""
    return _number(_PILE, name)


def is_structure(name: str) -> bool:
    """A cell group of the structure (a pile or the cap)."""
    return name == CAP or pile_of(name) is not None


def shaft_of(name: str) -> tuple[int, int] | None:
    """(pile, layer) of a ``shaft_p{i}_l{jj}`` facet group, else ``None``."""
    m = _SHAFT.match(name)
    return (int(m.group(1)), int(m.group(2))) if m else None


def base_of(name: str) -> int | None:
    """Pile of a ``base_p{i}`` facet group, else ``None``."""
    return _number(_BASE, name)


def is_interface(name: str) -> bool:
    """A pile-soil interface facet group (a shaft or a base)."""
    return shaft_of(name) is not None or base_of(name) is not None


def head_of(name: str) -> int | None:
    """Pile of a ``head_p{i}`` facet group, else ``None``."""
    return _number(_HEAD, name)


def heads(names: Iterable[str]) -> list[str]:
    """The pile-head facet groups among ``names`` (in the given order)."""
    return [n for n in names if head_of(n) is not None]


def embed_of(name: str) -> int | None:
    """Pile of an ``embed_p{i}`` facet group, else ``None``."""
    return _number(_EMBED, name)


#: Tag function of every group family numbered by one pile or layer, by its parser.
_NUMBERED = ((layer_of, soil_layer_tag), (pile_of, pile_tag), (base_of, base_tag),
             (head_of, head_tag), (embed_of, embed_tag))


def tag_of(name: str) -> int:
    """Tag value of the group ``name`` (module docstring table); ``ValueError`` if unknown."""
    if name == CAP:
        return CAP_TAG
    if name in FACET_TAGS:
        return FACET_TAGS[name]
    pile_layer = shaft_of(name)
    if pile_layer is not None:
        return shaft_tag(*pile_layer)
    for parse, tag in _NUMBERED:
        k = parse(name)
        if k is not None:
            return tag(k)
    raise ValueError(f"{name!r} is not a mesh group name")
