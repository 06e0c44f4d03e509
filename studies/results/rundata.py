"""One run output folder, read and checked, for the figures and the Markdown summary.

Files: the CSV files of :mod:`pilegroup.studies.results.tables` (settlement, pile profiles, layer
history, pile loads, load-settlement curve, gauges), ``summary.json`` (may be partial;
``"complete": false`` when interrupted; ``"centre_pile"``) and ``scenario.json``, if present,
which names the load stages and the layers. The end of loading is the last ``settlement.csv``
time in a load stage (without scenario.json: a stage whose name contains "load"; without any:
the first output time after 0).

Any file may be missing (its table is ``None``, logged).

From ``scenario.json`` also: the piles, named by their place in the group
(:mod:`pilegroup.studies.results.pile_roles`) with their lengths (the depth axes end below the
deepest toe), the layers' depths, and the ``[reference]`` table of published values, if the
scenario has one (:class:`~pilegroup.model.reference.Reference`): without it nothing of a
publication is drawn or written.
"""

from __future__ import annotations

import dataclasses
import json
import logging
from pathlib import Path
from typing import Any

import numpy as np

from pilegroup.model import Piles, Reference, ScenarioError
from pilegroup.model.loader import build_dataclass
from pilegroup.studies.results.pile_roles import PileInfo, key_piles, name_piles
from pilegroup.studies.results.tables import (
    BENDING_CSV,
    CAP_MOTION_CSV,
    CAPACITY_CSV,
    GAUGES_CSV,
    HEADS_CSV,
    LAYER_HISTORY_CSV,
    LOAD_SETTLEMENT_CSV,
    LOADS_CSV,
    NEUTRAL_PLANE_CSV,
    PROFILES_CSV,
    SETTLEMENT_CSV,
    SETTLEMENT_PROFILES_CSV,
    TROUGH_CSV,
    Table,
    read_csv,
)

log = logging.getLogger(__name__)

#: The CSV files a run folder is read from, in this order.
RUN_FILES = (SETTLEMENT_CSV, PROFILES_CSV, LAYER_HISTORY_CSV, LOADS_CSV, LOAD_SETTLEMENT_CSV,
             GAUGES_CSV, NEUTRAL_PLANE_CSV, SETTLEMENT_PROFILES_CSV, TROUGH_CSV, CAPACITY_CSV,
             BENDING_CSV, CAP_MOTION_CSV, HEADS_CSV)

#: Default centre pile of a 3 x 3 group numbered row by row.
DEFAULT_CENTRE_PILE = 5


def select(table: Table, mask: np.ndarray) -> Table:
    """The rows of ``table`` where ``mask`` holds (or in the order of an index array)."""
    return {k: v[mask] for k, v in table.items()}


def _read_json(path: Path) -> dict[str, Any]:
    if not path.is_file():
        return {}
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError) as exc:
        log.warning("ignoring %s: %s", path, exc)
        return {}
    return data if isinstance(data, dict) else {}


@dataclasses.dataclass(frozen=True)
class RunData:
    """One run output folder, read and checked.

    ``profiles``, ``history`` and ``gauges`` hold the centre pile only (``centre_pile``: the
    pile nearest the group's plan centre, whose layer means are recorded after every step; it
    need not stand on the centre); ``all_profiles`` every pile.
    """

    out_dir: Path
    settlement: Table | None
    profiles: Table | None
    history: Table | None
    loads: Table | None
    load_settlement: Table | None
    summary: dict[str, Any]
    centre_pile: int
    t_load: float | None
    layer_names: dict[int, str]
    gauges: Table | None = None
    neutral: Table | None = None
    """``neutral_plane.csv``, every pile."""
    settlement_profiles: Table | None = None
    """``settlement_profiles.csv``, every pile and the free field (``pile = 0``)."""
    trough: Table | None = None
    """``surface_trough.csv``."""
    capacity: Table | None = None
    """``capacity.csv`` (a run with a capacity stage), the group and every pile."""
    bending: Table | None = None
    """``pile_bending.csv``, every pile; ``None`` when no pile bends (a vertical load only)."""
    cap_motion: Table | None = None
    """``cap_motion.csv``; ``None`` when the cap neither moves sideways nor rotates."""
    all_profiles: Table | None = None
    """``pile_profiles.csv``, every pile."""
    heads: Table | None = None
    """``pile_heads.csv``, every pile: the cap's action on each pile at its head."""
    piles: tuple[PileInfo, ...] = ()
    """Every pile named by its place, with its length (scenario.json; else the positions of
    ``pile_loads.csv`` without lengths; else none)."""
    layer_bottoms: tuple[float, ...] = ()
    """Depth of each layer's bottom (m), top down (scenario.json); the last is the block's."""
    reference: Reference | None = None
    """The scenario's published values (its ``[reference]`` table), if it has one."""
    scenario: dict[str, Any] = dataclasses.field(default_factory=dict)
    """``scenario.json`` as read (empty without it)."""

    @property
    def complete(self) -> bool | None:
        """``summary.json``'s ``complete`` flag (top level or ``solver``), ``None`` if absent."""
        for d in (self.summary, self.summary.get("solver") or {}):
            if isinstance(d, dict) and "complete" in d:
                return bool(d["complete"])
        return None

    def has(self, needs: str) -> bool:
        """Whether any of the tables ``needs`` names (``"history|profiles"``) was read."""
        return any(getattr(self, n) is not None for n in needs.split("|"))

    def pile(self, i: int) -> PileInfo:
        """Pile ``i`` (from 1) named by its place; ``pile i`` alone when the run does not say."""
        for p in self.piles:
            if p.number == i:
                return p
        return PileInfo(i, float("nan"), float("nan"))

    def pile_name(self, i: int) -> str:
        """``pile 5 (row 2, column 2, centre)``, or ``pile 5`` when its place is unknown."""
        p = self.pile(i)
        return p.name if np.isfinite(p.x) else f"pile {i}"

    @property
    def deepest_toe(self) -> float | None:
        """Depth of the deepest pile toe below the ground surface (m), if the run says."""
        lengths = [p.length for p in self.piles if p.length is not None]
        return max(lengths) if lengths else None

    def depth_limit(self, deepest_data: float) -> float:
        """The bottom of a depth axis: 10 % below the deepest toe, else below the data."""
        toe = self.deepest_toe
        return 1.1 * (toe if toe is not None else deepest_data)

    def head_forces(self) -> tuple[float, dict[int, float], str] | None:
        """The head force of every pile at the last output time: ``(t, {pile: kN}, source)``.

        The cap's action on the pile at its head (``pile_heads.csv``'s ``N_kN``) where the run
        has it, else ``pile_loads.csv``'s ``head_force_kN`` (the same number in a run folder
        that has both; a folder without ``pile_heads.csv`` is of a run without cap actions
        from before the heads were written); ``source`` says which, in words.
        """
        for table, column, source in (
                (self.heads, "N_kN", "the cap's action on the pile at its head, "
                                     "`pile_heads.csv`"),
                (self.loads, "head_force_kN", "the axial force at the pile's uppermost section, "
                                              "`pile_loads.csv`")):
            if table is not None:
                t = float(table["t_day"].max())
                m = table["t_day"] == t
                return t, {int(i): float(f) for i, f in zip(table["pile"][m], table[column][m],
                                                            strict=True)}, source
        return None

    def key_piles(self) -> list[tuple[PileInfo, str]]:
        """The piles the profile figures show and why (:func:`key_piles`), by head force."""
        last = self.head_forces()
        return key_piles(self.piles, last[1] if last else None)


def _centre_pile(summary: dict[str, Any], tables: list[Table | None]) -> int:
    for d in (summary, summary.get("solver") or {}):
        if isinstance(d, dict) and d.get("centre_pile") is not None:
            return int(d["centre_pile"])
    for t in tables:
        if t is not None and len(np.unique(t["pile"])) == 1:
            return int(t["pile"][0])
    return DEFAULT_CENTRE_PILE


def _end_of_loading(settlement: Table | None, scenario: dict[str, Any]) -> float | None:
    """Last output time in a load stage (names from scenario.json, else names with "load")."""
    if settlement is None:
        return None
    stages = scenario.get("stages") or []
    names = {s.get("name") for s in stages if isinstance(s, dict) and s.get("kind") == "load"}
    is_load = np.array([(s in names) if names else ("load" in s.lower())
                        for s in settlement["stage"]], dtype=bool)
    if is_load.any():
        return float(settlement["t_day"][is_load].max())
    positive = settlement["t_day"][settlement["t_day"] > 0]
    return float(positive.min()) if positive.size else None


def _read_tables(out_dir: Path) -> dict[str, Table | None]:
    """The :data:`RUN_FILES` of ``out_dir``; ``None`` for a missing or empty file.

    Raises :class:`ScenarioError` if the folder does not exist or holds none of them.
    """
    if not out_dir.is_dir():
        raise ScenarioError("OUT_DIR", str(out_dir), "no such folder")
    raw = {name: read_csv(out_dir / name) for name in RUN_FILES}
    if all(t is None for t in raw.values()):
        raise ScenarioError("OUT_DIR", str(out_dir),
                            f"holds none of {', '.join(RUN_FILES)}: not a run output folder")
    for name, t in raw.items():
        if t is None:
            log.info("%s not found in %s", name, out_dir)
        elif len(next(iter(t.values()))) == 0:
            log.info("%s has no data rows", name)
            raw[name] = None
    return raw


def _centre_only(name: str, t: Table | None, centre: int) -> Table | None:
    """The rows of pile ``centre`` in table ``t`` of file ``name`` (``None`` if none)."""
    sel = None if t is None else select(t, t["pile"] == centre)
    if sel is not None and len(sel["pile"]) == 0:
        log.info("%s has no rows for the centre pile %d", name, centre)
        sel = None
    return sel


def load_run(out_dir: Path) -> RunData:
    """Read and check every file of the contract in ``out_dir``.

    Raises :class:`ScenarioError` if the folder does not exist or holds none of the CSV files.
    """
    out_dir = Path(out_dir)
    raw = _read_tables(out_dir)
    summary = _read_json(out_dir / "summary.json")
    scenario = _read_json(out_dir / "scenario.json")
    centre = _centre_pile(summary, [raw[PROFILES_CSV], raw[LAYER_HISTORY_CSV]])
    profiles = _centre_only(PROFILES_CSV, raw[PROFILES_CSV], centre)
    history = _centre_only(LAYER_HISTORY_CSV, raw[LAYER_HISTORY_CSV], centre)
    names: dict[int, str] = {}
    for j, lay in enumerate(scenario.get("layers") or [], start=1):
        if isinstance(lay, dict) and lay.get("name"):
            names[j] = str(lay["name"])
    if history is not None:
        names.update({int(j): str(n) for j, n in zip(history["layer"], history["layer_name"],
                                                      strict=True)})
    return RunData(out_dir, raw[SETTLEMENT_CSV], profiles, history, raw[LOADS_CSV],
                   raw[LOAD_SETTLEMENT_CSV], summary, centre,
                   _end_of_loading(raw[SETTLEMENT_CSV], scenario), names,
                   _centre_only(GAUGES_CSV, raw[GAUGES_CSV], centre), raw[NEUTRAL_PLANE_CSV],
                   raw[SETTLEMENT_PROFILES_CSV], raw[TROUGH_CSV], raw[CAPACITY_CSV],
                   _if_lateral(raw[BENDING_CSV], ("Mx_kNm", "My_kNm")),
                   _if_lateral(raw[CAP_MOTION_CSV], ("ux_m", "uy_m", "rx_rad", "ry_rad")),
                   raw[PROFILES_CSV], raw[HEADS_CSV], _piles(scenario, raw),
                   _layer_bottoms(scenario), _part(Reference, scenario, "reference"), scenario)


def _part[T](cls: type[T], scenario: dict[str, Any], key: str) -> T | None:
    """The scenario part ``key`` of scenario.json as ``cls``; None if absent or unreadable."""
    data = scenario.get(key)
    if data is None:
        return None
    try:
        return build_dataclass(cls, data, key)
    except ScenarioError as exc:
        log.warning("ignoring %s of scenario.json: %s", key, exc)
        return None


def _piles(scenario: dict[str, Any], raw: dict[str, Table | None]) -> tuple[PileInfo, ...]:
    """The piles named by place: from scenario.json, else from a table's positions."""
    piles = _part(Piles, scenario, "piles")
    if piles is not None:
        return name_piles(piles.xy, piles.lengths)
    for name in (HEADS_CSV, LOADS_CSV):
        t = raw[name]
        if t is not None:
            first = t["t_day"] == t["t_day"].min()
            order = np.argsort(t["pile"][first])
            return name_piles(np.column_stack([t["x_m"][first][order], t["y_m"][first][order]]))
    return ()


def _layer_bottoms(scenario: dict[str, Any]) -> tuple[float, ...]:
    """Each layer's bottom depth (m) from scenario.json; the last one's is the block's."""
    layers = [lay for lay in scenario.get("layers") or [] if isinstance(lay, dict)]
    depth = (scenario.get("site") or {}).get("depth_m")
    out, z = [], 0.0
    for lay in layers:
        h = lay.get("thickness_m")
        if h is None:
            if depth is None:
                break
            z = float(depth)
        else:
            z += float(h)
        out.append(z)
    return tuple(out)


def _if_lateral(t: Table | None, columns: tuple[str, ...]) -> Table | None:
    """``t`` when any of its ``columns`` is non-zero (a lateral response), else ``None``."""
    if t is None or not any(np.any(t[c] != 0.0) for c in columns if c in t):
        return None
    return t


def layer_series(run: RunData, column: str) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Layer-mean ``column`` of the centre pile against time: ``{layer: (t_day, value)}``.

    From ``layer_history.csv``; without it, the mean over the stations of ``pile_profiles.csv``
    in each layer at each output time.
    """
    out: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    if run.history is not None:
        h = run.history
        for j in np.unique(h["layer"]):
            m = h["layer"] == j
            order = np.argsort(h["t_day"][m], kind="stable")
            out[int(j)] = (h["t_day"][m][order], h[column][m][order])
    elif run.profiles is not None:
        p = run.profiles
        for j in np.unique(p["layer"]):
            m = p["layer"] == j
            ts = np.unique(p["t_day"][m])
            out[int(j)] = (ts, np.array([p[column][m & (p["t_day"] == t)].mean() for t in ts]))
    return out


def pile_loads_last(run: RunData) -> tuple[float, Table] | None:
    """Time and rows of ``pile_loads.csv`` at its last output time (sorted by pile)."""
    if run.loads is None:
        return None
    t = float(run.loads["t_day"].max())
    sel = select(run.loads, run.loads["t_day"] == t)
    return t, select(sel, np.argsort(sel["pile"]))


def layer_label(run: RunData, j: int) -> str:
    """``"j name"`` of layer ``j`` (1-based), or ``"layer j"`` without a name."""
    return f"{j} {run.layer_names[j]}" if j in run.layer_names else f"layer {j}"


def zero_note(run: RunData) -> str:
    """A title note when every relative displacement is zero (tied interface), else ``""``."""
    src = run.history if run.history is not None else run.profiles
    if src is not None and np.all(np.abs(src["relative_displacement_m"]) < 1e-12):
        return " (all zero: tied interface)"
    return ""
