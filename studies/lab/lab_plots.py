"""The figures of ``pilegroup lab``, one per test, in the style of the laboratory's plots.

Interface tests: one panel per Eq. 15 reading (``default``, ``seed``) side by side with the
same axes where the two are comparable (shear curves share one panel: solid default, dashed
seed). Soil tests: the triaxial's deviator and volume change against axial strain and its
stress path; the oedometer's void ratio against the vertical stress (log scale), each step's
strain against the time since its load (log scale: creep) and the lateral stress.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib import colormaps
from matplotlib.figure import Figure
from matplotlib.ticker import NullFormatter

from pilegroup.studies.report.plots import save_figure
from pilegroup.studies.results.tables import Table

_STYLE = {"default": "-", "seed": "--"}


def _colour(k: int, n: int) -> tuple[float, ...]:
    return colormaps["viridis"](0.1 + 0.75 * k / max(n - 1, 1))


def _curves(t: Table, variant: str) -> list[np.ndarray]:
    mask = t["variant"] == variant
    return [mask & (t["curve"] == c) for c in np.unique(t["curve"][mask])]


def _label(test: str, t: Table, m: np.ndarray) -> str:
    sn = t["normal_stress_kPa"][m][0]
    if test == "interface-shear":
        return f"$\\sigma_n$ = {sn:g} kPa"
    if test == "interface-rate":
        return f"{t['slip_rate_m_per_day'][m][0] / 1.44:.3g} mm/min"
    tau0 = t["shear_stress_kPa"][m][0]
    return f"$\\tau$ = {tau0:.3g} kPa ($\\sigma_n$ = {sn:g})"


def _shear_figure(t: Table, test: str, title: str) -> Figure:
    fig = Figure(figsize=(11.0, 4.5))
    ax, env = fig.subplots(1, 2)
    for v in dict.fromkeys(t["variant"]):
        curves = _curves(t, v)
        for k, m in enumerate(curves):
            ax.plot(1e3 * t["slip_m"][m], t["shear_stress_kPa"][m], _STYLE.get(v, ":"),
                    color=_colour(k, len(curves)), label=f"{v}: {_label(test, t, m)}")
        if test == "interface-shear":
            peaks = [(t["normal_stress_kPa"][m][0], t["shear_stress_kPa"][m].max())
                     for m in curves]
            env.plot(*zip(*peaks, strict=True), "o" + _STYLE.get(v, ":"), label=v)
        else:
            env.semilogx([t["slip_rate_m_per_day"][m][0] / 1.44 for m in curves],
                         [t["shear_stress_kPa"][m][-1] for m in curves],
                         "o" + _STYLE.get(v, ":"), label=v)
    ax.set_xlabel("slip (mm)")
    ax.set_ylabel("shear stress (kPa)")
    ax.legend(fontsize="x-small")
    if test == "interface-shear":
        env.set_xlabel("normal stress (kPa)")
        env.set_ylabel("peak shear stress (kPa)")
        env.set_title("strength at failure")
    else:
        env.set_xlabel("slip rate (mm/min)")
        env.set_ylabel("shear stress at the last slip (kPa)")
        env.set_title("rate effect")
    env.legend(fontsize="small")
    for a in (ax, env):
        a.grid(alpha=0.3)
    ax.set_title(title)
    return fig


def _time_figure(t: Table, test: str, title: str) -> Figure:
    variants = list(dict.fromkeys(t["variant"]))
    fig = Figure(figsize=(5.5 * len(variants), 4.5))
    axes = np.atleast_1d(fig.subplots(1, len(variants), sharey=test == "interface-relaxation"))
    for ax, v in zip(axes, variants, strict=True):
        curves = _curves(t, v)
        for k, m in enumerate(curves):
            if test == "interface-creep":
                ax.plot(t["time_day"][m], 1e3 * t["slip_m"][m], color=_colour(k, len(curves)),
                        label=_label(test, t, m))
            else:
                keep = m & (t["time_day"] > 0)
                ax.semilogx(t["time_day"][keep], t["shear_stress_kPa"][keep],
                            color=_colour(k, len(curves)), label=_label(test, t, m))
        ax.set_xlabel("time (days)")
        ax.set_ylabel("slip (mm)" if test == "interface-creep" else "shear stress (kPa)")
        ax.set_title(f"{v} reading")
        ax.legend(fontsize="x-small")
        ax.grid(alpha=0.3)
    fig.suptitle(title)
    return fig


def _triaxial_figure(t: Table, title: str) -> Figure:
    fig = Figure(figsize=(15.0, 4.5))
    axq, axv, axp = fig.subplots(1, 3)
    curves = np.unique(t["curve"])
    for k, c in enumerate(curves):
        m = t["curve"] == c
        drained = t["drainage"][m][0] == "drained"
        style = "-" if drained else "--"
        lab = f"{t['drainage'][m][0]}, {t['confining_stress_kPa'][m][0]:g} kPa"
        col = _colour(k % (len(curves) // 2 or 1), len(curves) // 2 or 1)
        axq.plot(100 * t["axial_strain"][m], t["q_kPa"][m], style, color=col, label=lab)
        if drained:
            axv.plot(100 * t["axial_strain"][m], 100 * t["volumetric_strain"][m], style,
                     color=col, label=lab)
        else:
            axv.plot(100 * t["axial_strain"][m], t["excess_pore_pressure_kPa"][m], style,
                     color=col, label=lab + " (u, kPa)")
        axp.plot(t["p_kPa"][m], t["q_kPa"][m], style, color=col, label=lab)
    axq.set(xlabel="axial strain (%)", ylabel="deviator q (kPa)", title=title)
    axv.set(xlabel="axial strain (%)", ylabel="volumetric strain (%) / excess pore pressure",
            title="volume change (drained), pore pressure (undrained)")
    axp.set(xlabel="mean effective stress p' (kPa)", ylabel="q (kPa)", title="stress paths")
    for a in (axq, axv, axp):
        a.grid(alpha=0.3)
        a.legend(fontsize="x-small")
    return fig


def _oedometer_figure(t: Table, title: str) -> Figure:
    fig = Figure(figsize=(15.0, 4.5))
    ax, axt, axh = fig.subplots(1, 3)
    steps = np.unique(t["step"])
    ends = np.array([np.nonzero(t["step"] == k)[0][-1] for k in steps])
    ax.semilogx(t["vertical_stress_kPa"], t["void_ratio"], "-", color="0.6", lw=0.8,
                label="every reading")
    ax.semilogx(t["vertical_stress_kPa"][ends], t["void_ratio"][ends], "o", ms=4,
                label="end of each step")
    ax.set(xlabel="vertical effective stress (kPa)", ylabel="void ratio e", title=title)
    ax.xaxis.set_minor_formatter(NullFormatter())
    for k in steps[1:]:
        m = t["step"] == k
        start = t["time_day"][np.nonzero(m)[0][0] - 1]  # the previous step's last reading
        u = t["time_day"][m] - start
        strain = 100 * (t["vertical_strain"][m] - t["vertical_strain"][m][0])
        axt.semilogx(u[u > 0], strain[u > 0], color=_colour(int(k) - 1, len(steps) - 1),
                     label=f"step {k:g}: {t['vertical_stress_kPa'][m][0]:.4g} kPa")
    axt.set(xlabel="time since the step's load (days)",
            ylabel="vertical strain since its first reading (%)", title="creep in each step")
    axh.plot(t["vertical_stress_kPa"], t["horizontal_stress_kPa"], "o-", ms=3)
    axh.set(xlabel="vertical effective stress (kPa)",
            ylabel="horizontal effective stress (kPa)", title="lateral stress")
    for a in (ax, axt, axh):
        a.grid(alpha=0.3, which="both")
    ax.legend(fontsize="x-small")
    axt.legend(fontsize="xx-small", ncol=2)
    return fig


def lab_figure(test: str, table: Table, title: str) -> Figure:
    """The figure of one test's table."""
    if test in ("interface-shear", "interface-rate"):
        return _shear_figure(table, test, title)
    if test in ("interface-creep", "interface-relaxation"):
        return _time_figure(table, test, title)
    if test == "triaxial":
        return _triaxial_figure(table, title)
    return _oedometer_figure(table, title)


def write_lab_figure(path: Path, test: str, table: Table, title: str) -> Path:
    """Write the figure of one test as PNG."""
    return save_figure(lab_figure(test, table, title), path)


__all__ = ["lab_figure", "write_lab_figure"]
