"""The scenario's keys: table, type, unit, default, allowed values, use and meaning of each.

Read from the dataclasses the loader builds (:func:`pilegroup.model.loader.build_dataclass`
walks the same type hints), so that the reference cannot drift from what is validated:

* a field is a key (fields marked ``derived`` are set by the scenario, not read);
* its meaning is the first paragraph of the field's docstring (the string below it), a
  table's introduction the first paragraph of its class's docstring;
* its unit the field's ``metadata["unit"]``, else its range's, else the key's suffix
  (:data:`SUFFIX_UNITS`; a number without one is dimensionless);
* its allowed values the range of :data:`~pilegroup.model.bounds.BOUNDS` (the field's
  ``metadata["bound"]`` names another key's), the choices of its type and
  ``metadata["allowed"]``, a rule between keys in words;
* who uses it: the stage kinds of :data:`~pilegroup.model.stages.STAGE_KEYS`, the soil models
  (``metadata["soil_models"]``) and interface modes (``metadata["interface_modes"]``).

docs/scenario.md is :func:`markdown` (``pilegroup scenario keys --markdown``);
``pilegroup scenario keys [TABLE]`` prints :func:`text`.
"""

from __future__ import annotations

import ast
import dataclasses
import inspect
import re
import textwrap
import types
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

from pilegroup.errors import ScenarioError
from pilegroup.model.bounds import BOUNDS, Bound
from pilegroup.model.scenario import Scenario
from pilegroup.model.stages import STAGE_KEYS, Stage

#: Key suffix -> unit, longest first (a key carries its unit: ``E_MPa``, ``k_m_per_day``).
SUFFIX_UNITS = (("_kN_per_m3", "kN/m^3"), ("_kg_per_m3", "kg/m^3"), ("_m_per_day", "m/day"),
                ("_MPa_day", "MPa·day/m"), ("_kNm", "kN m"), ("_kN", "kN"), ("_kPa", "kPa"),
                ("_MPa", "MPa"), ("_deg", "degree"), ("_day", "day"), ("_every_min", "min"),
                ("_m", "m"))
#: The tables whose TOML form is an array of tables (``[[layers]]``).
ARRAYS = ("layers", "stages", "piles.layout")


@dataclass(frozen=True)
class Key:
    """One scenario key: ``table`` (dotted, ``""`` for ``[scenario]``'s) and ``name``."""

    table: str
    name: str
    type: str
    unit: str
    default: str
    allowed: str
    used_by: str
    meaning: str

    @property
    def path(self) -> str:
        """The dotted path without list indices, e.g. ``layers.interface.K``."""
        return f"{self.table}.{self.name}" if self.table else self.name


@dataclass(frozen=True)
class Table:
    """A table of keys: its dotted name, introduction and keys."""

    name: str
    intro: str
    keys: tuple[Key, ...]

    @property
    def header(self) -> str:
        """The TOML header, e.g. ``[site]``, ``[[layers]]``, ``[layers.interface]``."""
        name = self.name or "scenario"
        return f"[[{name}]]" if name in ARRAYS else f"[{name}]"


def _doc_paragraph(text: str | None) -> str:
    """The first paragraph of a docstring on one line, ``x`` as Markdown's `x`."""
    if not text:
        return ""
    first = inspect.cleandoc(text).split("\n\n")[0]
    return " ".join(first.split()).replace("``", "`")


def field_docs(cls: type) -> dict[str, str]:
    """The docstring of every field of dataclass ``cls`` (and its bases), by name."""
    out: dict[str, str] = {}
    for klass in reversed(cls.__mro__):
        try:
            source = textwrap.dedent(inspect.getsource(klass))
        except (OSError, TypeError):
            continue
        body = ast.parse(source).body[0]
        if not isinstance(body, ast.ClassDef):
            continue
        for a, b in zip(body.body, body.body[1:], strict=False):
            if (isinstance(a, ast.AnnAssign) and isinstance(a.target, ast.Name)
                    and isinstance(b, ast.Expr) and isinstance(b.value, ast.Constant)
                    and isinstance(b.value.value, str)):
                out[a.target.id] = _doc_paragraph(b.value.value)
    return out


def _inner(tp: Any) -> Any:
    """``tp`` without ``None`` (``float | None`` -> ``float``)."""
    if get_origin(tp) in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        return args[0] if len(args) == 1 else tp
    return tp


def _table_class(tp: Any) -> type | None:
    """The dataclass a field holds (a table, or an array of tables), or None."""
    tp = _inner(tp)
    if get_origin(tp) is tuple and get_args(tp) and dataclasses.is_dataclass(get_args(tp)[0]):
        return get_args(tp)[0]
    return tp if dataclasses.is_dataclass(tp) else None


def type_text(tp: Any) -> str:
    """A key's type in words: ``number``, ``integer``, ``list of numbers``, ..."""
    tp = _inner(tp)
    origin = get_origin(tp)
    if origin is Literal:
        return "string"
    if origin in (Union, types.UnionType):
        return " or ".join(type_text(a) for a in get_args(tp) if a is not type(None))
    if origin is tuple:
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            inner = type_text(args[0])
            return "list of " + ("lists" if inner.startswith("list") else f"{inner}s")
        return f"list of {len(args)} {type_text(args[0])}s"
    if origin is dict:
        return "table"
    return {float: "number", int: "integer", str: "string", bool: "boolean"}.get(tp, str(tp))


def _toml(value: Any) -> str:
    """``value`` in TOML syntax."""
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, str):
        return f'"{value}"'
    if isinstance(value, float):
        return f"{value:g}"
    if isinstance(value, tuple | list):
        return "[" + ", ".join(_toml(v) for v in value) + "]"
    if isinstance(value, dict):
        return "{}" if not value else str(value)
    return str(value)


def _default(f: dataclasses.Field[Any]) -> str:
    if f.default is not dataclasses.MISSING:
        return "not set" if f.default is None else _toml(f.default)
    if f.default_factory is not dataclasses.MISSING:
        return _toml(f.default_factory())
    return "required"


def interval(b: Bound) -> str:
    """A bound in the usual notation, e.g. ``[0, 1)``."""
    return f"{'(' if b.lo_open else '['}{b.lo:g}, {b.hi:g}{')' if b.hi_open else ']'}"


def _bound(path: str, f: dataclasses.Field[Any]) -> Bound | None:
    return BOUNDS.get(f.metadata.get("bound", path))


def _unit(path: str, f: dataclasses.Field[Any], tp: Any) -> str:
    if "unit" in f.metadata:
        return str(f.metadata["unit"])
    bound = _bound(path, f)
    if bound is not None:
        return bound.unit
    name = path.rsplit(".", 1)[-1]
    for suffix, unit in SUFFIX_UNITS:
        if name.endswith(suffix):
            return unit
    return "-" if re.search(r"number|integer", type_text(tp)) else ""


def _allowed(path: str, f: dataclasses.Field[Any], tp: Any) -> str:
    parts = []
    bound = _bound(path, f)
    if bound is not None:
        parts.append(interval(bound))
    if get_origin(_inner(tp)) is Literal:
        parts.append(", ".join(_toml(a) for a in get_args(_inner(tp))))
    if "allowed" in f.metadata:
        parts.append(str(f.metadata["allowed"]))
    return "; ".join(parts)


def _used_by(cls: type, f: dataclasses.Field[Any], table_use: Mapping[str, Any]) -> str:
    """Who uses a key: stage kinds (required ones marked), soil models, interface modes.

    ``table_use``: the metadata of the field that holds the key's table, for a key that says
    nothing itself (a layer's ``interface`` table is the interface law's).
    """
    if cls is Stage and f.name not in ("name", "kind"):
        kinds = [k + (" (required)" if f.name in req else "")
                 for k, (req, opt) in STAGE_KEYS.items() if f.name in req + opt]
        return "stages of kind " + ", ".join(kinds)
    parts = []
    for meta in (f.metadata, table_use):
        if "soil_models" in meta:
            parts.append("soil.model " + ", ".join(meta["soil_models"]))
        if "interface_modes" in meta:
            parts.append("interface.mode " + ", ".join(meta["interface_modes"]))
        if parts:
            break
    return "; ".join(parts) or "all"


def _tables(cls: type, table: str, out: list[Table], use: Mapping[str, Any]) -> None:
    """The table ``table`` of dataclass ``cls``, then its sub-tables, appended to ``out``.

    ``use``: the metadata of the field holding the table (:func:`_used_by`).
    """
    hints, docs = get_type_hints(cls), field_docs(cls)
    keys, subs = [], []
    for f in dataclasses.fields(cls):
        if f.metadata.get("derived"):
            continue
        sub = _table_class(hints[f.name])
        if sub is not None:
            subs.append((sub, f"{table}.{f.name}" if table else f.name, f.metadata))
            continue
        path = f"{table}.{f.name}" if table else f.name
        keys.append(Key(table, f.name, type_text(hints[f.name]),
                        _unit(path, f, hints[f.name]), _default(f),
                        _allowed(path, f, hints[f.name]), _used_by(cls, f, use),
                        docs.get(f.name, "")))
    if keys:
        out.append(Table(table, _doc_paragraph(cls.__doc__), tuple(keys)))
    for sub, name, meta in subs:
        _tables(sub, name, out, meta)


def tables() -> tuple[Table, ...]:
    """Every table of a scenario with its keys, in the order of :class:`Scenario`'s fields."""
    out: list[Table] = []
    _tables(Scenario, "", out, {})
    head = out.pop(0)  # name and description: the [scenario] table
    intro = "The scenario's name (the default output folder) and what it is."
    return (Table("", intro, head.keys), *out)


def keys() -> tuple[Key, ...]:
    """Every scenario key."""
    return tuple(k for t in tables() for k in t.keys)


def select(table: str | None) -> tuple[Table, ...]:
    """The tables named ``table`` (and those under it); all of them for ``None``.

    ``scenario`` names the ``[scenario]`` table; an unknown name is invalid input.
    """
    every = tables()
    if table is None:
        return every
    name = table.strip("[]")
    name = "" if name == "scenario" else name
    chosen = tuple(t for t in every if t.name == name or t.name.startswith(name + ".")
                   ) if name else every[:1]
    if not chosen:
        raise ScenarioError("TABLE", table, "unknown table; known: scenario, " + ", ".join(
            t.name for t in every if t.name))
    return chosen


#: The page's text before the tables (docs/scenario.md).
PREAMBLE = """\
# Scenario reference

<!-- Generated from the scenario's dataclasses (model/keys.py) by
`pilegroup scenario keys --markdown > docs/scenario.md`: edit the field docstrings and
metadata there, then regenerate. tests/model/test_keys.py fails while they differ. -->

A scenario is a TOML file: `pilegroup scenario show pier667` prints a commented one to start
from, `pilegroup scenario validate FILE` checks one (exit code 2 and one line naming the key, its
value and what is allowed), `pilegroup scenario keys [TABLE]` prints the tables below in the
terminal. Every key of every table is listed here, with what the validator accepts.

## Coordinates and units

* x and y are horizontal, z points up; lengths in metres. The plan's origin, x = y = 0, is the
  centre of the soil block and of the cap; a `grid` of piles is centred on it, `positions_m`
  and `layout` give pile positions in these coordinates.
* z = 0 is the ground surface: the soil fills `-site.depth_m <= z <= 0`, the cap
  `0 <= z <= cap.thickness_m`. Depths (`depth_m`, `thickness_m`, `water_table_depth_m`,
  `gauge_depths_m`, a pile's `length_in_soil_m`) are measured down from the ground surface and
  are positive; the layers are listed top down.
* Forces and moments of a load stage act in these axes about `actions.point_m` (moments by the
  right-hand rule); a downward load is `cap_load_kN > 0`, or `Fz_kN < 0`.
* A key's name carries its unit (`E_MPa`, `k_m_per_day`); the unit column repeats it. Time is
  in days: day 0 is the piles' installation.

## How to read the tables

* **default**: `required`, `not set` (the meaning says what happens then), or the value a key
  left out takes.
* **allowed**: the range (`[a, b]` includes its ends, `(a, b)` does not; docs/model.md,
  "Physical ranges of the scenario", gives each range's source), the choices, and rules
  between keys in words.
* **used by**: `all`, or the stage kinds, soil models (`soil.model`) and interface modes
  (`interface.mode`) that read the key. A key that nothing of the scenario uses may be left out,
  e.g. `phi_deg` and `c_kPa` of a layer with `soil.model = "linear_elastic"` and no interface
  law.
* Messages name a key by its path, with list indices counting from 0 as `--set` takes them,
  followed by the entry counted from 1: `layers[1].E_MPa (layer 2)`, `piles.layout[0] (pile 1)`.
"""

_COLUMNS = ("key", "type", "unit", "default", "allowed", "used by", "meaning")


def _cells(k: Key) -> tuple[str, ...]:
    return (k.name, k.type, k.unit, k.default, k.allowed, k.used_by, k.meaning)


def markdown() -> str:
    """docs/scenario.md: :data:`PREAMBLE`, then one table of keys per scenario table."""
    lines = [PREAMBLE]
    for t in tables():
        lines += ["", f"## `{t.header}`", "", t.intro, "",
                  "| " + " | ".join(_COLUMNS) + " |", "|" + " --- |" * len(_COLUMNS)]
        for k in t.keys:
            cells = [c.replace("|", "\\|") for c in _cells(k)]
            cells[0] = f"`{cells[0]}`"
            lines.append("| " + " | ".join(c or " " for c in cells) + " |")
    return "\n".join(lines) + "\n"


def text(table: str | None = None, width: int = 100) -> str:
    """The tables (or the one named ``table``, with those under it) for a terminal.

    One line per key with its type, unit and default aligned; below it, indented, what is
    allowed, who uses it and its meaning.
    """
    out = []
    for t in select(table):
        out += [t.header, *textwrap.wrap(t.intro, width, initial_indent="  ",
                                         subsequent_indent="  ")]
        rows = [_COLUMNS[:4]] + [_cells(k)[:4] for k in t.keys]
        widths = [max(len(r[i]) for r in rows) for i in range(4)]
        for i, row in enumerate(rows):
            out.append("  " + "  ".join(c.ljust(w) for c, w in zip(row, widths, strict=True)
                                        ).rstrip())
            if i:
                k = t.keys[i - 1]
                more = f"allowed: {k.allowed or 'any'}; used by: {k.used_by}. {k.meaning}"
                out += textwrap.wrap(more, width, initial_indent="      ",
                                     subsequent_indent="      ")
        out.append("")
    return "\n".join(out)


__all__ = ["ARRAYS", "PREAMBLE", "SUFFIX_UNITS", "Key", "Table", "field_docs", "interval",
           "keys", "markdown", "select", "tables", "text", "type_text"]
