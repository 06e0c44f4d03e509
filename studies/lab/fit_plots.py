"""The figures of a fit: the data against the fitted curves (or the best run), and residuals."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from pilegroup.studies.lab.fit_stats import FitResult
from pilegroup.studies.lab.interface_fit import CurveFit
from pilegroup.studies.lab.oedometer_fit import OedometerFit
from pilegroup.studies.report.plots import save_figure

if TYPE_CHECKING:  # the scenario fit needs MPI and the solver; the curve fits do not
    from pilegroup.studies.lab.scenario_fit import ScenarioFit


def curve_fit_figure(cf: CurveFit) -> Figure:
    """Data (markers) and fitted model (lines) per curve; residuals per point below."""
    creep = cf.result.fit == "interface-creep"
    fig = Figure(figsize=(7.5, 8.0))
    ax, axr = fig.subplots(2, 1, height_ratios=[3, 1.4])
    n = len(cf.curves)
    start = 0
    for i, c in enumerate(cf.curves):
        col = colormaps["viridis"](0.1 + 0.75 * i / max(n - 1, 1))
        x = c.time if creep else c.slip
        y = c.slip if creep else c.shear
        xs = np.linspace(x.min(), x.max(), 200)
        ax.plot(x if creep else 1e3 * x, 1e3 * y if creep else y, ".", ms=3, color=col,
                label=f"data, $\\sigma_n$ = {c.normal_kPa:g} kPa"
                + (f", $\\tau$ = {np.mean(c.shear):.3g} kPa" if creep else ""))
        fx = cf.model(i, xs)
        ax.plot(xs if creep else 1e3 * xs, 1e3 * fx if creep else fx, "-", color=col, lw=1.2)
        axr.plot(x if creep else 1e3 * x, cf.residual[start:start + x.size], ".", ms=3,
                 color=col)
        start += x.size
    vals = ", ".join(f"{k} = {v:.4g}" for k, v in zip(cf.result.names, cf.result.values,
                                                       strict=True))
    ax.set_title(f"{cf.result.fit} fit: {vals}", fontsize="medium")
    ax.set_xlabel("time (days)" if creep else "slip (mm)")
    ax.set_ylabel("slip (mm)" if creep else "shear stress (kPa)")
    ax.legend(fontsize="x-small")
    axr.axhline(0.0, color="0.4", lw=0.8)
    axr.set_xlabel(ax.get_xlabel())
    axr.set_ylabel("residual, model / measured - 1")
    for a in (ax, axr):
        a.grid(alpha=0.3)
    return fig


def oedometer_fit_figure(of: OedometerFit) -> Figure:
    """Data (markers) and the fitted law (lines); residuals.

    End-of-step strains against log stress, every reading over time, the longest hold against
    log time.
    """
    d = of.data
    fig = Figure(figsize=(11.0, 8.0), layout="constrained")
    (ax, axt), (axc, axr) = fig.subplots(2, 2)
    e = d.ends()
    ax.semilogx(d.stress[e], 100 * d.strain[e], "o", ms=4, label="data, end of each step")
    ax.semilogx(d.stress[e], 100 * of.model[e], "-", label="fitted law")
    axt.plot(d.time, 100 * d.strain, ".", ms=3, label="data")
    axt.plot(d.time, 100 * of.model, "-", lw=1.0, label="fitted law")
    k = max(range(1, len(d.steps)), key=lambda j: d.steps[j].times[-1] - d.steps[j].start_day)
    m = (d.number == d.number[e[k]]) & (d.time > d.steps[k].start_day)
    u = d.time[m] - d.steps[k].start_day
    axc.semilogx(u, 100 * d.strain[m], "o", ms=3, label="data")
    axc.semilogx(u, 100 * of.model[m], "-", label="fitted law")
    axr.plot(d.time[of.used], of.residual, ".", ms=3)
    axr.axhline(0.0, color="0.4", lw=0.8)
    vals = ", ".join(f"{k} = {v:.4g}" for k, v in zip(of.result.names, of.result.values,
                                                       strict=True))
    ax.set(xlabel="vertical effective stress (kPa)", ylabel="vertical strain (%)")
    ax.xaxis.set_minor_formatter(NullFormatter())
    ax.set_title(f"oedometer fit: {vals}", fontsize="medium")
    axt.set(xlabel="time (days)", ylabel="vertical strain (%)", title="every reading")
    axc.set(xlabel=f"time since the load of step {d.number[e[k]]:g} (days)",
            ylabel="vertical strain (%)", title="the longest hold")
    axr.set(xlabel="time (days)", ylabel="residual, model / measured - 1")
    for a in (ax, axt, axc, axr):
        a.grid(alpha=0.3, which="both")
    for a in (ax, axt, axc):
        a.legend(fontsize="x-small")
    return fig


def scenario_fit_figure(fit: ScenarioFit, result: FitResult) -> Figure:
    """Measured values against the best run's, over time; residuals below."""
    data = fit.data
    best = fit.values_at(result.values)
    fig = Figure(figsize=(7.5, 7.0))
    ax, axr = fig.subplots(2, 1, height_ratios=[3, 1.4])
    unit = fit.unit
    scale, label = (1e3, "settlement (mm)") if data.layout == "settlement" else (1e6,
                                                                                "strain (1e-6)")
    if data.layout == "settlement":
        groups = [np.ones(data.values.size, dtype=bool)]
    else:
        keys = sorted(set(zip(data.table["pile"], data.table["section"], strict=True)))
        groups = [(data.table["pile"] == p) & (data.table["section"] == s) for p, s in keys]
    labels = (["settlement"] if data.layout == "settlement" else
              [f"pile {p:g}, section {s:g}" for p, s in keys])
    for k, (m, lab) in enumerate(zip(groups, labels, strict=True)):
        col = colormaps["viridis"](0.1 + 0.75 * k / max(len(groups) - 1, 1))
        o = np.argsort(data.times[m], kind="stable")
        ax.plot(data.times[m][o], scale * data.values[m][o], "o", ms=4, color=col, label=lab)
        ax.plot(data.times[m][o], scale * best[m][o], "-", color=col)
        axr.plot(data.times[m][o], scale * (best - data.values)[m][o], ".", color=col)
    vals = fit.describe(result.values)
    ax.set_title(f"fit: {vals}\n(markers measured, lines the model; {len(fit.cases)} runs)",
                 fontsize="medium")
    ax.set(xlabel="time (days)", ylabel=label)
    ax.legend(fontsize="x-small")
    axr.axhline(0.0, color="0.4", lw=0.8)
    axr.set(xlabel="time (days)", ylabel=f"model - measured ({'mm' if unit == 'm' else '1e-6'})")
    for a in (ax, axr):
        a.grid(alpha=0.3)
    return fig


def write_scenario_fit_figure(path: Path, fit: ScenarioFit, result: FitResult) -> Path:
    """Write the figure of a scenario fit as PNG."""
    return save_figure(scenario_fit_figure(fit, result), path)


def write_oedometer_fit_figure(path: Path, of: OedometerFit) -> Path:
    """Write the figure of an oedometer fit as PNG."""
    return save_figure(oedometer_fit_figure(of), path)


def write_fit_figure(path: Path, cf: CurveFit) -> Path:
    """Write the figure of a fit as PNG."""
    return save_figure(curve_fit_figure(cf), path)


__all__ = ["curve_fit_figure", "oedometer_fit_figure", "scenario_fit_figure",
           "write_fit_figure", "write_oedometer_fit_figure", "write_scenario_fit_figure"]
