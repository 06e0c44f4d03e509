"""docs/tutorial.md, run as a new user would: every command of it, in order, in an empty folder.

The tutorial's runnable commands are the ``$ `` lines of its ```console blocks; its ```toml
block whose first line is ``# FILE`` is the edit a user makes, written to FILE at its place in
the text. The commands run under bash in a temporary folder with the venv's ``bin`` first on
PATH (so ``pilegroup`` is the venv's entry point), each must exit 0, and every
``out/my_site/...`` file the text names must exist at the end. The install block (```sh, in the
repository) is checked by ``make -n bootstrap`` (the target exists; nothing is installed).
About 20 s on the shared 2-core machine.
"""

import os
import re
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
TUTORIAL = ROOT / "docs" / "tutorial.md"
BIN = Path(sys.executable).parent
FENCE = re.compile(r"^```(\w*)\n(.*?)^```$", re.S | re.M)


def steps(text):
    """The tutorial's steps in order: ``("run", command)`` or ``("write", name, content)``."""
    out = []
    for lang, body in FENCE.findall(text):
        if lang == "console":
            out += [("run", line[2:]) for line in body.splitlines() if line.startswith("$ ")]
        elif lang == "toml" and body.startswith("# "):
            out.append(("write", body.splitlines()[0][2:].strip(), body))
    return out


def test_the_tutorial_names_its_steps():
    got = steps(TUTORIAL.read_text())
    runs = [s[1] for s in got if s[0] == "run"]
    writes = [s[1] for s in got if s[0] == "write"]
    assert writes == ["my_site.toml"]
    assert runs[0].startswith("pilegroup scenario show ")
    assert any(r.startswith("pilegroup scenario validate my_site.toml") for r in runs)
    assert any(r.startswith("pilegroup run my_site.toml --out out/my_site") for r in runs)
    assert runs[-1] == "pilegroup report out/my_site"
    kinds = [s[0] for s in got]
    assert kinds.index("write") == 1  # the edit follows `scenario show`, before anything else


def test_install_target_exists():
    r = subprocess.run(["make", "-n", "bootstrap"], cwd=ROOT, capture_output=True, text=True,
                       timeout=60)
    assert r.returncode == 0, r.stderr
    assert "make bootstrap" in TUTORIAL.read_text()


def test_every_command_of_the_tutorial_runs(tmp_path):
    text = TUTORIAL.read_text()
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ['PATH']}",
           "PILEGROUP_MESH_CACHE": str(tmp_path / ".cache")}
    work = tmp_path / "my_site"
    work.mkdir()
    shown = None
    for step in steps(text):
        if step[0] == "write":
            (work / step[1]).write_text(step[2])
            continue
        r = subprocess.run(["bash", "-euo", "pipefail", "-c", step[1]], cwd=work, env=env,
                           capture_output=True, text=True, timeout=300)
        assert r.returncode == 0, f"$ {step[1]}\n{r.stdout[-2000:]}\n{r.stderr[-3000:]}"
        if step[1].startswith("pilegroup scenario show "):
            shown = (work / "my_site.toml").read_text()
        if step[1].startswith("pilegroup scenario validate"):
            assert "valid scenario 'my_site'" in r.stdout + r.stderr
    # `scenario show` wrote the bundled scenario, which the edit then replaced
    assert shown and "[[layers]]" in shown and "single_pile" in shown
    out = work / "out" / "my_site"
    assert '"status": "complete"' in (out / "summary.json").read_text()
    named = set(re.findall(r"out/my_site/[\w./]+\w", text))
    missing = sorted(n for n in named if not (work / n).exists())
    assert not missing, missing
    for name in ("report.md", "report.html"):
        assert (out / name).stat().st_size > 0
    assert "# Report: my_site" in (out / "report.md").read_text()
