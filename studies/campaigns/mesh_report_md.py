"""The text of ``mesh_study.md`` (the numbers are gathered by :mod:`.mesh_report`).

A published mesh study is written of only where the scenario's ``[reference]`` carries one
(:attr:`~pilegroup.studies.campaigns.mesh_records.StudyInfo.published`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from pilegroup.model.reference import MeshStudyReference
from pilegroup.studies.campaigns.gci import GCIResult, gci
from pilegroup.studies.campaigns.mesh_records import StudyInfo

#: Relative change (of the value) above which the answer is said to depend on the penalty.
PENALTY_TOL = 0.01
SETTLEMENT = "settlement_m"


def published_gci(pub: MeshStudyReference) -> GCIResult | None:
    """The GCI of a published study's settlements (m) from its three finest sizes.

    None with fewer than three sizes.
    """
    if len(pub.sizes_m) < 3:
        return None
    return gci(tuple(pub.sizes_m[:-4:-1]), tuple(pub.settlements_m[:-4:-1]))


def _f(x: Any, spec: str = ".4g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return format(x, spec) if isinstance(x, int | float) else str(x)


def display(key: str) -> tuple[str, float]:
    """A quantity key as a label with its unit, and the factor from the stored unit."""
    if key == SETTLEMENT:
        return "cap settlement (mm)", 1000.0
    return key.replace("friction_kPa[", "shaft friction (kPa), ").rstrip("]"), 1.0


def _published_intro(source: str, pub: MeshStudyReference) -> str:
    """Where the published columns come from: the reference's source and the study's note."""
    what = f": {pub.note}" if pub.note else ""
    return (f"The published columns ({pub.label}) are the scenario's `[reference.mesh_study]` "
            f"from {source}{what}. ")


def _size_section(info: StudyInfo, sizes: list[dict[str, Any]]) -> list[str]:
    t_last = next((s["t_last_day"] for s in sizes if s["t_last_day"] is not None), None)
    pub = info.published
    head = ("| h (m) | published: elements | published: time (h) | published: settlement (cm) "
            if pub else "| h (m) ")
    lines = ["## The published mesh study beside ours" if pub else "## The sizes", "",
             head + "| ours: cells (model run) | unknowns | wall (s) | peak memory per rank (MB) "
             f"| settlement (cm) at t = {_f(t_last)} d | status |",
             "|" + "---|" * (10 if pub else 7)]
    for s in sizes:
        cells = _f(s["cells"], ",") + (f" ({s['symmetry']})" if s.get("symmetry") else "")
        published = (f"{_f(s['published_elements'], ',')} | {_f(s['published_hours'])} | "
                     f"{_f(s['published_settlement_cm'])} | " if pub else "")
        lines.append(f"| {s['h_m']:g} | {published}"
                     f"{cells if s['cells'] else '–'} | {_f(s['unknowns'], ',')} | "
                     f"{_f(s['wall_s'], '.1f')} | {_f(s['peak_rss_mb_max'], '.0f')} | "
                     f"{_f(s['settlement_cm'], '.4f')} | {s['status']} |")
    ref = info.scenario.reference
    intro = _published_intro(ref.source, pub) if pub is not None and ref is not None else ""
    lines += ["", intro + "Ours: hexahedra of the model "
              "that ran (a symmetry-reduced model holds a half or a quarter of the whole), "
              "unknowns, wall time of the case (meshing, solve, outputs), the largest peak "
              "resident memory over the case's ranks, cap settlement at the last output time "
              f"of scenario `{info.scenario.name}`.", ""]
    skipped = [s for s in sizes if s["status"].startswith(("not run", "failed"))]
    if skipped:
        lines += ["### Sizes that did not run", ""]
        lines += [f"* h = {s['h_m']:g} m: {s['status']}" for s in skipped] + [""]
    return lines


def _gci_section(table: dict[str, GCIResult], pub: MeshStudyReference | None,
                 element: str) -> list[str]:
    lines = ["## Convergence: Richardson extrapolation and grid convergence index", ""]
    if not table:
        return lines + ["Needs three sizes that ran to completion; fewer did.", ""]
    g0 = next(iter(table.values()))
    lines += [f"From the three finest sizes that ran, h = {g0.h[0]:g}, {g0.h[1]:g}, "
              f"{g0.h[2]:g} m (r21 = {g0.r21:.3g}, r32 = {g0.r32:.3g}), at the last output "
              "time. h is the element size at the pile surfaces (`numerics.mesh.size_m`) of the "
              f"{element} pair; the "
              "far-field and vertical sizing are the same for every size, so h is the refined "
              "length. Observed order p, extrapolated value and GCI by Celik et al. (2008) "
              "(Fs = 1.25).", "",
              "| quantity | h1 | h2 | h3 | p | extrapolated | e_a21 | e_ext21 | GCI_fine21 | "
              "convergence |", "|" + "---|" * 10]
    for k, g in table.items():
        label, sc = display(k)
        lines.append(f"| {label} | {_f(sc * g.phi[0])} | {_f(sc * g.phi[1])} | "
                     f"{_f(sc * g.phi[2])} | {_f(g.p, '.3g')} | {_f(sc * g.phi_ext)} | "
                     f"{_f(100 * g.e_a21, '.3g')} % | {_f(100 * g.e_ext21, '.3g')} % | "
                     f"{_f(100 * g.gci_fine21, '.3g')} % | {g.note} |")
    pg = published_gci(pub) if pub is not None else None
    if pg is not None and pg.defined:
        sizes = ", ".join(f"{h:g}" for h in reversed(pg.h))
        lines += ["", f"The same for the published settlements ({pub.label}; {sizes} m): "
                  f"p = {pg.p:.3g}, extrapolated {100 * pg.phi_ext:.4g} cm, GCI_fine21 = "
                  f"{100 * pg.gci_fine21:.3g} %."]
    return lines + ["", "![settlement against h](settlement_vs_h.png)", ""]


def _penalty_section(info: StudyInfo, checks: Sequence[dict[str, Any]]) -> list[str]:
    factor = info.scenario.interface.normal_stiffness_factor
    lines = ["## Interface normal penalty", "",
             f"The interface's normal stiffness is `interface.normal_stiffness_factor` (here "
             f"{factor:g}) x E of the layer / h, so it grows as h shrinks. The coarsest and the "
             f"finest sizes ran again with the factor x {info.penalty_factor:g}.", ""]
    if info.scenario.interface.mode == "tied":
        return lines + ["Not run: the piles are tied to the soil (`interface.mode = "
                        "\"tied\"`), there is no interface penalty.", ""]
    if not checks:
        return lines + ["Not run: no size ran.", ""]
    lines += ["| h (m) | case | cap settlement change | largest friction change | |",
              "|---|---|---|---|---|"]
    worst = 0.0
    for c in checks:
        if c["status"] != "complete":
            lines.append(f"| {c['h_m']:g} | {c['case']} | – | – | {c['status']} |")
            continue
        ch = c["change"]
        fric = {k: v for k, v in ch.items() if k != SETTLEMENT}
        key = max(fric, key=lambda k: abs(fric[k])) if fric else None
        worst = max([worst, *map(abs, ch.values())])
        settle = _f(100 * ch.get(SETTLEMENT, math.nan), "+.3g")
        most = f"{100 * fric[key]:+.3g} % ({display(key)[0]})" if key else "–"
        lines.append(f"| {c['h_m']:g} | {c['case']} | {settle} % | {most} | |")
    verdict = ("does not depend on it" if worst <= PENALTY_TOL else "depends on it")
    lines += ["", f"Largest relative change of any reported quantity: {100 * worst:.3g} %: the "
              f"answer {verdict} (threshold {100 * PENALTY_TOL:g} % of the value).", ""]
    return lines


def report_markdown(info: StudyInfo, sizes: list[dict[str, Any]], table: dict[str, GCIResult],
                    penalty: Sequence[dict[str, Any]], machine: str) -> str:
    """``mesh_study.md``."""
    lines = [f"# Mesh study: {info.scenario.name}", "", f"Machine: {machine}.", "",
             "Every case's run folder is `h<size>/` (penalty cases `h<size>_penalty_x<factor>/`);"
             " the per-case numbers at every output time are in `batch.csv` and `batch.json`, "
             "the per-size numbers of this report in `mesh_study.csv` and `gci.csv`.", ""]
    pub = info.published
    lines += _size_section(info, sizes)
    lines += _gci_section(table, pub, info.scenario.numerics.element)
    theirs = (f", and the published study's ({pub.label}: its hours, against the extrapolation "
              "of its own three finest sizes)" if pub is not None and pub.hours else "")
    lines += ["## Error against computation time", "",
              "Relative difference of the settlement to the extrapolated value against the "
              f"computation time: ours (wall time of each case){theirs}.", "",
              "![error against time](error_vs_time.png)", "",
              "## Centre-pile profiles at the last output time", "",
              "![shaft friction](friction_profiles_sizes.png)",
              "![relative displacement](relative_displacement_profiles_sizes.png)", ""]
    lines += _penalty_section(info, penalty)
    return "\n".join(lines)


__all__ = ["PENALTY_TOL", "SETTLEMENT", "display", "published_gci", "report_markdown"]
