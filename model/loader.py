"""TOML -> :class:`~pilegroup.model.scenario.Scenario`, with one clear error per problem.

The loader walks the dataclass type hints: unknown keys, missing keys and wrong types are
rejected with the dotted key path (``layers[3].E_MPa``); range rules live in the dataclasses'
``__post_init__`` and get the same path prefixed here.
"""

from __future__ import annotations

import dataclasses
import tomllib
import types
from importlib import resources
from pathlib import Path
from typing import Any, Literal, Union, get_args, get_origin, get_type_hints

from pilegroup.errors import ScenarioError
from pilegroup.model.scenario import Scenario

#: Scenarios shipped with the package (``pilegroup scenario show NAME``).
BUNDLED = ("pier667", "single_pile")


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
    fields = {f.name: f for f in dataclasses.fields(cls)}
    prefix = f"{key}." if key else ""
    for k in data:
        if k not in fields:
            raise ScenarioError(f"{prefix}{k}", data[k],
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


def load_scenario(source: str | Path) -> Scenario:
    """Load a scenario from a TOML file path, or a bundled scenario by name (e.g. ``pier667``)."""
    path = Path(source)
    if not path.suffix and str(source) in BUNDLED:
        text = bundled_text(str(source))
        where = f"bundled scenario {source!r}"
    else:
        if not path.is_file():
            raise ScenarioError("file", str(source),
                                f"no such file; give a TOML path or a bundled name "
                                f"({', '.join(BUNDLED)})")
        text = path.read_text(encoding="utf-8")
        where = str(path)
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ScenarioError("file", where, f"is not valid TOML: {exc}") from None
    return scenario_from_dict(data)


def bundled_text(name: str) -> str:
    """The TOML text of a bundled scenario."""
    if name not in BUNDLED:
        raise ScenarioError("name", name, f"unknown bundled scenario; available: "
                            f"{', '.join(BUNDLED)}")
    return resources.files("pilegroup.model.scenarios").joinpath(f"{name}.toml").read_text(
        encoding="utf-8")


__all__ = ["BUNDLED", "build_dataclass", "bundled_text", "load_scenario", "scenario_from_dict"]
