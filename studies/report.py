"""Post-processing of a finished (or interrupted) run: CSV files to PNG plots and Markdown.

Input is a run output folder (the data contract; depths in m below the ground surface, positive
down; forces kN; stresses kPa; displacements m):

* ``settlement.csv``: ``t_day,stage,settlement_m`` (cap settlement, down positive);
* ``pile_profiles.csv``: ``t_day,pile,depth_m,layer,axial_force_kN,shaft_friction_kPa,
  relative_displacement_m`` (axial force compression positive; friction positive = the soil
  supports the pile; relative displacement = pile minus adjacent soil settlement, positive = the
  pile moves down relative to the soil);
* ``layer_history.csv``: ``t_day,pile,layer,layer_name,depth_top_m,depth_bottom_m,
  shaft_friction_kPa,relative_displacement_m,viscoplastic_slip_m,normal_traction_kPa`` (layer
  means on the shaft, every accepted step);
* ``pile_loads.csv``: ``t_day,pile,x_m,y_m,head_force_kN``;
* ``summary.json`` (may be partial; ``"complete": false`` when interrupted; ``"centre_pile"``);
* ``results*.xdmf``/``.h5`` for the 3D view (see :mod:`pilegroup.studies.view3d`).

``scenario.json``, if present, names the load stages and the layers. The end of loading is the
last ``settlement.csv`` time in a load stage (without scenario.json: a stage whose name contains
"load"; without any: the first output time after 0).

Any file may be missing: its figures are skipped (logged). A CSV with a wrong header or a
non-numeric value raises :class:`~pilegroup.model.ScenarioError` naming the file, the column and
the columns required (the CLI exits with code 2).
"""

from __future__ import annotations

import csv
import dataclasses
import json
import logging
import os
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from pilegroup.model import ScenarioError
from pilegroup.studies.view3d import FILE as VIEW3D
from pilegroup.studies.view3d import write_view3d

log = logging.getLogger(__name__)

Table = dict[str, np.ndarray]

#: Required columns of each CSV of the contract (extra columns are ignored).
COLUMNS: dict[str, tuple[str, ...]] = {
    "settlement.csv": ("t_day", "stage", "settlement_m"),
    "pile_profiles.csv": ("t_day", "pile", "depth_m", "layer", "axial_force_kN",
                          "shaft_friction_kPa", "relative_displacement_m"),
    "layer_history.csv": ("t_day", "pile", "layer", "layer_name", "depth_top_m",
                          "depth_bottom_m", "shaft_friction_kPa", "relative_displacement_m",
                          "viscoplastic_slip_m", "normal_traction_kPa"),
    "pile_loads.csv": ("t_day", "pile", "x_m", "y_m", "head_force_kN"),
}
TEXT_COLUMNS = frozenset({"stage", "layer_name"})

#: The soft layers of Table 1 of the paper: (1) clay, (2) mud, (3) mucky clay.
SOFT_LAYERS = (1, 2, 3)
#: The paper's "0 days to 89 days" early period (Section 2, text on Figures 6-7; Section 5).
EARLY_DAY = 89.0
#: Default centre pile of a 3 x 3 group numbered row by row.
DEFAULT_CENTRE_PILE = 5
#: A change smaller than this fraction of the larger magnitude counts as no change.
REL_TOL = 1e-3

#: Cap settlement computed by the paper with ABAQUS, cm, by mesh size at the pile surface (m):
#: Section 5, Table 2 "Settlement of pile foundation calculated by numerical simulation with
#: different mesh sizes". The paper adopts 0.3 m ("the optimal mesh size ... is 0.3m"). The table
#: states no time; the simulation runs 317 days (Section 5). The paper reports no *measured*
#: settlement of the pier (its field data are strains, friction and relative displacement).
PAPER_SETTLEMENT_CM: dict[float, float] = {1.0: 36.5, 0.8: 35.2, 0.6: 34.6, 0.3: 30.3, 0.1: 30.2}
PAPER_MESH_M = 0.3


def _columns_error(path: Path, header: list[str], problem: str) -> ScenarioError:
    required = ", ".join(COLUMNS[path.name])
    return ScenarioError(f"{path} header", ",".join(header),
                         f"{problem}; required columns: {required}")


def read_csv(path: Path) -> Table | None:
    """Columns of a contract CSV as arrays (text or float); ``None`` if the file does not exist.

    Raises :class:`ScenarioError` for an empty file, a missing column, a short row or a
    non-numeric value, naming the file, the column and the columns required.
    """
    if not path.is_file():
        return None
    with path.open(newline="", encoding="utf-8") as fh:
        rows = [r for r in csv.reader(fh) if any(x.strip() for x in r)]
    header = [h.strip() for h in rows[0]] if rows else []
    if not header:
        raise _columns_error(path, header, "no header row")
    missing = [c for c in COLUMNS[path.name] if c not in header]
    if missing:
        raise _columns_error(path, header, f"missing column {missing[0]!r}")
    body = rows[1:]
    for n, row in enumerate(body, start=2):
        if len(row) < len(header):
            raise ScenarioError(f"{path} row {n}", ",".join(row),
                                f"{len(row)} fields, the header has {len(header)}")
    table: Table = {}
    for c in COLUMNS[path.name]:
        i = header.index(c)
        if c in TEXT_COLUMNS:
            table[c] = np.array([r[i].strip() for r in body], dtype=str)
            continue
        vals = np.empty(len(body))
        for n, row in enumerate(body, start=2):
            try:
                vals[n - 2] = float(row[i])
            except ValueError:
                raise ScenarioError(f"{path} row {n}", row[i].strip(),
                                    f"column {c!r} must be a number") from None
        table[c] = vals
    return table


def _select(table: Table, mask: np.ndarray) -> Table:
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
    """One run output folder, read and checked; pile tables hold the centre pile only."""

    out_dir: Path
    settlement: Table | None
    profiles: Table | None
    history: Table | None
    loads: Table | None
    summary: dict[str, Any]
    centre_pile: int
    t_load: float | None
    layer_names: dict[int, str]

    @property
    def complete(self) -> bool | None:
        """``summary.json``'s ``complete`` flag (top level or ``solver``), ``None`` if absent."""
        for d in (self.summary, self.summary.get("solver") or {}):
            if isinstance(d, dict) and "complete" in d:
                return bool(d["complete"])
        return None


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


def load_run(out_dir: Path) -> RunData:
    """Read and check every file of the contract in ``out_dir``.

    Raises :class:`ScenarioError` if the folder does not exist or holds none of the CSV files.
    """
    out_dir = Path(out_dir)
    if not out_dir.is_dir():
        raise ScenarioError("OUT_DIR", str(out_dir), "no such folder")
    raw = {name: read_csv(out_dir / name) for name in COLUMNS}
    if all(t is None for t in raw.values()):
        raise ScenarioError("OUT_DIR", str(out_dir),
                            f"holds none of {', '.join(COLUMNS)}: not a run output folder")
    for name, t in raw.items():
        if t is None:
            log.info("%s not found in %s", name, out_dir)
        elif len(t["t_day"]) == 0:
            log.info("%s has no data rows", name)
            raw[name] = None
    summary = _read_json(out_dir / "summary.json")
    scenario = _read_json(out_dir / "scenario.json")
    profiles, history = raw["pile_profiles.csv"], raw["layer_history.csv"]
    centre = _centre_pile(summary, [profiles, history])
    centre_only: dict[str, Table | None] = {}
    for name, t in (("pile_profiles.csv", profiles), ("layer_history.csv", history)):
        sel = None if t is None else _select(t, t["pile"] == centre)
        if sel is not None and len(sel["t_day"]) == 0:
            log.info("%s has no rows for the centre pile %d", name, centre)
            sel = None
        centre_only[name] = sel
    names: dict[int, str] = {}
    for j, lay in enumerate(scenario.get("layers") or [], start=1):
        if isinstance(lay, dict) and lay.get("name"):
            names[j] = str(lay["name"])
    h = centre_only["layer_history.csv"]
    if h is not None:
        names.update({int(j): str(n) for j, n in zip(h["layer"], h["layer_name"], strict=True)})
    return RunData(out_dir, raw["settlement.csv"], centre_only["pile_profiles.csv"], h,
                   raw["pile_loads.csv"], summary, centre,
                   _end_of_loading(raw["settlement.csv"], scenario), names)


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


def _at(t: np.ndarray, v: np.ndarray, tq: float | None) -> float | None:
    """``v`` interpolated at ``tq``; ``None`` outside the data (1e-9 day slack)."""
    if tq is None or t.size == 0 or tq < t[0] - 1e-9 or tq > t[-1] + 1e-9:
        return None
    return float(np.interp(tq, t, v))


def _layer_label(run: RunData, j: int) -> str:
    return f"{j} {run.layer_names[j]}" if j in run.layer_names else f"layer {j}"


# ---------------------------------------------------------------------------------------- plots

def _profile_figure(run: RunData, column: str, scale: float, xlabel: str, title: str) -> Figure:
    assert run.profiles is not None
    p = run.profiles
    fig = Figure(figsize=(6.0, 7.0))
    ax = fig.subplots()
    times = np.unique(p["t_day"])
    colors = [(0.1 + 0.8 * k / max(len(times) - 1, 1)) for k in range(len(times))]
    for t, c in zip(times, colors, strict=True):
        m = p["t_day"] == t
        order = np.argsort(p["depth_m"][m])
        ax.plot(scale * p[column][m][order], p["depth_m"][m][order], marker=".",
                color=_cmap(c), label=f"t = {t:g} d")
    if run.history is not None:
        for d in np.unique(run.history["depth_bottom_m"]):
            ax.axhline(d, color="0.8", lw=0.6, zorder=0)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.invert_yaxis()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("depth below ground surface (m)")
    ax.set_title(f"{title}, centre pile {run.centre_pile}")
    ax.legend(fontsize="small")
    ax.grid(alpha=0.3)
    return fig


def _cmap(x: float) -> tuple[float, float, float, float]:
    from matplotlib import colormaps

    return colormaps["viridis"](x)


def _time_figure(run: RunData, column: str, scale: float, ylabel: str, title: str) -> Figure:
    series = layer_series(run, column)
    fig = Figure(figsize=(8.5, 5.0))
    ax = fig.subplots()
    for j, (t, v) in series.items():
        ax.plot(t, scale * v, label=_layer_label(run, j), lw=2.0 if j in SOFT_LAYERS else 1.0)
    tmax = max((float(t[-1]) for t, _ in series.values()), default=0.0)
    if tmax > EARLY_DAY:
        ax.axvline(EARLY_DAY, color="0.5", ls=":", lw=0.8)
        ax.text(EARLY_DAY, 1.0, f" {EARLY_DAY:g} d", transform=ax.get_xaxis_transform(),
                va="top", fontsize="small", color="0.4")
    ax.set_xlabel("time (day)")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title}, centre pile {run.centre_pile} (thick: soft layers 1-3)")
    ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5), title="layer")
    ax.grid(alpha=0.3)
    return fig


def _zero_note(run: RunData) -> str:
    src = run.history if run.history is not None else run.profiles
    if src is not None and np.all(np.abs(src["relative_displacement_m"]) < 1e-12):
        return " (all zero: tied interface)"
    return ""


def plot_settlement(run: RunData) -> Figure:
    """Cap settlement (mm, down) against time, with the paper's ABAQUS value (Table 2)."""
    assert run.settlement is not None
    s = run.settlement
    fig = Figure(figsize=(7.0, 4.5))
    ax = fig.subplots()
    order = np.argsort(s["t_day"], kind="stable")
    ax.plot(s["t_day"][order], 1000 * s["settlement_m"][order], marker="o", label="this run")
    ref = 10 * PAPER_SETTLEMENT_CM[PAPER_MESH_M]
    ax.axhline(ref, color="C3", ls="--", lw=1.0,
               label=f"paper, ABAQUS, Table 2 ({PAPER_MESH_M:g} m mesh): "
                     f"{PAPER_SETTLEMENT_CM[PAPER_MESH_M]:g} cm (time not stated)")
    ax.set_ylim(bottom=min(0.0, 1000 * float(s["settlement_m"].min())))
    ax.invert_yaxis()
    ax.set_xlabel("time (day)")
    ax.set_ylabel("cap settlement (mm, down)")
    status = "" if run.complete is not False else " (interrupted run)"
    ax.set_title(f"Cap settlement{status}")
    ax.legend(fontsize="small", loc="best")
    ax.grid(alpha=0.3)
    return fig


def plot_friction_profiles(run: RunData) -> Figure:
    """Centre-pile shaft friction (kPa) against depth, one curve per output time (Figure 4)."""
    return _profile_figure(run, "shaft_friction_kPa", 1.0,
                           "shaft friction (kPa, + = soil supports the pile)", "Shaft friction")


def plot_friction_time(run: RunData) -> Figure:
    """Layer-mean shaft friction (kPa) against time, one curve per layer (Figure 5)."""
    return _time_figure(run, "shaft_friction_kPa", 1.0, "layer-mean shaft friction (kPa)",
                        "Shaft friction")


def plot_relative_displacement_profiles(run: RunData) -> Figure:
    """Centre-pile relative displacement (mm) against depth per output time (Figure 6)."""
    return _profile_figure(run, "relative_displacement_m", 1000.0,
                           "pile-soil relative displacement (mm, + = pile moves down)",
                           "Relative displacement" + _zero_note(run))


def plot_relative_displacement_time(run: RunData) -> Figure:
    """Layer-mean relative displacement (mm) against time, one curve per layer (Figure 7)."""
    return _time_figure(run, "relative_displacement_m", 1000.0,
                        "layer-mean relative displacement (mm)",
                        "Relative displacement" + _zero_note(run))


def plot_axial_force_profiles(run: RunData) -> Figure:
    """Centre-pile axial force (kN, compression positive) against depth per output time."""
    return _profile_figure(run, "axial_force_kN", 1.0, "axial force (kN, compression +)",
                           "Axial force")


def pile_loads_last(run: RunData) -> tuple[float, Table] | None:
    """Time and rows of ``pile_loads.csv`` at its last output time (sorted by pile)."""
    if run.loads is None:
        return None
    t = float(run.loads["t_day"].max())
    sel = _select(run.loads, run.loads["t_day"] == t)
    return t, _select(sel, np.argsort(sel["pile"]))


def plot_pile_loads(run: RunData) -> Figure:
    """Plan view of the head force of each pile at the last output time (kN and % of total)."""
    last = pile_loads_last(run)
    assert last is not None
    t, rows = last
    f = rows["head_force_kN"]
    total = float(f.sum())
    fig = Figure(figsize=(7.0, 6.0))
    ax = fig.subplots()
    size = 3000.0 * np.abs(f) / max(float(np.abs(f).max()), 1e-30)
    ax.scatter(rows["x_m"], rows["y_m"], s=size, alpha=0.4, color="C0", edgecolor="k")
    for x, y, i, fi in zip(rows["x_m"], rows["y_m"], rows["pile"], f, strict=True):
        share = f"{100 * fi / total:.1f} %" if total else "-"
        ax.annotate(f"pile {int(i)}\n{fi:.0f} kN\n{share}", (x, y), ha="center", va="center",
                    fontsize="small")
    ax.set_aspect("equal")
    ax.margins(0.25)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Pile head forces at t = {t:g} d (total {total:.0f} kN of the listed piles)")
    ax.grid(alpha=0.3)
    return fig


#: Every figure: file name, caption, the RunData table it needs, plotting function.
FIGURES: tuple[tuple[str, str, str, Callable[[RunData], Figure]], ...] = (
    ("settlement_time.png", "Cap settlement against time", "settlement", plot_settlement),
    ("friction_profiles.png", "Shaft friction profiles of the centre pile (cf. paper Fig. 4)",
     "profiles", plot_friction_profiles),
    ("friction_time.png", "Layer-mean shaft friction against time (cf. paper Fig. 5)",
     "history|profiles", plot_friction_time),
    ("relative_displacement_profiles.png",
     "Relative displacement profiles of the centre pile (cf. paper Fig. 6)", "profiles",
     plot_relative_displacement_profiles),
    ("relative_displacement_time.png",
     "Layer-mean relative displacement against time (cf. paper Fig. 7)", "history|profiles",
     plot_relative_displacement_time),
    ("axial_force_profiles.png", "Axial force profiles of the centre pile", "profiles",
     plot_axial_force_profiles),
    ("pile_loads.png", "Pile head forces at the last output time", "loads", plot_pile_loads),
)


def _has(run: RunData, needs: str) -> bool:
    return any(getattr(run, n) is not None for n in needs.split("|"))


def save_figure(fig: Figure, path: Path) -> Path:
    """Save ``fig`` as PNG to ``path`` atomically (temporary file in the same folder)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}.", suffix=".png", dir=path.parent)
    os.close(fd)
    try:
        fig.savefig(tmp, format="png", dpi=110, bbox_inches="tight")
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return path


def write_report(out_dir: Path) -> list[Path]:
    """Write the PNG figures of the run in ``out_dir`` to ``out_dir/plots``; return their paths.

    The :data:`FIGURES`, then the 3D view ``view3d.png`` of the XDMF results at the last
    output time (:mod:`pilegroup.studies.view3d`). Figures whose data are missing are skipped
    with a logged message.
    """
    run = load_run(Path(out_dir))
    written = []
    for name, _, needs, plot in FIGURES:
        if not _has(run, needs):
            log.info("skipping %s: no %s data", name, needs.replace("|", " or "))
            continue
        written.append(save_figure(plot(run), run.out_dir / "plots" / name))
        log.info("wrote %s", written[-1])
    view = write_view3d(run.out_dir, run.summary.get("scenario"))
    if view is not None:
        written.append(view)
        log.info("wrote %s", view)
    return written


# ------------------------------------------------------------------------------------- markdown

def _settlement_section(run: RunData) -> list[str]:
    lines = ["### Cap settlement", ""]
    paper = ", ".join(f"{v:g} cm ({h:g} m mesh)" for h, v in PAPER_SETTLEMENT_CM.items())
    ref = (f"The paper reports no measured settlement of the pier. Its settlement values are "
           f"ABAQUS results, Section 5, Table 2 (mesh-size study): {paper}; it adopts the "
           f"{PAPER_MESH_M:g} m mesh, i.e. **{PAPER_SETTLEMENT_CM[PAPER_MESH_M]:g} cm**. "
           f"Table 2 states no time; the simulation runs 317 days (Section 5).")
    s = run.settlement
    if s is None:
        return lines + ["No `settlement.csv`: no settlement data.", "", ref, ""]
    lines += ["| t (day) | stage | settlement (mm) |", "| ---: | --- | ---: |"]
    order = np.argsort(s["t_day"], kind="stable")
    for i in order:
        lines.append(f"| {s['t_day'][i]:g} | {s['stage'][i]} | {1000 * s['settlement_m'][i]:.3f} |")
    t_last, w_last = float(s["t_day"][order[-1]]), float(s["settlement_m"][order[-1]])
    ratio = 100 * (100 * w_last) / PAPER_SETTLEMENT_CM[PAPER_MESH_M]
    lines += ["", f"Settlement at the last output time, t = {t_last:g} day: "
              f"**{1000 * w_last:.3f} mm** ({100 * w_last:.2f} cm), {ratio:.0f} % of the "
              f"paper's {PAPER_SETTLEMENT_CM[PAPER_MESH_M]:g} cm.", "", ref, ""]
    return lines


def _verdict(flags: dict[int, bool]) -> str:
    if all(flags.values()):
        return "yes"
    some = [str(j) for j, ok in flags.items() if ok]
    return "no" + (f" (only in layer(s) {', '.join(some)})" if some else "")


def _friction_section(run: RunData) -> list[str]:
    lines = ["### Does shaft friction grow with time in the soft layers?", "",
             "Soft layers 1-3 of Table 1 (clay, mud, mucky clay); layer-mean shaft friction of "
             f"the centre pile (pile {run.centre_pile}, + = soil supports the pile) at the end of "
             "loading against the last output time; growth = an increase above "
             f"{100 * REL_TOL:g} % of the larger value.", ""]
    series = layer_series(run, "shaft_friction_kPa")
    rows, flags = [], {}
    t_last = None
    for j in SOFT_LAYERS:
        if j not in series:
            continue
        t, v = series[j]
        f0, t_last = _at(t, v, run.t_load), float(t[-1])
        if f0 is None or run.t_load is None or t_last <= run.t_load:
            continue
        f1 = float(v[-1])
        flags[j] = f1 - f0 > REL_TOL * max(abs(f0), abs(f1))
        rows.append(f"| {_layer_label(run, j)} | {f0:.3f} | {f1:.3f} | {f1 - f0:+.3f} "
                    f"| {'yes' if flags[j] else 'no'} |")
    if not flags:
        why = ("no end of loading (no `settlement.csv` with a load stage)" if run.t_load is None
               else "no friction data (`layer_history.csv` / `pile_profiles.csv`) for layers "
                    "1-3 of the centre pile from the end of loading to a later time")
        return lines + [f"**Answer: no data** — {why}.", ""]
    lines += [f"| layer | f at end of loading, t = {run.t_load:g} d (kPa) "
              f"| f at t = {t_last:g} d (kPa) | change (kPa) | grows |",
              "| --- | ---: | ---: | ---: | --- |", *rows, "",
              f"**Answer: {_verdict(flags)}.**", ""]
    return lines


def _relative_section(run: RunData) -> list[str]:
    lines = [f"### Does relative displacement grow fastest in the first {EARLY_DAY:g} days?", "",
             "Mean growth rate of the layer-mean relative displacement of the centre pile "
             f"(+ = pile moves down relative to the soil) from the end of loading to "
             f"{EARLY_DAY:g} days against {EARLY_DAY:g} days to the last time; the paper "
             "(Section 2) finds the rate from 0 to 89 days \"much larger\" than later.", ""]
    note = _zero_note(run)
    if note:
        return lines + ["**Answer: not applicable** — every relative displacement is zero "
                        "(tied pile-soil interface).", ""]
    series = layer_series(run, "relative_displacement_m")
    rows, flags = [], {}
    t0, t_last = run.t_load, None
    for j, (t, v) in series.items():
        w0, w89 = _at(t, v, t0), _at(t, v, EARLY_DAY)
        t_last = float(t[-1])
        if w0 is None or w89 is None or t0 is None or t_last <= EARLY_DAY or t0 >= EARLY_DAY:
            continue
        w1 = float(v[-1])
        r1, r2 = (w89 - w0) / (EARLY_DAY - t0), (w1 - w89) / (t_last - EARLY_DAY)
        flags[j] = r1 > r2 + REL_TOL * max(abs(r1), abs(r2))
        rows.append(f"| {_layer_label(run, j)} | {1000 * w0:.3f} | {1000 * w89:.3f} "
                    f"| {1000 * w1:.3f} | {1000 * r1:.5f} | {1000 * r2:.5f} "
                    f"| {'yes' if flags[j] else 'no'} |")
    if not flags:
        why = ("no end of loading (no `settlement.csv` with a load stage)" if t0 is None
               else f"no relative displacement data of the centre pile spanning the end of "
                    f"loading, {EARLY_DAY:g} days and a later time")
        return lines + [f"**Answer: no data** — {why}.", ""]
    lines += [f"| layer | w at t = {t0:g} d (mm) | w at {EARLY_DAY:g} d (mm) "
              f"| w at {t_last:g} d (mm) | rate {t0:g}-{EARLY_DAY:g} d (mm/day) "
              f"| rate {EARLY_DAY:g}-{t_last:g} d (mm/day) | faster early |",
              "| --- | ---: | ---: | ---: | ---: | ---: | --- |", *rows, "",
              f"**Answer: {_verdict(flags)}.**", ""]
    return lines


def _loads_section(run: RunData) -> list[str]:
    last = pile_loads_last(run)
    if last is None:
        return []
    t, rows = last
    total = float(rows["head_force_kN"].sum())
    lines = [f"### Pile head forces at t = {t:g} day", "",
             "| pile | x (m) | y (m) | head force (kN) | share (%) |",
             "| ---: | ---: | ---: | ---: | ---: |"]
    for i, x, y, f in zip(rows["pile"], rows["x_m"], rows["y_m"], rows["head_force_kN"],
                          strict=True):
        share = f"{100 * f / total:.1f}" if total else "-"
        lines.append(f"| {int(i)} | {x:g} | {y:g} | {f:.1f} | {share} |")
    return lines + ["", f"Total of the listed piles: {total:.1f} kN (paper, Section 5: "
                        "total load on the pile foundation 10856 kN).", ""]


def results_markdown(out_dir: Path, figures_rel: str) -> str:
    """A Markdown section summarising the run in ``out_dir`` from its CSV and JSON files.

    ``figures_rel`` is the path of the ``plots`` folder as seen from the Markdown file.
    """
    run = load_run(Path(out_dir))
    name = run.summary.get("scenario") or run.out_dir.name
    status = {True: "complete", False: "**interrupted** (summary.json: `\"complete\": false`)",
              None: "unknown (no `complete` flag in summary.json)"}[run.complete]
    t_load = "unknown" if run.t_load is None else f"t = {run.t_load:g} day"
    lines = [f"## Results: {name}", "",
             f"Run folder `{run.out_dir}`; run status: {status}. Centre pile: "
             f"{run.centre_pile}. End of loading: {t_load}.", ""]
    lines += _settlement_section(run)
    lines += _friction_section(run)
    lines += _relative_section(run)
    lines += _loads_section(run)
    figs = [(f, cap) for f, cap, needs, _ in FIGURES if _has(run, needs)]
    if (run.out_dir / "plots" / VIEW3D).is_file():
        figs.append((VIEW3D, "3D view: settlement at the last output time"))
    if figs:
        lines += ["### Figures", ""]
        rel = figures_rel.rstrip("/")
        for f, cap in figs:
            lines += [f"![{cap}]({rel}/{f})", ""]
    return "\n".join(lines)
