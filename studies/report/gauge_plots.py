"""Figures of the virtual strain gauges (``gauges.csv``) of the centre pile.

The field method's friction and relative displacement (Eqs. 1-3, solid lines with dots) beside
the model's own values at the same sections (dashed): profiles at the output times nearest to
:data:`~pilegroup.studies.report.paper_values.PAPER_PROFILE_DAYS` (cf. paper Figures 4 and 6) and
time histories at the gauge sections
:data:`~pilegroup.studies.report.paper_values.PAPER_HISTORY_SECTIONS` that exist
(cf. Figures 5, 7, 12 and 13). A friction value belongs to the interval from its section down to
the next one and is drawn at the interval's mid-depth.
"""

from __future__ import annotations

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure

from pilegroup.studies.report.paper_values import PAPER_HISTORY_SECTIONS, PAPER_PROFILE_DAYS
from pilegroup.studies.results.gauges import nearest_times
from pilegroup.studies.results.rundata import RunData, select

_NOTE = "solid: field method (Eqs. 1-3); dashed: model"

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
    times = nearest_times(run.gauges["time_day"], PAPER_PROFILE_DAYS)
    for k, t in enumerate(times):
        g = select(run.gauges, run.gauges["time_day"] == t)
        g = select(g, np.argsort(g["section"]))
        z = _depth_axis(g, field)
        c = colormaps["viridis"](0.1 + 0.8 * k / max(len(times) - 1, 1))
        ax.plot(g[field], z, marker="o", color=c, label=f"t = {t:g} d")
        ax.plot(g[model], z, ls="--", marker="x", color=c)
    ax.axvline(0.0, color="0.5", lw=0.6)
    ax.invert_yaxis()
    ax.set_xlabel(xlabel)
    ax.set_ylabel("depth below ground surface (m)")
    ax.set_title(f"{title}, centre pile {run.centre_pile}\n{_NOTE}", fontsize="medium")
    ax.legend(fontsize="small", title="output time")
    ax.grid(alpha=0.3)
    return fig


def _histories(run: RunData, quantity: tuple[str, str, str, str]) -> Figure:
    assert run.gauges is not None
    field, model, ylabel, title = quantity
    fig = Figure(figsize=(8.5, 5.0))
    ax = fig.subplots()
    g = run.gauges
    shown = [s for s in PAPER_HISTORY_SECTIONS
             if np.any((g["section"] == s) & np.isfinite(g[field]))]
    for k, s in enumerate(shown):
        m = select(g, g["section"] == s)
        m = select(m, np.argsort(m["time_day"], kind="stable"))
        where = f"section {s}, {m['depth_m'][0]:g} m"
        ax.plot(m["time_day"], m[field], marker=".", color=f"C{k}", label=where)
        ax.plot(m["time_day"], m[model], ls="--", color=f"C{k}")
    ax.set_xlabel("time (day)")
    ax.set_ylabel(ylabel)
    ax.set_title(f"{title} against time, centre pile {run.centre_pile}\n{_NOTE}",
                 fontsize="medium")
    if shown:
        ax.legend(fontsize="small", loc="center left", bbox_to_anchor=(1.0, 0.5))
    ax.grid(alpha=0.3)
    return fig


def plot_gauge_friction_profiles(run: RunData) -> Figure:
    """Gauge friction (kPa) of the centre pile against depth at up to five output times."""
    return _profiles(run, _FRICTION)


def plot_gauge_relative_profiles(run: RunData) -> Figure:
    """Gauge relative displacement (mm) of the centre pile against depth at output times."""
    return _profiles(run, _RELATIVE)


def plot_gauge_friction_time(run: RunData) -> Figure:
    """Gauge friction (kPa) against time at sections 1, 5, 11 and 17 (those that exist)."""
    return _histories(run, _FRICTION)


def plot_gauge_relative_time(run: RunData) -> Figure:
    """Gauge relative displacement (mm) against time at sections 1, 5, 11 and 17."""
    return _histories(run, _RELATIVE)


#: The gauge figures: file name, caption, the RunData table they need, plotting function.
GAUGE_FIGURES = (
    ("gauge_friction_profiles.png",
     "Gauge friction profiles of the centre pile, field method and model (cf. paper Fig. 4)",
     "gauges", plot_gauge_friction_profiles),
    ("gauge_relative_displacement_profiles.png",
     "Gauge relative displacement profiles of the centre pile, field method and model "
     "(cf. paper Fig. 6)", "gauges", plot_gauge_relative_profiles),
    ("gauge_friction_time.png",
     "Gauge friction against time at sections 1, 5, 11, 17 (cf. paper Figs. 5, 13)",
     "gauges", plot_gauge_friction_time),
    ("gauge_relative_displacement_time.png",
     "Gauge relative displacement against time at sections 1, 5, 11, 17 (cf. paper Figs. 7, "
     "12)", "gauges", plot_gauge_relative_time),
)
