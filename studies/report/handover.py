"""The report an engineer hands on: ``report.md`` and a self-contained ``report.html``.

``pilegroup report OUT`` writes both into the run folder ``OUT``: how the run ended (at the
top: a failed or stopped run says so), the scenario in one table
(:mod:`pilegroup.studies.report.scenario_table`), the cap's motion, the pile heads, the largest
moments, the load shares, the neutral plane where the ground moves and the run's mesh and
solver (:mod:`pilegroup.studies.report.handover_tables`), then the figures of ``OUT/plots``.
The HTML page is rendered from the Markdown by ``markdown-it-py`` with every figure embedded as
a ``data:`` URI, so it opens offline in any browser and can be mailed as one file.

A folder that holds none of a run's CSV files and no ``summary.json`` is not a run
(:class:`~pilegroup.model.ScenarioError`, exit 2); a run that stopped before its first output
(``summary.json`` only) gets a report of its status, scenario and discretisation.
"""

from __future__ import annotations

import base64
import html
import json
import logging
import mimetypes
from pathlib import Path
from typing import Any

from markdown_it import MarkdownIt
from markdown_it.token import Token

from pilegroup.fileio import write_text_atomic
from pilegroup.model import ScenarioError
from pilegroup.studies.report.handover_tables import (
    cap_motion_section,
    heads_section,
    neutral_section,
    run_section,
    shares_section,
    status_lines,
)
from pilegroup.studies.report.plots import FIGURES
from pilegroup.studies.report.run_report import write_report
from pilegroup.studies.report.scenario_table import scenario_table
from pilegroup.studies.report.view3d import FILE as VIEW3D
from pilegroup.studies.results.rundata import RUN_FILES, RunData, load_run

log = logging.getLogger(__name__)

REPORT_MD = "report.md"
REPORT_HTML = "report.html"
#: Figures of the mesh (``mesh/``) shown after those of ``plots/``.
MESH_FIGURES = (("mesh/plan.png", "Mesh: plan view"), ("mesh/cutaway.png", "Mesh: cutaway"))

_CSS = """
body { font-family: system-ui, -apple-system, "Segoe UI", Helvetica, Arial, sans-serif;
       color: #1b1b1b; margin: 0; background: #fafafa; }
main { max-width: 1100px; margin: 0 auto; padding: 1.5rem 2rem 3rem; background: #fff; }
h1 { border-bottom: 2px solid #333; padding-bottom: .3rem; }
h2 { margin-top: 2.2rem; border-bottom: 1px solid #ccc; padding-bottom: .2rem; }
table { border-collapse: collapse; margin: .6rem 0 1rem; font-size: .9rem; display: block;
        overflow-x: auto; }
th, td { border: 1px solid #ccc; padding: .25rem .55rem; vertical-align: top; }
th { background: #eef1f4; }
tr:nth-child(even) td { background: #f7f8fa; }
td { font-variant-numeric: tabular-nums; }
blockquote { border-left: 5px solid #c0392b; background: #fdecea; margin: 1rem 0;
             padding: .4rem 1rem; }
img { max-width: 100%; height: auto; display: block; margin: .5rem 0 1.5rem; }
code { background: #f0f0f0; padding: 0 .2rem; border-radius: 3px; }
@media print { main { max-width: none; } h2 { page-break-after: avoid; }
               img, table { page-break-inside: avoid; } }
"""


def _json(path: Path) -> dict[str, Any]:
    try:
        data = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):
        return {}
    return data if isinstance(data, dict) else {}


def load_report_run(out_dir: Path) -> RunData:
    """The run folder ``out_dir`` read for its report.

    A folder with none of the CSV files of a run but a ``summary.json`` (a run that stopped
    before its first output) gives a :class:`RunData` without tables. Raises
    :class:`ScenarioError` for a folder that does not exist or is not a run.
    """
    out = Path(out_dir)
    if not out.is_dir():
        raise ScenarioError("OUT_DIR", str(out), "no such folder")
    if any((out / name).is_file() for name in RUN_FILES):
        return load_run(out)
    summary = _json(out / "summary.json")
    if not summary:
        raise ScenarioError("OUT_DIR", str(out), f"holds no summary.json and none of "
                            f"{', '.join(RUN_FILES)}: not a run output folder")
    return RunData(out, None, None, None, None, None, summary, 1, None, {},
                   scenario=_json(out / "scenario.json"))


def _figures(out: Path) -> list[tuple[str, str]]:
    """The figures of the run that exist: ``(path relative to out, caption)``."""
    figs = [(f"plots/{name}", caption) for name, caption, _, _ in FIGURES]
    figs.append((f"plots/{VIEW3D}", "3D view: settlement at the last output time"))
    figs += list(MESH_FIGURES)
    return [(rel, cap) for rel, cap in figs if (out / rel).is_file()]


def handover_markdown(run: RunData) -> str:
    """The text of ``report.md`` of the run ``run`` (figures linked from ``plots/``)."""
    name = run.summary.get("scenario") or run.scenario.get("name") or run.out_dir.name
    lines = [f"# Report: {name}", "", *status_lines(run.summary),
             f"Run folder `{run.out_dir}`. Units: kN, m, day; depths below the ground "
             "surface; every value is the change since the geostatic state.", ""]
    lines += scenario_table(run.scenario)
    lines += cap_motion_section(run)
    lines += heads_section(run)
    lines += shares_section(run)
    lines += neutral_section(run)
    lines += run_section(run.summary)
    figs = _figures(run.out_dir)
    if figs:
        lines += ["## Figures", ""]
        for rel, cap in figs:
            lines += [f"**{cap}**", "", f"![{cap}]({rel})", ""]
    return "\n".join(lines)


def data_uri(path: Path) -> str:
    """The file ``path`` as a ``data:`` URI (its type from its suffix)."""
    mime = mimetypes.guess_type(path.name)[0] or "application/octet-stream"
    return f"data:{mime};base64,{base64.b64encode(path.read_bytes()).decode('ascii')}"


def _embed_images(tokens: list[Token], base: Path) -> None:
    """Every image of ``tokens`` embedded; one whose file is missing becomes a note."""
    for tok in tokens:
        for child in tok.children or []:
            if child.type != "image":
                continue
            src = str(child.attrGet("src") or "")
            path = base / src
            if src and not src.startswith("data:") and path.is_file():
                child.attrSet("src", data_uri(path))
            elif not src.startswith("data:"):
                log.warning("figure %s not found: left out of the HTML report", path)
                child.type, child.tag, child.children = "text", "", None
                child.content, child.attrs = f"[figure missing: {src}]", {}


def markdown_to_html(text: str, base: Path, title: str) -> str:
    """A standalone HTML page of the Markdown ``text``; images relative to ``base`` embedded."""
    md = MarkdownIt("commonmark", {"html": False, "xhtmlOut": False}).enable("table")
    tokens = md.parse(text)
    _embed_images(tokens, base)
    body = md.renderer.render(tokens, md.options, {})
    return ("<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
            "<meta name=\"viewport\" content=\"width=device-width, initial-scale=1\">\n"
            f"<title>{html.escape(title)}</title>\n<style>{_CSS}</style>\n</head>\n<body>\n"
            f"<main>\n{body}</main>\n</body>\n</html>\n")


def write_handover(out_dir: Path, figures: bool = True) -> list[Path]:
    """Write the figures, ``report.md`` and ``report.html`` of the run in ``out_dir``.

    ``figures``: redraw ``plots/*.png`` first. Returns the paths written. Raises
    :class:`ScenarioError` if ``out_dir`` is not a run folder.
    """
    run = load_report_run(Path(out_dir))
    has_tables = any((run.out_dir / name).is_file() for name in RUN_FILES)
    written = write_report(run.out_dir) if figures and has_tables else []
    text = handover_markdown(run)
    written.append(write_text_atomic(run.out_dir / REPORT_MD, text))
    title = f"Report: {run.summary.get('scenario') or run.out_dir.name}"
    written.append(write_text_atomic(run.out_dir / REPORT_HTML,
                                     markdown_to_html(text, run.out_dir, title)))
    return written
