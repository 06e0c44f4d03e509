"""Post-processing of a finished (or interrupted) run: PNG figures and a Markdown summary.

Input is a run output folder: the CSV files of :mod:`pilegroup.studies.results.tables`,
``summary.json`` and ``scenario.json`` (read by :mod:`pilegroup.studies.results.rundata`) and
``results*.xdmf``/``.h5`` for the 3D view (:mod:`pilegroup.studies.report.view3d`). Any file may be
missing: its figures are skipped (logged). A CSV with a wrong header or a non-numeric value
raises :class:`~pilegroup.model.ScenarioError` naming the file, the column and the columns
required (the CLI exits with code 2).
"""

from __future__ import annotations

import logging
from pathlib import Path

import numpy as np

from pilegroup.studies.report.plots import FIGURES, save_figure
from pilegroup.studies.report.view3d import FILE as VIEW3D
from pilegroup.studies.report.view3d import write_view3d
from pilegroup.studies.results.rundata import (
    RunData,
    layer_label,
    layer_series,
    load_run,
    select,
    zero_note,
)

log = logging.getLogger(__name__)

#: A change smaller than this fraction of the larger magnitude counts as no change.
REL_TOL = 1e-3


def _at(t: np.ndarray, v: np.ndarray, tq: float | None) -> float | None:
    """``v`` interpolated at ``tq``; ``None`` outside the data (1e-9 day slack)."""
    if tq is None or t.size == 0 or tq < t[0] - 1e-9 or tq > t[-1] + 1e-9:
        return None
    return float(np.interp(tq, t, v))


def write_report(out_dir: Path, share: tuple[int, int] = (0, 1)) -> list[Path]:
    """Write the PNG figures of the run in ``out_dir`` to ``out_dir/plots``; return their paths.

    The :data:`FIGURES`, then the 3D view ``view3d.png`` of the XDMF results at the last
    output time (:mod:`pilegroup.studies.report.view3d`). Figures whose data are missing are skipped
    with a logged message; the caller lists the paths written. ``share = (k, n)``: only the
    figures ``k, k + n, ...`` of the list, and the 3D view if ``k = n - 1``, so that ``n``
    processes write the report together.
    """
    k, n = share
    run = load_run(Path(out_dir))
    written = []
    for name, _, needs, plot in FIGURES[k::n]:
        if not run.has(needs):
            log.info("skipping %s: no %s data", name, needs.replace("|", " or "))
            continue
        written.append(save_figure(plot(run), run.out_dir / "plots" / name))
    view = write_view3d(run.out_dir, run.summary.get("scenario")) if k == n - 1 else None
    if view is not None:
        written.append(view)
    return written


# ------------------------------------------------------------------------------------- markdown

def _reference_settlement(run: RunData, w_last: float | None) -> list[str]:
    """The reference's published settlement and the run's last one against it, if any."""
    ref = run.reference
    if ref is None or ref.settlement_m is None:
        return []
    when = f"at day {ref.settlement_day:g}" if ref.settlement_day is not None else \
        "no time stated"
    lines = [f"Reference settlement: **{1000 * ref.settlement_m:g} mm** "
             f"({when})" + (f"; {ref.settlement_note}" if ref.settlement_note else "") + "."]
    if w_last is not None:
        lines[0] += (f" The run's last settlement is {100 * w_last / ref.settlement_m:.0f} % "
                     "of it.")
    return lines + [""]


def _settlement_section(run: RunData) -> list[str]:
    lines = ["### Cap settlement", ""]
    s = run.settlement
    if s is None:
        return lines + ["No `settlement.csv`: no settlement data.", "",
                        *_reference_settlement(run, None)]
    lines += ["| t (day) | stage | settlement (mm) |", "| ---: | --- | ---: |"]
    order = np.argsort(s["t_day"], kind="stable")
    for i in order:
        lines.append(f"| {s['t_day'][i]:g} | {s['stage'][i]} | {1000 * s['settlement_m'][i]:.3f} |")
    t_last, w_last = float(s["t_day"][order[-1]]), float(s["settlement_m"][order[-1]])
    lines += ["", f"Settlement at the last output time, t = {t_last:g} day: "
              f"**{1000 * w_last:.3f} mm** ({100 * w_last:.2f} cm).", ""]
    return lines + _reference_settlement(run, w_last)


def _verdict(flags: dict[int, bool]) -> str:
    if all(flags.values()):
        return "yes"
    some = [str(j) for j, ok in flags.items() if ok]
    return "no" + (f" (only in layer(s) {', '.join(some)})" if some else "")


def soft_layers(run: RunData) -> tuple[int, ...]:
    """The layers the scenario's ``[reference]`` calls soft (none without one)."""
    return run.reference.soft_layers if run.reference is not None else ()


def friction_change(run: RunData, layers: tuple[int, ...] | None = None
                    ) -> dict[int, tuple[float, float, bool]]:
    """Centre-pile mean friction per layer: (at the end of loading, at the last time, grew).

    ``layers``: those asked about (default: the reference's soft layers, else every layer).
    Friction in kPa; grew: by more than :data:`REL_TOL` of the larger value.
    """
    out: dict[int, tuple[float, float, bool]] = {}
    series = layer_series(run, "shaft_friction_kPa")
    for j in layers if layers is not None else (soft_layers(run) or tuple(series)):
        if j not in series:
            continue
        t, v = series[j]
        f0 = _at(t, v, run.t_load)
        if f0 is None or run.t_load is None or float(t[-1]) <= run.t_load:
            continue
        f1 = float(v[-1])
        out[j] = (f0, f1, f1 - f0 > REL_TOL * max(abs(f0), abs(f1)))
    return out


def _friction_section(run: RunData) -> list[str]:
    soft = soft_layers(run)
    pile = run.pile_name(run.centre_pile)
    if soft:
        names = ", ".join(run.layer_names.get(j, f"layer {j}") for j in soft)
        lines = ["### Does shaft friction grow with time in the soft layers?", "",
                 f"Soft layers {', '.join(map(str, soft))} of the reference ({names}); "
                 f"layer-mean shaft friction of {pile}"]
    else:
        lines = ["### Shaft friction from the end of loading to the last output time", "",
                 f"Layer-mean shaft friction of {pile}"]
    lines[-1] += (" (+ = soil supports the pile) at the end of loading against the last "
                  f"output time; growth = an increase above {100 * REL_TOL:g} % of the larger "
                  "value.")
    lines.append("")
    change = friction_change(run)
    if not change:
        why = ("no end of loading (no `settlement.csv` with a load stage)" if run.t_load is None
               else "no friction data (`layer_history.csv` / `pile_profiles.csv`) of the "
                    "layers from the end of loading to a later time")
        return lines + [f"**Answer: no data** — {why}.", ""]
    t_last = float(layer_series(run, "shaft_friction_kPa")[next(iter(change))][0][-1])
    rows = [f"| {layer_label(run, j)} | {f0:.3f} | {f1:.3f} | {f1 - f0:+.3f} "
            f"| {'yes' if ok else 'no'} |" for j, (f0, f1, ok) in change.items()]
    lines += [f"| layer | f at end of loading, t = {run.t_load:g} d (kPa) "
              f"| f at t = {t_last:g} d (kPa) | change (kPa) | grows |",
              "| --- | ---: | ---: | ---: | --- |", *rows, ""]
    if soft:
        return lines + [f"**Answer: {_verdict({j: c[2] for j, c in change.items()})}.**", ""]
    grows = [str(j) for j, c in change.items() if c[2]]
    where = ("every layer" if len(grows) == len(change) else
             f"layer(s) {', '.join(grows)} of {len(change)}" if grows else "no layer")
    return lines + [f"**Friction grows in {where}.**", ""]


def relative_rates(run: RunData) -> dict[int, tuple[float, float, float, float, float, bool]]:
    """Per layer of the centre pile: (w0, w_early, w_last, rate early, rate late, early faster).

    Relative displacement (m) at the end of loading, at the reference's ``early_day`` and at
    the last time; the two mean rates (m/day); whether the early rate is the larger. Empty
    without a reference early period.
    """
    out: dict[int, tuple[float, float, float, float, float, bool]] = {}
    t0 = run.t_load
    early = run.reference.early_day if run.reference is not None else None
    if early is None:
        return out
    for j, (t, v) in layer_series(run, "relative_displacement_m").items():
        w0, w_early = _at(t, v, t0), _at(t, v, early)
        t_last = float(t[-1])
        if w0 is None or w_early is None or t0 is None or t_last <= early or t0 >= early:
            continue
        w1 = float(v[-1])
        r1, r2 = (w_early - w0) / (early - t0), (w1 - w_early) / (t_last - early)
        out[j] = (w0, w_early, w1, r1, r2, r1 > r2 + REL_TOL * max(abs(r1), abs(r2)))
    return out


def _relative_section(run: RunData) -> list[str]:
    """Whether the relative displacement grows fastest in the reference's early period."""
    ref = run.reference
    if ref is None or ref.early_day is None:
        return []
    early = ref.early_day
    lines = [f"### Does relative displacement grow fastest in the first {early:g} days?", "",
             f"Mean growth rate of the layer-mean relative displacement of "
             f"{run.pile_name(run.centre_pile)} (+ = pile moves down relative to the soil) "
             f"from the end of loading to {early:g} days against {early:g} days to the last "
             "time; the early period is the reference's.", ""]
    if zero_note(run):
        return lines + ["**Answer: not applicable** — every relative displacement is zero "
                        "(tied pile-soil interface).", ""]
    rates, t0 = relative_rates(run), run.t_load
    if not rates:
        why = ("no end of loading (no `settlement.csv` with a load stage)" if t0 is None
               else f"no relative displacement data of the pile spanning the end of "
                    f"loading, {early:g} days and a later time")
        return lines + [f"**Answer: no data** — {why}.", ""]
    t_last = float(layer_series(run, "relative_displacement_m")[next(iter(rates))][0][-1])
    rows = [f"| {layer_label(run, j)} | {1000 * w0:.3f} | {1000 * we:.3f} "
            f"| {1000 * w1:.3f} | {1000 * r1:.5f} | {1000 * r2:.5f} "
            f"| {'yes' if ok else 'no'} |" for j, (w0, we, w1, r1, r2, ok) in rates.items()]
    lines += [f"| layer | w at t = {t0:g} d (mm) | w at {early:g} d (mm) "
              f"| w at {t_last:g} d (mm) | rate {t0:g}-{early:g} d (mm/day) "
              f"| rate {early:g}-{t_last:g} d (mm/day) | faster early |",
              "| --- | ---: | ---: | ---: | ---: | ---: | --- |", *rows, "",
              f"**Answer: {_verdict({j: r[5] for j, r in rates.items()})}.**", ""]
    return lines


def applied_vertical_load(scenario: dict) -> float | None:
    """The vertical load (kN, down) of the scenario's last load stage, from scenario.json."""
    load = None
    for st in scenario.get("stages") or []:
        if not isinstance(st, dict) or st.get("kind") != "load":
            continue
        if st.get("cap_load_kN") is not None:
            load = float(st["cap_load_kN"])
        elif st.get("Fz_kN") is not None:
            load = -float(st["Fz_kN"])
    return load


def _loads_section(run: RunData) -> list[str]:
    last = run.head_forces()
    if last is None:
        return []
    t, forces, source = last
    total = sum(forces.values())
    lines = [f"### Pile head forces at t = {t:g} day", "",
             f"Head force: {source}.", "",
             "| pile | place | x (m) | y (m) | head force (kN) | share (%) |",
             "| ---: | --- | ---: | ---: | ---: | ---: |"]
    for i in sorted(forces):
        p, f = run.pile(i), forces[i]
        share = f"{100 * f / total:.1f}" if total else "-"
        place = p.place if np.isfinite(p.x) else "-"
        lines.append(f"| {i} | {place} | {p.x:g} | {p.y:g} | {f:.1f} | {share} |")
    notes = [f"Total of the piles: {total:.1f} kN"]
    applied = applied_vertical_load(run.scenario)
    if applied is not None:
        notes.append(f"vertical load of the last load stage: {applied:.1f} kN")
    ref = run.reference
    if ref is not None and ref.total_load_kN is not None:
        notes.append(f"reference total load on the foundation: {ref.total_load_kN:g} kN")
    return lines + ["", "; ".join(notes) + ".", ""]


def _upper(text: str) -> str:
    """``text`` with its first letter a capital."""
    return text[:1].upper() + text[1:]


def _fmt(x: float, spec: str) -> str:
    return "-" if not np.isfinite(x) else format(x, spec)


def _gauges_section(run: RunData) -> list[str]:
    """The field method's error per gauge section of the centre pile at the last output time."""
    g = run.gauges
    if g is None:
        return []
    t = float(g["time_day"].max())
    g = select(g, g["time_day"] == t)
    g = select(g, np.argsort(g["section"]))
    lines = [f"### Virtual strain gauges: the field method against the model, t = {t:g} day", "",
             f"{_upper(run.pile_name(run.centre_pile))}, `gauges.csv`. Field method = the "
             "force, friction and relative displacement a field engineer derives from the "
             "model's section-mean strains (docs/model.md, \"Virtual strain gauges\"); "
             "error = field minus model. Friction: mean over the interval from the section down "
             "to the next one (none below the last section). Relative displacement: the field "
             "method's pile-top settlement minus the pile's shortening, i.e. the pile's "
             "settlement (model: column \"w pile\"), against the model's pile minus adjacent "
             "soil displacement: what it misses is the settlement of the soil next to the pile.",
             "", "| section | depth (m) | N field (kN) | N model (kN) | f field (kPa) "
             "| f model (kPa) | f error (kPa) | w field (mm) | w pile (mm) | w model (mm) "
             "| w error (mm) |", "| ---: " * 11 + "|"]
    for r in range(len(g["section"])):
        v = {k: float(a[r]) for k, a in g.items()}
        lines.append(
            f"| {int(v['section'])} | {v['depth_m']:g} | {v['N_kN']:.1f} | {v['N_model_kN']:.1f} "
            f"| {_fmt(v['f_kPa'], '.3f')} | {_fmt(v['f_model_kPa'], '.3f')} "
            f"| {_fmt(v['f_error_kPa'], '+.3f')} | {v['w_mm']:.3f} | {v['w_pile_mm']:.3f} "
            f"| {v['w_model_mm']:.3f} | {v['w_error_mm']:+.3f} |")
    return lines + [""]


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
             f"Run folder `{run.out_dir}`; run status: {status}. Piles: {len(run.piles) or '-'}; "
             f"layer histories of {run.pile_name(run.centre_pile)}. End of loading: {t_load}.",
             ""]
    if run.reference is not None:
        lines += [f"Published values beside the run's (the scenario's `[reference]`): "
                  f"{run.reference.source}.", ""]
    lines += _settlement_section(run)
    lines += _friction_section(run)
    lines += _relative_section(run)
    lines += _loads_section(run)
    lines += _gauges_section(run)
    figs = [(f, cap) for f, cap, needs, _ in FIGURES if run.has(needs)]
    if (run.out_dir / "plots" / VIEW3D).is_file():
        figs.append((VIEW3D, "3D view: settlement at the last output time"))
    if figs:
        lines += ["### Figures", ""]
        rel = figures_rel.rstrip("/")
        for f, cap in figs:
            lines += [f"![{cap}]({rel}/{f})", ""]
    return "\n".join(lines)
