"""The scenario of a run in one Markdown table, read from its ``scenario.json``.

One row per part: the site, each layer (its depths, its soil model and that model's key
parameters), the piles, the cap, each stage (its kind and the keys it sets), the time and the
pile-soil interface. Only the keys a scenario sets are written; a key's unit is its name's
suffix (``cap_load_kN`` -> ``cap_load 500 kN``). Pure: a dict in, text out.
"""

from __future__ import annotations

from typing import Any

#: Unit suffixes of the scenario keys, longest first, and how the report writes them.
_UNITS = (("_kN_per_m3", "kN/m³"), ("_m_per_day", "m/day"), ("_MPa_day", "MPa day"),
          ("_kg_per_m3", "kg/m³"), ("_kNm", "kN m"), ("_kPa", "kPa"), ("_MPa", "MPa"),
          ("_kN", "kN"), ("_deg", "°"), ("_day", "day"), ("_m", "m"))

#: The key parameters of each soil model (besides unit weight and permeability).
MODEL_KEYS: dict[str, tuple[str, ...]] = {
    "mohr_coulomb": ("E_MPa", "nu", "phi_deg", "c_kPa", "psi_deg"),
    "drucker_prager": ("E_MPa", "nu", "phi_deg", "c_kPa", "psi_deg"),
    "linear_elastic": ("E_MPa", "nu"),
    "modified_cam_clay": ("lam", "kappa", "M", "phi_cs_deg", "e0", "nu", "OCR", "POP_kPa"),
    "soft_soil_creep": ("lambda_star", "kappa_star", "mu_star", "M", "phi_cs_deg", "nu_ur",
                        "OCR", "POP_kPa", "tau_ref_day"),
}
#: What every layer shows after its model's keys (where set and not zero).
_LAYER_KEYS = ("gamma_kN_per_m3", "k_m_per_day", "k_h_m_per_day", "K0",
               "excess_pore_pressure_ratio", "excess_pore_pressure_kPa")
#: Model names in words.
MODEL_NAMES = {"mohr_coulomb": "Mohr–Coulomb", "drucker_prager": "Drucker–Prager",
               "linear_elastic": "linear elastic", "modified_cam_clay": "Modified Cam Clay",
               "soft_soil_creep": "Soft Soil Creep"}
#: The stage kinds that move the ground around the piles (ground actions).
GROUND_KINDS = ("surcharge", "groundwater")


def number(v: float) -> str:
    """``v`` in four significant figures, without a trailing ``.0``."""
    return f"{float(v):.4g}"


def key_value(key: str, value: Any) -> str:
    """``cap_load 500 kN`` of the key ``cap_load_kN``; lists as ``a × b``; booleans yes/no."""
    name, unit = key, ""
    for suffix, words in _UNITS:
        if key.endswith(suffix):
            name, unit = key[: -len(suffix)], words
            break
    if isinstance(value, bool):
        text = "yes" if value else "no"
    elif isinstance(value, int | float):
        text = number(value)
    elif isinstance(value, list | tuple):
        parts = [number(x) if isinstance(x, int | float) else str(x) for x in value]
        text = " × ".join(parts) if len(parts) == 2 else "(" + ", ".join(parts) + ")"
    else:
        text = str(value)
    return f"{name} {text}" + ("" if not unit else unit if unit == "°" else f" {unit}")


def _set_keys(part: dict[str, Any], keys: tuple[str, ...] | None = None,
              skip: tuple[str, ...] = ()) -> str:
    """The keys of ``part`` that are set (not None, not a nested table), joined by commas."""
    keys = tuple(part) if keys is None else keys
    out = []
    for k in keys:
        v = part.get(k)
        if k in skip or v is None or isinstance(v, dict) or \
                (isinstance(v, list) and v and isinstance(v[0], dict)):
            continue
        out.append(key_value(k, v))
    return ", ".join(out) or "-"


def layer_rows(scenario: dict[str, Any]) -> list[tuple[str, str]]:
    """One row per layer: its depths, its model and that model's key parameters."""
    default = (scenario.get("soil") or {}).get("model") or "mohr_coulomb"
    depth = (scenario.get("site") or {}).get("depth_m")
    rows, top = [], 0.0
    for j, lay in enumerate(scenario.get("layers") or [], start=1):
        if not isinstance(lay, dict):
            continue
        h = lay.get("thickness_m")
        bottom = top + float(h) if h is not None else (float(depth) if depth else None)
        where = f"{number(top)}–{number(bottom)} m" if bottom is not None else \
            f"from {number(top)} m"
        model = lay.get("model") or default
        keys = MODEL_KEYS.get(model, ("E_MPa", "nu"))
        extra = tuple(k for k in _LAYER_KEYS if lay.get(k))
        drained = "; drained" if lay.get("drained") else ""
        rows.append((f"layer {j}: {lay.get('name') or '-'}",
                     f"{where}; {MODEL_NAMES.get(model, model)}; "
                     f"{_set_keys(lay, keys + extra)}{drained}"))
        top = bottom if bottom is not None else top
    return rows


def _piles_row(piles: dict[str, Any]) -> str:
    if piles.get("layout"):
        return f"layout of {len(piles['layout'])} piles; " + _set_keys(
            piles, ("embedment_m",))
    n = len(piles["positions_m"]) if piles.get("positions_m") else None
    grid = piles.get("grid")
    if n is None and grid:
        n = int(grid[0]) * int(grid[1])
    head = f"{n} pile{'s' if n != 1 else ''}; " if n else ""
    return head + _set_keys(piles, skip=("installation",) if not piles.get("installation")
                            else ())


def _stage_rows(scenario: dict[str, Any]) -> list[tuple[str, str]]:
    rows = []
    for i, st in enumerate(scenario.get("stages") or [], start=1):
        if isinstance(st, dict):
            keys = _set_keys(st, skip=("name", "kind"))
            rows.append((f"stage {i}: {st.get('name', '-')}",
                         str(st.get("kind", "-")) + (f"; {keys}" if keys != "-" else "")))
    return rows


def scenario_rows(scenario: dict[str, Any]) -> list[tuple[str, str]]:
    """The rows ``(part, what it is)`` of the scenario table."""
    rows = [("scenario", str(scenario.get("name", "-")))]
    if scenario.get("description"):
        rows.append(("description", str(scenario["description"])))
    rows.append(("site", _set_keys(scenario.get("site") or {})))
    rows += layer_rows(scenario)
    piles = scenario.get("piles")
    rows.append(("piles", _piles_row(piles) if isinstance(piles, dict) else "-"))
    cap = scenario.get("cap")
    rows.append(("cap", _set_keys(cap) if isinstance(cap, dict) else "none (pile heads loaded)"))
    rows += _stage_rows(scenario)
    rows.append(("time", _set_keys(scenario.get("time") or {})))
    interface = scenario.get("interface") or {}
    if interface:
        rows.append(("pile–soil interface", _set_keys(interface, ("mode", "quadrature"))))
    return rows


def escape_cell(text: str) -> str:
    """``text`` safe in a Markdown table cell (no pipe, no line break)."""
    return text.replace("|", "\\|").replace("\n", " ")


def scenario_table(scenario: dict[str, Any]) -> list[str]:
    """The scenario section: one Markdown table (a note without ``scenario.json``)."""
    lines = ["## Scenario", ""]
    if not scenario:
        return lines + ["No `scenario.json` in the run folder: the scenario is unknown.", ""]
    lines += ["| part | value |", "| --- | --- |"]
    lines += [f"| {escape_cell(a)} | {escape_cell(b)} |" for a, b in scenario_rows(scenario)]
    return lines + [""]


def moves_ground(scenario: dict[str, Any]) -> bool:
    """Whether the ground moves around the piles.

    A surcharge or groundwater stage, or a layer that starts with excess pore pressure (still
    consolidating).
    """
    if any(isinstance(st, dict) and st.get("kind") in GROUND_KINDS
           for st in scenario.get("stages") or []):
        return True
    return any(isinstance(lay, dict) and (lay.get("excess_pore_pressure_ratio")
                                          or lay.get("excess_pore_pressure_kPa"))
               for lay in scenario.get("layers") or [])
