"""TOML -> :class:`~pilegroup.model.scenario.Scenario`, with one clear error per problem.

The loader walks the dataclass type hints: unknown keys, missing keys and wrong types are
rejected with the dotted key path (``layers[3].E_MPa``); range rules live in the dataclasses'
``__post_init__`` and get the same path prefixed here. A dataclass with a classmethod
``unknown_key_message(key)`` says itself what is wrong with an unknown key (a pile layout entry
rejects a rake: :class:`~pilegroup.model.piles.LayoutPile`).
"""

from __future__ import annotations

import copy
import dataclasses
import re
import tomllib
import types
from collections.abc import Mapping
from importlib import resources
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

from pilegroup.errors import ScenarioError
from pilegroup.model.scenario import Scenario

#: Scenarios shipped with the package (``pilegroup scenario show NAME``).
BUNDLED = ("pier667", "pier667_downdrag", "group3x3_downdrag", "single_pile",
           "pier667_lateral", "group2x3_lateral", "pier667_soft_soil")
_INDEXED = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)\[(\d+)\]")


def _type_name(tp: Any) -> str:
    origin = get_origin(tp)
    if origin is Literal:
        return "one of " + ", ".join(repr(a) for a in get_args(tp))
    if origin in (Union, types.UnionType):
        args = [a for a in get_args(tp) if a is not type(None)]
        return " or ".join(_type_name(a) for a in args)
    if origin is tuple:
        args = get_args(tp)
        if len(args) == 2 and args[1] is Ellipsis:
            return f"a list of {_type_name(args[0])}"
        return f"a list of {len(args)} numbers"
    if origin is dict:
        return "a table"
    if dataclasses.is_dataclass(tp):
        return "a table"
    return {float: "a number", int: "an integer", str: "a string", bool: "true or false"}.get(
        tp, str(tp))


def _convert(value: Any, tp: Any, key: str) -> Any:  # noqa: C901 - one branch per type kind
    origin = get_origin(tp)
    if origin in (Union, types.UnionType):
        args = get_args(tp)
        if value is None and type(None) in args:
            return None
        errors = []
        for a in args:
            if a is type(None):
                continue
            try:
                return _convert(value, a, key)
            except ScenarioError as exc:
                errors.append(exc)
        if len(errors) == 1:
            raise errors[0]
        raise ScenarioError(key, value, f"must be {_type_name(tp)}")
    if origin is Literal:
        if value not in get_args(tp):
            raise ScenarioError(key, value, f"must be {_type_name(tp)}")
        return value
    if tp is bool:
        if not isinstance(value, bool):
            raise ScenarioError(key, value, "must be true or false")
        return value
    if tp is int:
        if isinstance(value, bool) or not isinstance(value, int):
            raise ScenarioError(key, value, "must be an integer")
        return value
    if tp is float:
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ScenarioError(key, value, "must be a number")
        return float(value)
    if tp is str:
        if not isinstance(value, str):
            raise ScenarioError(key, value, "must be a string")
        return value
    if origin is tuple:
        args = get_args(tp)
        if not isinstance(value, list | tuple):
            raise ScenarioError(key, value, f"must be {_type_name(tp)}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_convert(v, args[0], f"{key}[{i}]") for i, v in enumerate(value))
        if len(value) != len(args):
            raise ScenarioError(key, value, f"must be {_type_name(tp)}")
        return tuple(_convert(v, a, f"{key}[{i}]") for i, (v, a) in enumerate(zip(value, args,
                                                                                   strict=True)))
    if origin is dict:
        if not isinstance(value, dict):
            raise ScenarioError(key, value, "must be a table")
        _, vt = get_args(tp)
        return {str(k): _convert(v, vt, f"{key}.{k}") for k, v in value.items()}
    if dataclasses.is_dataclass(tp):
        return build_dataclass(tp, value, key)
    raise TypeError(f"unsupported field type {tp!r} at {key}")  # a programming error


def build_dataclass[T](cls: type[T], data: object, key: str = "") -> T:
    """Build the frozen dataclass ``cls`` from a TOML table, validating every key."""
    if not isinstance(data, dict):
        raise ScenarioError(key or cls.__name__, data, "must be a table")
    hints = get_type_hints(cls)
    # fields marked ``derived`` are set by the scenario itself, never read from a file
    fields = {f.name: f for f in dataclasses.fields(cls) if not f.metadata.get("derived")}
    prefix = f"{key}." if key else ""
    for k in data:
        if k not in fields:
            special = getattr(cls, "unknown_key_message", None)
            raise ScenarioError(f"{prefix}{k}", data[k], special(str(k)) if special else
                                f"unknown key; allowed keys: {', '.join(fields)}")
    kwargs = {}
    for name, f in fields.items():
        if name in data:
            kwargs[name] = _convert(data[name], hints[name], f"{prefix}{name}")
        elif f.default is dataclasses.MISSING and f.default_factory is dataclasses.MISSING:
            raise ScenarioError(f"{prefix}{name}", None,
                                f"missing key; expected {_type_name(hints[name])}")
    try:
        return cls(**kwargs)
    except ScenarioError as exc:
        if key:
            raise ScenarioError(f"{key}.{exc.key}", exc.value, exc.allowed, exc.unit) from None
        raise


def scenario_from_dict(data: dict[str, Any]) -> Scenario:
    """Build a :class:`Scenario` from the parsed TOML document."""
    data = dict(data)
    head = data.pop("scenario", None)
    if head is None:
        raise ScenarioError("scenario", None, "missing table [scenario] with name = \"...\"")
    if not isinstance(head, dict):
        raise ScenarioError("scenario", head, "must be a table")
    for k in head:
        if k not in ("name", "description"):
            raise ScenarioError(f"scenario.{k}", head[k],
                                "unknown key; allowed keys: name, description")
    if "name" not in head:
        raise ScenarioError("scenario.name", None, "missing key; expected a string")
    for k in ("name", "description"):
        if k in head:
            data[k] = head[k]
            if not isinstance(head[k], str):
                raise ScenarioError(f"scenario.{k}", head[k], "must be a string")
    for k in ("name", "description"):
        if k in data and not isinstance(data[k], str):
            raise ScenarioError(k, data[k], "must be a string")
    return build_dataclass(Scenario, data)


def apply_overrides(data: dict[str, Any], overrides: Mapping[str, Any]) -> dict[str, Any]:
    """A copy of the TOML document ``data`` with dotted keys set (``numerics.mesh.size_m``).

    A path component may index a list (``layers[2].E_MPa``); missing tables are created, so an
    unknown key is reported by :func:`scenario_from_dict` with its dotted path.
    """
    out = copy.deepcopy(data)
    for key, value in overrides.items():
        node: Any = out
        parts = key.split(".")
        for depth, part in enumerate(parts):
            m = _INDEXED.fullmatch(part)
            name, index = (m.group(1), int(m.group(2))) if m else (part, None)
            if not name or not isinstance(node, dict):
                raise ScenarioError(key, value, "is not a dotted key path of the scenario")
            last = depth == len(parts) - 1
            if index is None:
                if last:
                    node[name] = value
                else:
                    node = node.setdefault(name, {})
                continue
            seq = node.get(name)
            if not isinstance(seq, list) or not 0 <= index < len(seq):
                n = len(seq) if isinstance(seq, list) else 0
                raise ScenarioError(key, value, f"{name} has {n} entries; index {index} is "
                                    "out of range")
            if last:
                seq[index] = value
            else:
                node = seq[index]
    return out


def parse_override(text: str) -> tuple[str, Any]:
    """``"key=value"`` (value in TOML syntax, else taken as a string) -> ``(key, value)``."""
    key, sep, raw = text.partition("=")
    if not sep or not key.strip():
        raise ScenarioError("--set", text, "must be KEY=VALUE, e.g. numerics.mesh.size_m=0.6")
    try:
        value = tomllib.loads(f"v = {raw.strip()}")["v"]
    except tomllib.TOMLDecodeError:
        value = raw.strip()
    return key.strip(), value


def load_scenario(source: str | Path, overrides: Mapping[str, Any] | None = None) -> Scenario:
    """Load a scenario from a TOML file path, or a bundled scenario by name (e.g. ``pier667``).

    ``overrides``: dotted keys set before validation (:func:`apply_overrides`).
    """
    path = Path(source)
    if not path.suffix and str(source) in BUNDLED:
        text = bundled_text(str(source))
        where = f"bundled scenario {source!r}"
    else:
        if not path.is_file():
            raise ScenarioError("file", str(source),
                                f"no such file; give a TOML path or a bundled name "
                                f"({', '.join(BUNDLED)})")
        where = str(path)
        text = _read_text(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError("file", where, f"is not valid TOML: {exc}") from None
    return scenario_from_dict(apply_overrides(data, overrides or {}))


def _read_text(path: Path) -> str:
    """The text of a scenario file; a file that is not UTF-8 text is invalid input."""
    data = path.read_bytes()
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ScenarioError("file", str(path), f"is not UTF-8 text (byte {exc.start} of "
                            f"{len(data)} is 0x{data[exc.start]:02x}); save it as UTF-8 "
                            "TOML") from None


def bundled_text(name: str) -> str:
    """The TOML text of a bundled scenario."""
    if name not in BUNDLED:
        raise ScenarioError("name", name, f"unknown bundled scenario; available: "
                            f"{', '.join(BUNDLED)}")
    return resources.files("pilegroup.model.scenarios").joinpath(f"{name}.toml").read_text(
        encoding="utf-8")


__all__ = ["BUNDLED", "apply_overrides", "build_dataclass", "bundled_text", "load_scenario",
           "parse_override", "scenario_from_dict"]
