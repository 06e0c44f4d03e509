"""Load cases and combinations (TOML): each combination a case of a batch.

The combinations file (README.md, "Load combinations"; example:
docs/examples/single_pile_combinations.toml)::

    [combinations]
    scenario = "single_pile"          # bundled name, or a path relative to this file's folder
    stage = "loading"                 # the load stage whose cap actions the combinations set
    set = { "outputs.xdmf" = false }  # optional: set in every combination

    [load_cases.permanent]            # a load case: cap actions at the stage's end
    cap_load_kN = 400.0
    [load_cases.braking]
    Fx_kN = 50.0
    My_kNm = 20.0

    [[combination]]                   # repeatable: factors on load cases
    name = "ULS_braking"
    factors = { permanent = 1.35, braking = 1.5 }

A load case gives any of the cap actions :data:`COMPONENTS` (global axes, z up, moments by the
right-hand rule about the scenario's reference point, the keys of a load stage) and, for the
vertical, ``cap_load_kN`` (downward positive) instead of ``Fz_kN`` (``Fz_kN = -cap_load_kN``).
A combination's component is the sum over its load cases of factor x the case's component (a
component a case does not give is 0).

A combination is a batch case named by the combination (its run folder) whose scenario is the
base scenario (with ``set``) and the combination's actions set on the named load stage, as
``--set stages[i].KEY=VALUE``: the vertical as ``cap_load_kN = -Fz_kN`` (as ``Fz_kN`` when the
base stage gives the vertical that way), which must not be negative; every other component that
a load case or the base stage gives (0 where no load case gives it: a combination replaces the
stage's actions). The keys go to the scenario as they are, so the scenario decides which
actions a load stage takes.

Every problem is a one-line :class:`~pilegroup.errors.ScenarioError` naming the file and the
key (``combos.toml: combination[1].factors.wind = 1.5: no such load case; ...``), and every
combination's scenario is built and validated when the file is read
(``combos.toml: combination 'ULS': stages[1].cap_load_kN = ...``).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pilegroup.errors import ScenarioError
from pilegroup.geometry.adapter import resolve_geometry
from pilegroup.model import BUNDLED, Scenario, bundled_text, load_scenario
from pilegroup.model.loader import apply_overrides
from pilegroup.studies.batch.batch_plan import (
    NAME,
    RESERVED,
    BatchCase,
    BatchPlan,
    as_table,
    check_keys,
    check_name,
    in_file,
    read_toml,
    scenario_source,
)
from pilegroup.studies.results.envelope import ENVELOPE_FILES

#: The cap actions of a load stage (global axes, z up, right-hand rule), in this order.
COMPONENTS = ("Fx_kN", "Fy_kN", "Fz_kN", "Mx_kNm", "My_kNm", "Mz_kNm")
#: The vertical cap load, downward positive: ``Fz_kN = -cap_load_kN``.
VERTICAL = "cap_load_kN"
#: The keys a load case may give.
CASE_KEYS = (*COMPONENTS, VERTICAL)
#: Tables of a combinations file and the keys each may hold.
FILE_KEYS = {"file": ("combinations", "load_cases", "combination"),
             "combinations": ("scenario", "stage", "set"), "combination": ("name", "factors")}
#: Names no combination may take: the batch's and the envelope's files in the folder.
RESERVED_NAMES = (*RESERVED, *ENVELOPE_FILES)


@dataclass(frozen=True)
class Combination:
    """A named combination: load case -> factor."""

    name: str
    factors: tuple[tuple[str, float], ...]


@dataclass(frozen=True)
class CombinationPlan:
    """A base scenario, its load stage, the load cases and the combinations of a file.

    ``stage_index``: the stage's index in ``stages``; ``vertical_key``: ``cap_load_kN`` or
    ``Fz_kN``, as the base stage gives the vertical; ``stage_components``: the other components
    the base stage gives.
    """

    scenario: str
    stage: str
    stage_index: int
    vertical_key: str
    stage_components: tuple[str, ...]
    common: tuple[tuple[str, Any], ...]
    load_cases: Mapping[str, Mapping[str, float]]
    combinations: tuple[Combination, ...]
    name: str = "combinations"

    def actions(self, combination: Combination) -> dict[str, float]:
        """Every component of :data:`COMPONENTS` of ``combination`` (0 where no case gives it)."""
        total = dict.fromkeys(COMPONENTS, 0.0)
        for case, factor in combination.factors:
            for key, value in self.load_cases[case].items():
                total[key] += factor * value
        return {k: _tidy(v) for k, v in total.items()}

    def stage_values(self, combination: Combination) -> dict[str, float]:
        """The keys of the load stage set by ``combination`` and their values."""
        given = {k for case in self.load_cases.values() for k in case} | set(
            self.stage_components)
        acts = self.actions(combination)
        out = {}
        for key in COMPONENTS:
            if key == "Fz_kN":
                vertical = acts[key] if self.vertical_key == key else _tidy(-acts[key])
                if self.vertical_key == VERTICAL and vertical < 0.0:
                    raise ScenarioError(
                        f"combination {combination.name!r}: {VERTICAL}", vertical,
                        f"the combined vertical action is upward (Fz_kN = {acts[key]:g}); a "
                        "load stage's cap load must be >= 0: check the factors and the signs "
                        "of the load cases", "kN")
                out[self.vertical_key] = vertical
            elif key in given:
                out[key] = acts[key]
        return out

    def overrides(self, combination: Combination) -> tuple[tuple[str, Any], ...]:
        """The scenario keys of ``combination``'s case: ``set``, then the stage's actions."""
        stage = f"stages[{self.stage_index}]"
        return self.common + tuple((f"{stage}.{k}", v)
                                   for k, v in self.stage_values(combination).items())

    def batch_plan(self) -> BatchPlan:
        """The batch: one case per combination, named by it."""
        return BatchPlan(self.scenario, tuple(BatchCase(c.name, self.overrides(c))
                                              for c in self.combinations), self.name)


def _tidy(x: float) -> float:
    """``x`` to 12 significant digits (no ``1.35 * 400 = 540.0000000000001``), never -0."""
    return float(f"{x:.12g}") + 0.0


def _number(value: object, key: str, unit: str) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or not math.isfinite(value):
        raise ScenarioError(key, value, "must be a finite number", unit)
    return float(value)


def _load_case(name: str, table: object) -> dict[str, float]:
    """A load case's components (``cap_load_kN`` as ``Fz_kN``)."""
    key = f"load_cases.{name}"
    if not NAME.fullmatch(name):
        raise ScenarioError(key, name, "a load case's name must be letters, digits and ._=,+-")
    case = as_table(table, key)
    check_keys(case, key, CASE_KEYS)
    if not case:
        raise ScenarioError(key, case, "give at least one action: " + ", ".join(CASE_KEYS))
    if VERTICAL in case and "Fz_kN" in case:
        raise ScenarioError(f"{key}.{VERTICAL}", case[VERTICAL],
                            "give the vertical once: cap_load_kN (down positive) or Fz_kN (up "
                            "positive)", "kN")
    out = {}
    for k, v in case.items():
        value = _number(v, f"{key}.{k}", "kNm" if k.endswith("kNm") else "kN")
        out["Fz_kN" if k == VERTICAL else k] = -value if k == VERTICAL else value
    return out


def _combination(i: int, entry: object, cases: Mapping[str, Any]) -> Combination:
    key = f"combination[{i}]"
    entry = as_table(entry, key)
    check_keys(entry, key, FILE_KEYS["combination"])
    name = check_name(entry.get("name"), f"{key}.name", RESERVED_NAMES)
    factors = as_table(entry.get("factors"), f"{key}.factors")
    if not factors:
        raise ScenarioError(f"{key}.factors", factors, "give at least one factor: "
                            "{ load_case = factor, ... }")
    for case, f in factors.items():
        if case not in cases:
            raise ScenarioError(f"{key}.factors.{case}", f, "no such load case; load cases: "
                                + ", ".join(cases))
        _number(f, f"{key}.factors.{case}", "-")
    return Combination(name, tuple((c, float(f)) for c, f in factors.items()))


def _combinations(data: dict[str, Any], cases: Mapping[str, Any]) -> tuple[Combination, ...]:
    entries = data.get("combination", [])
    if not isinstance(entries, list):
        raise ScenarioError("combination", entries, "must be a list of tables: [[combination]]")
    out = tuple(_combination(i, e, cases) for i, e in enumerate(entries))
    if not out:
        raise ScenarioError("combination", "none", "give [[combination]] entries with a name "
                            "and factors")
    seen: set[str] = set()
    for c in out:
        if c.name in seen:
            raise ScenarioError("combination name", c.name, "must be unique within the file")
        seen.add(c.name)
    return out


def _base(source: str, common: dict[str, Any]) -> Scenario:
    try:
        return load_scenario(source, common)
    except ScenarioError as exc:
        raise ScenarioError(f"base scenario: {exc.key}", exc.value, exc.allowed,
                            exc.unit) from None


def _stage_index(sc: Scenario, name: object) -> int:
    loads = [s.name for s in sc.stages if s.kind == "load"]
    hint = f"the scenario's load stages: {', '.join(loads) or 'none'}"
    if not isinstance(name, str):
        raise ScenarioError("combinations.stage", name, f"must name a load stage; {hint}")
    for i, s in enumerate(sc.stages):
        if s.name == name:
            if s.kind != "load":
                raise ScenarioError("combinations.stage", name,
                                    f"is a {s.kind} stage, not a load stage; {hint}")
            return i
    raise ScenarioError("combinations.stage", name, f"no stage of that name; {hint}")


def _raw_stage(source: str, common: dict[str, Any], index: int) -> dict[str, Any]:
    """The base stage as the TOML gives it (which keys it spells its actions with)."""
    bundled = not Path(source).suffix and source in BUNDLED
    text = bundled_text(source) if bundled else Path(source).read_text(encoding="utf-8")
    stage = apply_overrides(tomllib.loads(text), common)["stages"][index]
    return stage if isinstance(stage, dict) else {}


def combination_plan_from_dict(data: dict[str, Any], base_dir: Path | None = None,
                               name: str = "combinations") -> CombinationPlan:
    """A :class:`CombinationPlan` from a parsed file (``base_dir``: of relative paths)."""
    check_keys(data, "file", FILE_KEYS["file"])
    head = as_table(data.get("combinations"), "combinations")
    check_keys(head, "combinations", FILE_KEYS["combinations"])
    source = scenario_source(head.get("scenario"), "combinations.scenario", base_dir)
    common = dict(as_table(head.get("set", {}), "combinations.set"))
    table = as_table(data.get("load_cases"), "load_cases")
    if not table:
        raise ScenarioError("load_cases", table, "give at least one [load_cases.NAME] table")
    cases = {k: _load_case(k, v) for k, v in table.items()}
    combinations = _combinations(data, cases)
    index = _stage_index(_base(source, common), head.get("stage"))
    raw = _raw_stage(source, common, index)
    plan = CombinationPlan(source, str(head["stage"]), index,
                           "Fz_kN" if "Fz_kN" in raw else VERTICAL,
                           tuple(k for k in COMPONENTS if k in raw and k != "Fz_kN"),
                           tuple(common.items()), cases, combinations, name)
    for c in combinations:
        plan.stage_values(c)  # an upward vertical is an error of the file
    return plan


def check_scenarios(plan: CombinationPlan) -> None:
    """Build and validate every combination's scenario; a problem names the combination.

    Validated as ``pilegroup scenario validate`` does: the scenario and its geometry.
    """
    for c in plan.combinations:
        try:
            resolve_geometry(load_scenario(plan.scenario, dict(plan.overrides(c))))
        except ScenarioError as exc:
            raise ScenarioError(f"combination {c.name!r}: {exc.key}", exc.value, exc.allowed,
                                exc.unit) from None


def load_combination_plan(path: str | Path) -> CombinationPlan:
    """Read and check a combinations file, every combination's scenario included."""
    path = Path(path)
    data = read_toml(path)
    try:
        plan = combination_plan_from_dict(data, path.parent, path.stem)
        check_scenarios(plan)
    except ScenarioError as exc:
        raise in_file(path, exc) from None
    return plan


__all__ = ["CASE_KEYS", "COMPONENTS", "RESERVED_NAMES", "VERTICAL", "Combination",
           "CombinationPlan", "check_scenarios", "combination_plan_from_dict",
           "load_combination_plan"]
