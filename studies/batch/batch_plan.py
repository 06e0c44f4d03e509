"""A batch plan: one base scenario and the cases run from it, read from TOML and checked.

The plan file (README.md, "Batches of runs"; example: docs/examples/single_pile_sizes.toml)::

    [batch]
    scenario = "single_pile"            # bundled name, or a path relative to the plan's folder
    set = { "outputs.xdmf" = false }    # optional: set in every case

    [sweep]                             # optional: the cartesian product of these values
    "numerics.mesh.size_m" = [1.0, 0.8]

    [[case]]                            # optional, repeatable: one named case
    name = "stiff_mud"
    set = { "layers[0].E_MPa" = 6.0 }

Keys under ``set`` and ``[sweep]`` are dotted scenario keys, as ``pilegroup run --set``
(:func:`pilegroup.model.loader.apply_overrides`); values are TOML values. The cases are the
``[[case]]`` entries followed by the sweep's product (first key slowest); a sweep case is named
from its values (``size_m=1.0``, keys joined by ``,``; the full dotted key when two keys end
alike). A case's overrides are the ``[batch] set`` ones, then its own (later ones win).

:func:`resolve_cases` builds and validates every case's scenario before anything runs: a
problem is a :class:`~pilegroup.errors.ScenarioError` naming the case and the key.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import re
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pilegroup.errors import ScenarioError
from pilegroup.fileio import json_default
from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.model import BUNDLED, Scenario, load_scenario
from pilegroup.model.mesh_estimate import estimated_cells

#: Allowed case names: also the names of the cases' run folders.
NAME = re.compile(r"[A-Za-z0-9][A-Za-z0-9._=,+-]*")
#: Names of the batch's own files in its folder, which no case may take.
RESERVED = ("batch.json", "batch.csv")
#: Tables of a plan file and the keys each may hold.
PLAN_KEYS = {"batch": ("scenario", "set"), "case": ("name", "set")}


@dataclass(frozen=True)
class BatchCase:
    """One case of a plan: its name (run folder) and its overrides, in the order applied."""

    name: str
    overrides: tuple[tuple[str, Any], ...]

    def override_dict(self) -> dict[str, Any]:
        """The overrides as a dictionary (later keys win)."""
        return dict(self.overrides)


@dataclass(frozen=True)
class BatchPlan:
    """A base scenario (bundled name or file path) and its cases."""

    scenario: str
    cases: tuple[BatchCase, ...]
    name: str = "batch"


@dataclass(frozen=True)
class ResolvedCase:
    """A case with its validated scenario, the digest of it and its estimated cell count."""

    case: BatchCase
    scenario: Scenario
    digest: str
    cost: float

    @property
    def name(self) -> str:
        """The case's name."""
        return self.case.name


def as_table(value: object, key: str) -> dict[str, Any]:
    """``value`` if it is a TOML table, else a :class:`ScenarioError` naming ``key``."""
    if not isinstance(value, dict):
        raise ScenarioError(key, value, "must be a table")
    return value


def check_keys(table: dict[str, Any], key: str, allowed: tuple[str, ...]) -> None:
    """A :class:`ScenarioError` naming ``key.k`` for the first key ``k`` not in ``allowed``."""
    for k, v in table.items():
        if k not in allowed:
            raise ScenarioError(f"{key}.{k}", v, f"unknown key; allowed keys: {', '.join(allowed)}")


def check_name(name: object, key: str, reserved: tuple[str, ...] = RESERVED) -> str:
    """``name`` if it can name a run folder of the batch (:data:`NAME`, not one of ``reserved``)."""
    if not isinstance(name, str) or not NAME.fullmatch(name) or name in reserved:
        raise ScenarioError(key, name, "must be a name of letters, digits and ._=,+- (it "
                            f"names the case's run folder), other than {', '.join(reserved)}")
    return name


def scenario_source(source: object, key: str, base_dir: Path | None = None) -> str:
    """A bundled scenario name as it is, or the path of a scenario file.

    A relative path is taken from ``base_dir`` (the plan's folder); a missing file or a value
    that is not a name is a :class:`ScenarioError` naming ``key``.
    """
    if not isinstance(source, str) or not source:
        raise ScenarioError(key, source, "must name a scenario file or a bundled scenario ("
                            + ", ".join(BUNDLED) + ")")
    if not Path(source).suffix and source in BUNDLED:
        return source
    path = Path(source) if base_dir is None else base_dir.resolve() / source
    if not path.is_file():
        raise ScenarioError(key, source, "no such file (a relative path is taken from the "
                            "plan's folder); or a bundled name: " + ", ".join(BUNDLED))
    return str(path)


def _value_text(value: Any) -> str:
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return repr(value)
    text = str(value) if isinstance(value, int | str) else json.dumps(value, default=str)
    return re.sub(r"[^A-Za-z0-9._+-]", "_", text)


def sweep_cases(sweep: dict[str, Any]) -> list[BatchCase]:
    """The cartesian product of a ``[sweep]`` table (key -> list of values), named by value."""
    for key, values in sweep.items():
        if not isinstance(values, list) or not values:
            raise ScenarioError(f"sweep.{key}", values, "must be a non-empty list of values")
    keys = list(sweep)
    if not keys:
        return []
    short = [k.rsplit(".", 1)[-1] for k in keys]
    labels = [s if short.count(s) == 1 else re.sub(r"[^A-Za-z0-9._+-]", "_", k)
              for s, k in zip(short, keys, strict=True)]
    out = []
    for combo in itertools.product(*(sweep[k] for k in keys)):
        name = ",".join(f"{lab}={_value_text(v)}" for lab, v in zip(labels, combo, strict=True))
        out.append(BatchCase(name, tuple(zip(keys, combo, strict=True))))
    return out


def plan_from_dict(data: dict[str, Any], base_dir: Path | None = None,
                   name: str = "batch") -> BatchPlan:
    """A :class:`BatchPlan` from a parsed plan file; ``base_dir``: the folder of relative paths."""
    check_keys(data, "plan", ("batch", "sweep", "case"))
    head = as_table(data.get("batch"), "batch")
    check_keys(head, "batch", PLAN_KEYS["batch"])
    source = scenario_source(head.get("scenario"), "batch.scenario", base_dir)
    common = list(as_table(head.get("set", {}), "batch.set").items())
    cases = []
    entries = data.get("case", [])
    if not isinstance(entries, list):
        raise ScenarioError("case", entries, "must be a list of tables: [[case]]")
    for i, entry in enumerate(entries):
        entry = as_table(entry, f"case[{i}]")
        check_keys(entry, f"case[{i}]", PLAN_KEYS["case"])
        cname = check_name(entry.get("name"), f"case[{i}].name")
        cases.append(BatchCase(cname, tuple(as_table(entry.get("set", {}),
                                                  f"case[{i}].set").items())))
    cases += sweep_cases(as_table(data.get("sweep", {}), "sweep"))
    if not cases:
        raise ScenarioError("plan", "no cases", "give [[case]] entries and/or a [sweep] table")
    seen: set[str] = set()
    for c in cases:
        check_name(c.name, "case name")
        if c.name in seen:
            raise ScenarioError("case name", c.name, "must be unique within the plan")
        seen.add(c.name)
    return BatchPlan(source, tuple(BatchCase(c.name, tuple(common) + c.overrides) for c in cases),
                name)


def read_toml(path: Path) -> dict[str, Any]:
    """The parsed TOML file ``path`` (a missing, non-UTF-8 or invalid file: a ScenarioError)."""
    if not path.is_file():
        raise ScenarioError("plan", str(path), "no such file")
    try:
        return tomllib.loads(path.read_text(encoding="utf-8"))
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        raise ScenarioError("plan", str(path), f"is not valid TOML: {exc}") from None


def in_file(path: Path, exc: ScenarioError) -> ScenarioError:
    """``exc`` with its key prefixed by the name of the file ``path`` (one line, file and key)."""
    return ScenarioError(f"{path.name}: {exc.key}", exc.value, exc.allowed, exc.unit)


def load_plan(path: str | Path) -> BatchPlan:
    """Read and check a plan file (not yet its cases' scenarios: :func:`resolve_cases`)."""
    path = Path(path)
    data = read_toml(path)
    try:
        return plan_from_dict(data, path.parent, path.stem)
    except ScenarioError as exc:
        raise in_file(path, exc) from None


def scenario_digest(resolved: Scenario | dict[str, Any]) -> str:
    """SHA-256 of a resolved scenario as ``scenario.json`` holds it (key order ignored)."""
    data = json.loads(json.dumps(resolved, default=json_default))
    text = json.dumps(data, sort_keys=True, separators=(",", ":"))
    return hashlib.sha256(text.encode("utf-8")).hexdigest()


def resolve_case(plan: BatchPlan, case: BatchCase) -> ResolvedCase:
    """The validated scenario of ``case``; a problem names the case and the key.

    Validated as ``pilegroup scenario validate`` does: the scenario and its geometry
    (:func:`~pilegroup.geometry.adapter.resolve_geometry`), so that no case of a batch starts
    while another is refused for its input.
    """
    try:
        sc = load_scenario(plan.scenario, case.override_dict())
        resolve_geometry(sc)
    except ScenarioError as exc:
        raise ScenarioError(f"case {case.name!r}: {exc.key}", exc.value, exc.allowed,
                            exc.unit) from None
    return ResolvedCase(case, sc, scenario_digest(sc), estimated_cells(sc))


def resolve_cases(plan: BatchPlan) -> tuple[ResolvedCase, ...]:
    """Every case validated (the first problem is raised), in the plan's order."""
    return tuple(resolve_case(plan, c) for c in plan.cases)


def queue_order(cases: tuple[ResolvedCase, ...]) -> list[int]:
    """Indices of ``cases``, largest estimated mesh first (ties in the plan's order)."""
    return sorted(range(len(cases)), key=lambda i: (-cases[i].cost, i))


__all__ = ["BatchCase", "BatchPlan", "ResolvedCase", "as_table", "check_keys", "check_name",
           "in_file", "load_plan", "plan_from_dict", "queue_order", "read_toml", "resolve_case",
           "resolve_cases", "scenario_digest", "scenario_source", "sweep_cases"]
