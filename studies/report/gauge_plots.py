"""Figures of the virtual strain gauges (``gauges.csv``) of the pile nearest the centre.

The field method's friction and relative displacement (solid lines with dots) beside the
model's own values at the same sections (dashed): profiles at up to five output times and
time histories at up to four gauge sections, both spread over the run and the pile; a scenario
with a ``[reference]`` gives the times (``profile_days``: the nearest output times) and the
sections (``gauge_sections``) its publication draws. A friction value belongs to the interval
from its section down to the next one and is drawn at the interval's mid-depth.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from pilegroup.studies.report.figure_parts import depth_axis, spread
from pilegroup.studies.results.gauges import nearest_times
from pilegroup.studies.results.rundata import RunData, select

#: Output times of the profile figures and sections of the history figures, without a reference.
PROFILE_TIMES, HISTORY_SECTIONS = 5, 4

_NOTE = "solid: field method (from the gauge strains); dashed: model"

#: (field column, model column, axis label, title) of each quantity.
_FRICTION = ("f_kPa", "f_model_kPa", "gauge friction (kPa, + = soil supports the pile)",
             "Gauge friction")
_RELATIVE = ("w_mm", "w_model_mm", "pile-soil relative displacement (mm, + = pile down)",
             "Gauge relative displacement")


def _depth_axis(g: dict[str, np.ndarray], column: str) -> np.ndarray:
    """Depths at which ``column`` is drawn: interval mid-depths for the friction."""
    z = g["depth_m"]
    if not column.startswith("f_"):
        return z
    below = np.append(z[1:], np.nan)
    return 0.5 * (z + below)


def _profiles(run: RunData, quantity: tuple[str, str, str, str]) -> Figure:
    assert run.gauges is not None
    field, model, xlabel, title = quantity
    fig = Figure(figsize=(6.0, 7.0))
    ax = fig.subplots()
    ref = run.reference
    t_all = run.gauges["time_day"]
    times = (nearest_times(t_all, ref.profile_days) if ref is not None and ref.profile_days
             else spread(t_all[t_all > 0.0], PROFILE_TIMES))
    for k, t in enumerate(times):
        g = select(run.gauges, run.gauges["time_day"] == t)
        g = select(g, np.argsort(g["section"]))
        z = _depth_axis(g, field)
        c = colormaps["viridis"](0.1 + 0.8 * k / max(len(times) - 1, 1))
        ax.plot(g[field], z, marker="o", color=c, label=f"t = {t:g} d")
        ax.plot(g[model], z, ls="--", marker="x", color=c)
    ax.axvline(0.0, color="0.5", lw=0.6)
    depth_axis(ax, run, float(np.max(run.gauges["depth_m"])))
    ax.set_xlabel(xlabel)
    ax.set_title(f"{title}, {run.pile_name(run.centre_pile)}\n{_NOTE}", fontsize="medium")
    ax.legend(fontsize="small", title="output time")
    ax.grid(alpha=0.3)
    return fig


def _histories(run: RunData, quantity: tuple[str, str, str, str]) -> Figure:
    assert run.gauges is not None
    field, model, ylabel, title = quantity
    fig = Figure(figsize=(8.5, 5.0))
    ax = fig.subplots()
    g = run.gauges
    ref = run.reference
    sections = (ref.gauge_sections if ref is not None and ref.gauge_sections
                else [int(s) for s in spread(g["section"][np.isfinite(g[field])],
                                             HISTORY_SECTIONS)])
    shown = [s for s in sections if np.any((g["section"] == s) & np.isfinite(g[field]))]
    for k, s in enumerate(shown):
        m = select(g, g["section"] == s)
        m = select(m, np.argsort(m["time_day"], kind="stable"))
        where = f"section {s}, {m['depth_m'][0]:g} m"
        ax.plot(m["time_day"], m[field], marker=".", color=f"C{k}", label=where)
        ax.plot(m["time_day"], m[model], ls="--", color=f"C{k}")
    ax.set_xlabel("time (day)")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title} against time, {run.pile_name(run.centre_pile)}\n{_NOTE}",
                 fontsize="medium")
    if shown:
        ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5))
    ax.grid(alpha=0.3)
    return fig


def plot_gauge_friction_profiles(run: RunData) -> Figure:
    """Gauge friction (kPa) against depth at up to five output times."""
    return _profiles(run, _FRICTION)


def plot_gauge_relative_profiles(run: RunData) -> Figure:
    """Gauge relative displacement (mm) against depth at up to five output times."""
    return _profiles(run, _RELATIVE)


def plot_gauge_friction_time(run: RunData) -> Figure:
    """Gauge friction (kPa) against time at up to four sections."""
    return _histories(run, _FRICTION)


def plot_gauge_relative_time(run: RunData) -> Figure:
    """Gauge relative displacement (mm) against time at up to four sections."""
    return _histories(run, _RELATIVE)


#: The gauge figures: file name, caption, the RunData table they need, plotting function.
GAUGE_FIGURES = (
    ("gauge_friction_profiles.png",
     "Gauge friction profiles of the pile nearest the centre, field method and model",
     "gauges", plot_gauge_friction_profiles),
    ("gauge_relative_displacement_profiles.png",
     "Gauge relative displacement profiles of the pile nearest the centre, field method and "
     "model", "gauges", plot_gauge_relative_profiles),
    ("gauge_friction_time.png", "Gauge friction against time at selected sections", "gauges",
     plot_gauge_friction_time),
    ("gauge_relative_displacement_time.png",
     "Gauge relative displacement against time at selected sections", "gauges",
     plot_gauge_relative_time),
)
