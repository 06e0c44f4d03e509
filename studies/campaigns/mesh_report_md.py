"""The text of ``mesh_study.md`` (the numbers are gathered by :mod:`.mesh_report`)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Any

from pilegroup.studies.campaigns.gci import GCIResult, gci
from pilegroup.studies.campaigns.mesh_records import StudyInfo
from pilegroup.studies.report.paper_values import PAPER_SETTLEMENT_CM

#: Relative change (of the value) above which the answer is said to depend on the penalty.
PENALTY_TOL = 0.01
SETTLEMENT = "settlement_m"


def paper_gci() -> GCIResult:
    """The GCI of the paper's settlements (cm) from its three finest sizes (0.6, 0.3, 0.1 m)."""
    h = (0.1, 0.3, 0.6)
    return gci(h, (PAPER_SETTLEMENT_CM[0.1], PAPER_SETTLEMENT_CM[0.3], PAPER_SETTLEMENT_CM[0.6]))


def _f(x: Any, spec: str = ".4g") -> str:
    if x is None or (isinstance(x, float) and not math.isfinite(x)):
        return "–"
    return format(x, spec) if isinstance(x, int | float) else str(x)


def display(key: str) -> tuple[str, float]:
    """A quantity key as a label with its unit, and the factor from the stored unit."""
    if key == SETTLEMENT:
        return "cap settlement (mm)", 1000.0
    return key.replace("friction_kPa[", "shaft friction (kPa), ").rstrip("]"), 1.0


def _size_section(info: StudyInfo, sizes: list[dict[str, Any]]) -> list[str]:
    t_last = next((s["t_last_day"] for s in sizes if s["t_last_day"] is not None), None)
    lines = ["## The paper's Table 2 beside ours", "",
             "| h (m) | paper: elements | paper: time (h) | paper: settlement (cm) | ours: cells "
             "(model run) | unknowns | wall (s) | peak memory per rank (MB) | settlement (cm) at"
             f" t = {_f(t_last)} d | status |", "|" + "---|" * 10]
    for s in sizes:
        cells = _f(s["cells"], ",") + (f" ({s['symmetry']})" if s.get("symmetry") else "")
        lines.append(f"| {s['h_m']:g} | {_f(s['paper_elements'], ',')} | "
                     f"{_f(s['paper_hours'])} | {_f(s['paper_settlement_cm'])} | "
                     f"{cells if s['cells'] else '–'} | {_f(s['unknowns'], ',')} | "
                     f"{_f(s['wall_s'], '.1f')} | {_f(s['peak_rss_mb_max'], '.0f')} | "
                     f"{_f(s['settlement_cm'], '.4f')} | {s['status']} |")
    lines += ["", "The paper's columns are its Table 2 (Li et al. 2019, Section 5): elements of "
              "its whole-pier ABAQUS model, computation time on a machine it does not name, "
              "settlement of the pile foundation after 317 days. Ours: hexahedra of the model "
              "that ran (a symmetry-reduced model holds a half or a quarter of the whole), "
              "unknowns, wall time of the case (meshing, solve, outputs), the largest peak "
              "resident memory over the case's ranks, cap settlement at the last output time "
              f"of scenario `{info.scenario.name}`.", ""]
    skipped = [s for s in sizes if s["status"].startswith(("not run", "failed"))]
    if skipped:
        lines += ["### Sizes that did not run", ""]
        lines += [f"* h = {s['h_m']:g} m: {s['status']}" for s in skipped] + [""]
    return lines


def _gci_section(table: dict[str, GCIResult]) -> list[str]:
    lines = ["## Convergence: Richardson extrapolation and grid convergence index", ""]
    if not table:
        return lines + ["Needs three sizes that ran to completion; fewer did.", ""]
    g0 = next(iter(table.values()))
    lines += [f"From the three finest sizes that ran, h = {g0.h[0]:g}, {g0.h[1]:g}, "
              f"{g0.h[2]:g} m (r21 = {g0.r21:.3g}, r32 = {g0.r32:.3g}), at the last output "
              "time. h is the element size at the pile surfaces (`numerics.mesh.size_m`); the "
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
    pg = paper_gci()
    lines += ["", f"The same for the paper's settlements (0.6, 0.3, 0.1 m): p = {pg.p:.3g}, "
              f"extrapolated {pg.phi_ext:.4g} cm, GCI_fine21 = {100 * pg.gci_fine21:.3g} %.",
              "", "![settlement against h](settlement_vs_h.png)", ""]
    return lines


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
    lines += _size_section(info, sizes)
    lines += _gci_section(table)
    lines += ["## Error against computation time", "",
              "Relative difference of the settlement to the extrapolated value against the "
              "computation time, ours (wall time of each case) and the paper's (hours of its "
              "Table 2, against the extrapolation of its own three finest sizes).", "",
              "![error against time](error_vs_time.png)", "",
              "## Centre-pile profiles at the last output time", "",
              "![shaft friction](friction_profiles_sizes.png)",
              "![relative displacement](relative_displacement_profiles_sizes.png)", ""]
    lines += _penalty_section(info, penalty)
    return "\n".join(lines)


__all__ = ["PENALTY_TOL", "SETTLEMENT", "display", "paper_gci", "report_markdown"]
