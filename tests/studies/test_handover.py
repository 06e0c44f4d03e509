"""The report an engineer hands on (``pilegroup report OUT``): ``report.md`` and a
self-contained ``report.html`` (studies.report.handover), on the small pile's real run.

The HTML parses with the standard library's parser, its tags balance, every image is a
``data:`` URI (nothing outside the file is referenced) and every table is there; a failed or
stopped run says so at its top; a folder that is not a run exits 2. The slow tier renders the
page in a headless Chromium when one is installed.
"""

import base64
import json
import os
import shutil
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import pytest

from pilegroup.studies.cli.commands import main
from pilegroup.studies.report.handover import REPORT_HTML, REPORT_MD, write_handover
from pilegroup.studies.report.scenario_table import key_value, moves_ground, scenario_rows

#: Elements without an end tag.
VOID = {"meta", "img", "br", "hr", "link", "input"}
#: Each table of the report by a heading of its first row.
TABLES = {"scenario": "part", "cap motion": "settlement (mm)", "pile heads": "Vx (kN)",
          "largest moments": "M max (kN m)", "load shares": "share (%)", "run": "item"}


class Page(HTMLParser):
    """What a test reads of the page: tags opened and closed, images, links, tables, text."""

    def __init__(self) -> None:
        super().__init__(convert_charrefs=True)
        self.stack: list[str] = []
        self.errors: list[str] = []
        self.urls: list[tuple[str, str]] = []
        self.tables: list[list[str]] = []
        self.h2: list[str] = []
        self.text: list[str] = []
        self._cell: str | None = None

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        for key in ("src", "href"):
            if a.get(key) is not None:
                self.urls.append((tag, a[key]))
        if tag == "table":
            self.tables.append([])
        if tag in ("th", "h2"):
            self._cell = ""
        if tag not in VOID:
            self.stack.append(tag)

    def handle_startendtag(self, tag, attrs):
        self.handle_starttag(tag, attrs)
        if tag not in VOID:
            self.handle_endtag(tag)

    def handle_endtag(self, tag):
        if not self.stack or self.stack[-1] != tag:
            self.errors.append(f"</{tag}> closes {self.stack[-1:]}")
            return
        self.stack.pop()
        if tag == "th" and self._cell is not None:
            self.tables[-1].append(self._cell.strip())
        elif tag == "h2" and self._cell is not None:
            self.h2.append(self._cell.strip())
        if tag in ("th", "h2"):
            self._cell = None

    def handle_data(self, data):
        self.text.append(data)
        if self._cell is not None:
            self._cell += data


def parse(path: Path) -> Page:
    page = Page()
    page.feed(path.read_text(encoding="utf-8"))
    page.close()
    assert not page.errors and not page.stack, (page.errors, page.stack)
    return page


def copy_run(src: Path, dst: Path) -> Path:
    shutil.copytree(src, dst, ignore=shutil.ignore_patterns("checkpoint", "*.h5"))
    return dst


@pytest.mark.parametrize("small_pile_run", ["viscoplastic"], indirect=True)
def test_report_html_is_self_contained_with_every_table(small_pile_run, tmp_path, capsys):
    run = copy_run(small_pile_run, tmp_path / "run")
    assert main(["report", str(run)]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert str(run / REPORT_MD) in printed and str(run / REPORT_HTML) in printed
    page = parse(run / REPORT_HTML)
    imgs = [u for tag, u in page.urls if tag == "img"]
    assert len(imgs) >= 3  # the figures of plots/ and of the mesh
    for u in imgs:
        assert u.startswith("data:image/png;base64,"), u[:60]
        assert base64.b64decode(u.split(",", 1)[1])[:8] == b"\x89PNG\r\n\x1a\n"
    assert all(u.startswith(("data:", "#")) for _, u in page.urls)  # nothing outside the file
    headers = [t[0:] for t in page.tables]
    for what, head in TABLES.items():
        assert any(head in t for t in headers), what
    assert page.h2[:5] == ["Scenario", "Cap motion at every output time",
                           "Pile heads and largest moments", "Load shares",
                           "Mesh, element, solver and wall time"]
    assert "Neutral plane and dragload" not in page.h2  # no ground action in this scenario
    text = " ".join(page.text)
    assert "Run complete." in text and "INCOMPLETE" not in text
    assert "layer 1: mud" in text and "Mohr–Coulomb" in text and "cap_load 500 kN" in text
    assert "Q1Q1" in text and "the pile" in text
    md = (run / REPORT_MD).read_text()
    assert "| the pile | 500.0 | 0.0 | 0.0 | 0.0 | 0.0 | 0.0 |" in md  # N at the head
    assert "| 2 | consolidation | 13.046 |" in md  # the cap's settlement at 2 days
    assert "](plots/settlement_time.png)" in md
    assert "| the pile | single | 500.0 | 100.0 | 1.00 |" in md
    assert "Vertical load of the last load stage: 500.0 kN." in md


@pytest.mark.parametrize("small_pile_run", ["viscoplastic"], indirect=True)
def test_neutral_plane_where_the_ground_moves(small_pile_run, tmp_path):
    run = copy_run(small_pile_run, tmp_path / "run")
    sc = json.loads((run / "scenario.json").read_text())
    sc["stages"].insert(2, {"name": "fill", "kind": "surcharge", "surcharge_kPa": 20.0,
                            "duration_day": 0.5})
    (run / "scenario.json").write_text(json.dumps(sc))
    write_handover(run, figures=False)
    page = parse(run / REPORT_HTML)
    assert "Neutral plane and dragload" in page.h2
    assert any("dragload (kN)" in t and "neutral plane (m)" in t for t in page.tables)
    assert "| stage 3: fill | surcharge; surcharge 20 kPa, duration 0.5 day |" in \
        (run / REPORT_MD).read_text()


@pytest.mark.parametrize(("summary", "words"), [
    ({"status": "failed", "reason": "NewtonFailed: no convergence at t = 1 day"},
     "INCOMPLETE RUN: the run failed** (NewtonFailed: no convergence at t = 1 day)"),
    ({"status": "interrupted", "signal": "SIGTERM", "t_day": 0.5, "stage": "loading"},
     "INCOMPLETE RUN: the run was stopped by SIGTERM at t = 0.5 day in stage `loading`.**"),
])
@pytest.mark.parametrize("small_pile_run", ["viscoplastic"], indirect=True)
def test_a_failed_or_stopped_run_says_so_at_its_top(small_pile_run, tmp_path, summary, words):
    run = copy_run(small_pile_run, tmp_path / "run")
    (run / "summary.json").write_text(json.dumps({"scenario": "single_pile", **summary}))
    assert main(["report", str(run)]) == 0
    md = (run / REPORT_MD).read_text().splitlines()
    assert md[0] == "# Report: single_pile" and words in md[2]
    page = parse(run / REPORT_HTML)
    assert "INCOMPLETE RUN" in "".join(page.text).split("Scenario", 1)[0]


def test_a_run_stopped_before_its_first_output(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    (run / "summary.json").write_text(json.dumps(
        {"scenario": "mine", "status": "failed", "reason": "MeshError: bad far field"}))
    (run / "scenario.json").write_text(json.dumps({"name": "mine", "stages": []}))
    assert main(["report", str(run)]) == 0
    md = (run / REPORT_MD).read_text()
    assert "INCOMPLETE RUN: the run failed** (MeshError: bad far field)" in md
    assert "No `settlement.csv` or `cap_motion.csv`" in md and "No `pile_heads.csv`" in md
    parse(run / REPORT_HTML)


@pytest.mark.parametrize("problem", ["missing", "empty", "other_files"])
def test_a_folder_that_is_not_a_run_exits_2(tmp_path, capsys, problem):
    folder = tmp_path / "folder"
    if problem != "missing":
        folder.mkdir()
    if problem == "other_files":
        (folder / "notes.txt").write_text("not a run\n")
        (folder / "data.csv").write_text("a,b\n1,2\n")
    assert main(["report", str(folder)]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and err.startswith("pilegroup: invalid input: ")
    assert ("no such folder" if problem == "missing" else "not a run output folder") in err
    assert not (folder / REPORT_HTML).exists()


def test_scenario_rows_name_each_layer_s_model_and_keys():
    sc = {"name": "mine", "site": {"depth_m": 30.0, "water_table_depth_m": 1.0},
          "soil": {"model": "mohr_coulomb"},
          "layers": [{"name": "fill", "thickness_m": 2.0, "E_MPa": 10.0, "nu": 0.3,
                      "phi_deg": 30.0, "c_kPa": 0.0, "lam": 0.2},
                     {"name": "clay", "thickness_m": None, "model": "modified_cam_clay",
                      "lam": 0.2, "kappa": 0.03, "M": 1.0, "e0": 1.5, "OCR": 1.2,
                      "E_MPa": 5.0, "excess_pore_pressure_ratio": 0.3}],
          "piles": {"diameter_m": 1.0, "length_in_soil_m": 20.0, "grid": [2, 3],
                    "spacing_m": [3.0, 3.0]},
          "cap": {"size_x_m": 9.0, "size_y_m": 6.0, "thickness_m": 2.0},
          "stages": [{"name": "geostatic", "kind": "geostatic"},
                     {"name": "braking", "kind": "load", "Fz_kN": -24000.0, "Fx_kN": 800.0,
                      "My_kNm": 6000.0, "duration_day": 1.0}]}
    rows = dict(scenario_rows(sc))
    assert rows["layer 1: fill"] == "0–2 m; Mohr–Coulomb; E 10 MPa, nu 0.3, phi 30°, c 0 kPa"
    assert rows["layer 2: clay"].startswith("2–30 m; Modified Cam Clay; lam 0.2, kappa 0.03, "
                                            "M 1, e0 1.5, OCR 1.2")
    assert "E 5 MPa" not in rows["layer 2: clay"]  # not a key of the model
    assert rows["piles"] == ("6 piles; diameter 1 m, length_in_soil 20 m, grid 2 × 3, "
                             "spacing 3 × 3 m")
    assert rows["cap"] == "size_x 9 m, size_y 6 m, thickness 2 m"
    assert rows["stage 2: braking"] == ("load; Fz -2.4e+04 kN, Fx 800 kN, My 6000 kN m, "
                                        "duration 1 day")
    assert moves_ground(sc)  # the clay starts with excess pore pressure
    assert not moves_ground({"layers": [{"name": "x"}], "stages": [{"kind": "load"}]})
    assert moves_ground({"stages": [{"kind": "groundwater"}]})
    assert key_value("output_days", [0, 0.5, 2]) == "output_days (0, 0.5, 2)"


def _chromium() -> str:
    """Debian's ``chromium``, installed with apt-get when it is missing (root, Debian only)."""
    found = shutil.which("chromium") or shutil.which("chromium-browser")
    if found:
        return found
    if shutil.which("apt-get") is None or os.geteuid() != 0:
        pytest.skip("no `chromium` on PATH and no apt-get as root to install Debian's")
    env = {**os.environ, "DEBIAN_FRONTEND": "noninteractive"}
    for cmd in (["apt-get", "update", "-qq"],
                ["apt-get", "install", "-y", "-qq", "--no-install-recommends", "chromium"]):
        r = subprocess.run(cmd, capture_output=True, text=True, timeout=1200, env=env)
        assert r.returncode == 0, f"{' '.join(cmd)}: {r.stderr[-2000:]}"
    found = shutil.which("chromium")
    assert found, "apt-get installed chromium, but it is not on PATH"
    return found


@pytest.mark.slow
@pytest.mark.parametrize("small_pile_run", ["viscoplastic"], indirect=True)
def test_a_headless_browser_renders_the_report(small_pile_run, tmp_path):
    browser = _chromium()
    run = copy_run(small_pile_run, tmp_path / "run")
    write_handover(run)
    html = (run / REPORT_HTML).resolve()
    shot = tmp_path / "page.png"
    flags = [browser, "--headless", "--no-sandbox", "--disable-gpu", "--no-first-run",
             "--disable-extensions", f"--user-data-dir={tmp_path / 'profile'}"]
    dom = subprocess.run([*flags, "--dump-dom", html.as_uri()], capture_output=True,
                         text=True, timeout=120)
    assert dom.returncode == 0, dom.stderr[-2000:]
    assert "Report: single_pile" in dom.stdout and dom.stdout.count("<table") >= 5
    r = subprocess.run([*flags, f"--screenshot={shot}", "--window-size=1200,3000",
                        html.as_uri()], capture_output=True, text=True, timeout=120)
    assert r.returncode == 0 and shot.is_file(), r.stderr[-2000:]
    assert shot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and shot.stat().st_size > 20_000
