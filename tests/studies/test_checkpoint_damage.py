"""A damaged, cut-short or missing checkpoint file is refused with one line naming it.

Every file of a checkpoint is checked before a resume builds anything: the manifest by its
own SHA-256 (``manifest_sha256``) and JSON syntax, each rank file by the size and SHA-256 the
manifest records. Runs are subprocesses under a timeout (a rank waiting for another would fail
the test instead of blocking it).
"""

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

BIN = Path(sys.executable).parent
TIMEOUT = 300  # s, for every subprocess
SETS = ("outputs.plots=false",)


def _command(scenario, out, ranks=1, resume=False):
    cmd = [str(BIN / "pilegroup"), "run", str(scenario), "--out", str(out)]
    cmd += [a for kv in SETS for a in ("--set", kv)] + (["--resume"] if resume else [])
    return [str(BIN / "mpirun"), "-n", str(ranks), *cmd] if ranks > 1 else cmd


def _run(scenario, out, cache, ranks=1, resume=False):
    return subprocess.run(_command(scenario, out, ranks, resume), capture_output=True,
                          text=True, timeout=TIMEOUT,
                          env={**os.environ, "PILEGROUP_MESH_CACHE": str(cache)})


def _pilegroup_lines(stderr):
    assert "Traceback" not in stderr, stderr[-3000:]
    return [ln for ln in stderr.splitlines() if ln.startswith("pilegroup:")]


def _finished(tmp_path_factory, scenario, cache, ranks):
    out = tmp_path_factory.mktemp(f"ranks{ranks}") / "run"
    r = _run(scenario, out, cache, ranks=ranks)
    assert r.returncode == 0, r.stderr[-3000:]
    return out


@pytest.fixture(scope="module")
def finished(tmp_path_factory, scenario, cache):
    """A complete serial run: its last checkpoint stays in the folder."""
    return _finished(tmp_path_factory, scenario, cache, 1)


def _copy(run, tmp_path):
    out = tmp_path / "run"
    shutil.copytree(run, out)
    return out, out / "checkpoint"


def _manifest(folder):
    return json.loads((folder / "manifest.json").read_text())


def _cut(path, keep=0.5):
    data = path.read_bytes()
    path.write_bytes(data[:int(len(data) * keep)])
    return len(data)


def _flip(path, at=-100):
    data = bytearray(path.read_bytes())
    data[at] ^= 0xFF
    path.write_bytes(bytes(data))


def _damage(kind, folder):
    """Damage the checkpoint in ``folder`` as ``kind`` says; what the message must say."""
    m = _manifest(folder)
    rank0 = folder / m["files"][0]
    man = folder / "manifest.json"
    if kind == "rank file cut short":
        size = _cut(rank0)
        return f"checkpoint file {rank0} is cut short ({size // 2} bytes, the manifest says {size})"
    if kind == "rank file changed":
        _flip(rank0)
        return f"checkpoint file {rank0} is damaged (its SHA-256 differs from the manifest's)"
    if kind == "rank file missing":
        rank0.unlink()
        return f"checkpoint file {rank0} is missing"
    if kind == "manifest cut short":
        size = _cut(man)
        with pytest.raises(json.JSONDecodeError) as info:
            json.loads(man.read_text())
        return (f"checkpoint file {man} is cut short or damaged (not valid JSON at byte "
                f"{info.value.pos} of {size // 2})")
    if kind == "manifest value changed":  # still valid JSON: only its seal tells
        man.write_text(man.read_text().replace(f'"t_day": {m["t_day"]!r}', '"t_day": 1.5', 1))
        return f"checkpoint file {man} is damaged (its content does not match its manifest_sha256)"
    if kind in ("manifest key lost", "manifest format lost"):
        key = "state" if kind == "manifest key lost" else "format"
        del m[key]
        man.write_text(json.dumps(m))
        return f"checkpoint file {man} is damaged (no {key!r})"
    raise AssertionError(kind)


KINDS = ("rank file cut short", "rank file changed", "rank file missing", "manifest cut short",
         "manifest value changed", "manifest key lost", "manifest format lost")


@pytest.mark.parametrize("kind", KINDS)
def test_check_resume_names_the_damaged_file(kind, finished, scenario, tmp_path):
    from mpi4py import MPI

    from pilegroup.errors import ScenarioError
    from pilegroup.model import load_scenario
    from pilegroup.studies.run.checkpoint import check_resume

    sc = load_scenario(scenario, {"outputs.plots": False})
    out, folder = _copy(finished, tmp_path)
    check_resume(out, sc, MPI.COMM_SELF)  # intact: accepted
    what = _damage(kind, folder)
    with pytest.raises(ScenarioError) as info:
        check_resume(out, sc, MPI.COMM_SELF)
    assert str(info.value) == (f"--resume = '{out}': {what}; run without --resume to start "
                               "again")


def test_manifest_records_size_and_sha256_of_each_rank_file(finished):
    from pilegroup.studies.run.checkpoint import file_sha256

    folder = finished / "checkpoint"
    m = _manifest(folder)
    assert m["format"] == 2 and len(m["files"]) == len(m["sha256"]) == len(m["bytes"]) == 1
    assert m["sha256"][0] == file_sha256(folder / m["files"][0])
    assert m["bytes"][0] == (folder / m["files"][0]).stat().st_size


@pytest.mark.parametrize("kind", ["rank file cut short", "manifest cut short"])
def test_resume_from_damaged_checkpoint_exits_2_with_one_line(kind, finished, scenario, cache,
                                                              tmp_path):
    out, folder = _copy(finished, tmp_path)
    what = _damage(kind, folder)
    r = _run(scenario, out, cache, resume=True)
    assert r.returncode == 2, r.stderr[-3000:]
    assert _pilegroup_lines(r.stderr) == [
        f"pilegroup: invalid input: --resume = '{out}': {what}; run without --resume to start "
        "again"]
    assert "Error" not in r.stderr  # no exception name (BadZipFile, KeyError)


@pytest.fixture(scope="module")
def finished_on_two_ranks(tmp_path_factory, scenario, cache):
    return _finished(tmp_path_factory, scenario, cache, 2)


@pytest.mark.mpi
@pytest.mark.parametrize("kind", ["rank 1 cut short", "rank 1 missing", "manifest cut short"])
def test_two_ranks_agree_on_a_damaged_checkpoint(kind, finished_on_two_ranks, scenario, cache,
                                                 tmp_path):
    """Rank 1's file is damaged: rank 0 (whose file is intact) refuses with it, one line."""
    out, folder = _copy(finished_on_two_ranks, tmp_path)
    m = _manifest(folder)
    assert m["ranks"] == 2 and len(m["sha256"]) == 2
    rank1 = folder / m["files"][1]
    if kind == "rank 1 cut short":
        size = _cut(rank1, 0.25)
        what = (f"checkpoint file {rank1} is cut short ({size // 4} bytes, the manifest says "
                f"{size})")
    elif kind == "rank 1 missing":
        rank1.unlink()
        what = f"checkpoint file {rank1} is missing"
    else:
        what = _damage(kind, folder)
    r = _run(scenario, out, cache, ranks=2, resume=True)
    assert r.returncode == 2, r.stderr[-3000:]
    assert _pilegroup_lines(r.stderr) == [
        f"pilegroup: invalid input: --resume = '{out}': {what}; run without --resume to start "
        "again"]
