"""Both a normal (wheel) and an editable install import every sub-package."""

import os
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
SUBPACKAGES = ["model", "model.scenarios", "geometry", "constitutive", "solver", "studies",
               "studies.results", "studies.run", "studies.report", "studies.batch",
               "studies.verification", "studies.campaigns", "studies.lab", "studies.bench",
               "studies.cli"]
PROBE = (
    "import importlib, sys\n"
    "import pilegroup\n"
    f"for s in {SUBPACKAGES!r}:\n"
    "    m = importlib.import_module('pilegroup.' + s)\n"
    "    print(s, m.__file__)\n"
    "from pilegroup.model import load_scenario\n"
    "print('pier667', load_scenario('pier667').piles.count)\n"
)


def _probe(env=None, cwd=None) -> dict[str, str]:
    r = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True,
                       env=env, cwd=cwd, timeout=300)
    assert r.returncode == 0, r.stderr
    return dict(line.split(" ", 1) for line in r.stdout.splitlines())


def test_editable_install_imports_every_subpackage(tmp_path):
    out = _probe(cwd=tmp_path)  # outside the repository: the editable finder must map folders
    assert out["pier667"] == "9"
    for s in SUBPACKAGES:
        assert out[s].startswith(str(ROOT)), (s, out[s])


def test_normal_install_imports_every_subpackage(tmp_path):
    target = tmp_path / "site"
    r = subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                        "--no-build-isolation", "--target", str(target), str(ROOT)],
                       capture_output=True, text=True, timeout=600)
    if r.returncode != 0:
        pytest.fail(f"pip install failed:\n{r.stderr[-3000:]}")
    env = dict(os.environ, PYTHONPATH=str(target))
    out = _probe(env=env, cwd=tmp_path)
    assert out["pier667"] == "9"
    for s in SUBPACKAGES:
        assert out[s].startswith(str(target)), (s, out[s])


def test_atomic_files_get_the_usual_permissions(tmp_path):
    """Run outputs are readable by others like any file the user creates (umask applies)."""
    import os

    from pilegroup.fileio import write_text_atomic

    old = os.umask(0o022)
    try:
        path = write_text_atomic(tmp_path / "a.csv", "x\n")
    finally:
        os.umask(old)
    assert path.stat().st_mode & 0o777 == 0o644
