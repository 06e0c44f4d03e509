"""Test configuration: import pilegroup before any test module.

So dolfinx_solver is imported before dolfinx/petsc4py, whatever a test module's import order.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest  # noqa: E402

import pilegroup  # noqa: F401
from pilegroup.studies.bench.small_pile import small_pile_text

BIN = Path(sys.executable).parent


def _run_cli(scenario, out, ranks=1, sets=(), cache=None, timeout=900):
    """``pilegroup run SCENARIO --out OUT --set ...`` on ``ranks`` ranks, under a timeout.

    Returns the completed process; ``cache``: the mesh cache folder (default: next to OUT).
    """
    cmd = [str(BIN / "pilegroup"), "run", str(scenario), "--out", str(out)]
    cmd += [a for kv in sets for a in ("--set", kv)]
    if ranks > 1:
        cmd = [str(BIN / "mpirun"), "-n", str(ranks), *cmd]
    cache = cache or Path(out).parent / "cache"
    return subprocess.run(cmd, capture_output=True, text=True, timeout=timeout,
                          env={**os.environ, "PILEGROUP_MESH_CACHE": str(cache)})


def _run_symmetry(tmp, text, name, symmetry, *, timeout, ranks=1):
    """``pilegroup run`` of the scenario ``text`` with ``numerics.symmetry``; its folder.

    The scenario is written to ``tmp/group.toml``, the run to ``tmp/name``; a run that does not
    exit 0 within ``timeout`` seconds (every caller states it: a dead rank must not hang the
    suite) fails the test with its error output.
    """
    f = Path(tmp) / "group.toml"
    f.write_text(text)
    r = _run_cli(f, Path(tmp) / name, ranks, [f"numerics.symmetry='{symmetry}'"],
                 timeout=timeout)
    assert r.returncode == 0, r.stderr[-3000:]
    return Path(tmp) / name


@pytest.fixture(scope="session")
def run_symmetry():
    """``run_symmetry(tmp, text, name, symmetry, timeout=S, ranks=1)``: a run folder."""
    return _run_symmetry


@pytest.fixture(scope="session")
def small_pile_source() -> str:
    """The TOML text of :func:`small_pile` (for tests that derive their own scenario)."""
    return small_pile_text()


@pytest.fixture
def small_pile(tmp_path):
    """The bundled single_pile scenario coarsened for the fast tier (same physics): its path."""
    f = tmp_path / "small_pile.toml"
    f.write_text(small_pile_text())
    return str(f)


@pytest.fixture(scope="session", params=["viscoplastic", "tied"])
def small_pile_run(request, tmp_path_factory):
    """Output folder of one ``run_scenario`` of ``small_pile`` per interface mode (session).

    Output times 0, 0.5 and 2 days; read it, do not change it (copy it first).
    """
    from pilegroup.model import load_scenario
    from pilegroup.studies.run.job import run_scenario

    mode = request.param
    base = tmp_path_factory.mktemp(f"small_pile_{mode}")
    f = base / "small_pile.toml"
    f.write_text(small_pile_text().replace('mode = "viscoplastic"', f'mode = "{mode}"'))
    with pytest.MonkeyPatch.context() as mp:
        mp.setenv("PILEGROUP_MESH_CACHE", str(base / "cache"))
        run_scenario(load_scenario(f), base / "run")
    return base / "run"


def _run_preset(sc, md, preset):
    """Every stage of ``sc`` on mesh ``md`` with linear-solver ``preset``, in this process.

    Returns ``(problem, settlement at the end, run log)``.
    """
    from pilegroup.geometry.adapter import resolve_geometry
    from pilegroup.solver.probes import SettlementProbe
    from pilegroup.solver.stepping import run_stages
    from pilegroup.studies.run import pipeline as pier

    pb = pier.build_problem(sc, resolve_geometry(sc), md, preset)
    probe = SettlementProbe(pb, pier.loaded_facets(sc, md))
    log = run_stages(pb, pier.solver_stages(sc), pier.time_stepping(sc),
                     geostatic_tol=pier.GEOSTATIC_TOL_M)
    return pb, probe(), log


@pytest.fixture(scope="session")
def run_preset():
    """``run_preset(sc, md, preset)``: a run in this process; ``(problem, settlement, log)``."""
    return _run_preset


@pytest.fixture(scope="session")
def run_cli():
    """``run_cli(scenario, out, ranks=1, sets=(), ...)``: ``pilegroup run`` under a timeout."""
    return _run_cli


def _rerun_under_mpirun(test_file, ranks=2, timeout=600):
    """Run the other tests of ``test_file`` under ``mpirun -n ranks`` (those without "mpirun"
    in their name); a dead rank ends at ``timeout`` s instead of hanging CI."""
    r = subprocess.run([str(BIN / "mpirun"), "-n", str(ranks), sys.executable, "-m", "pytest",
                        "-q", "-x", "-p", "no:cacheprovider", str(test_file), "-k", "not mpirun"],
                       capture_output=True, text=True, timeout=timeout)
    assert r.returncode == 0, r.stdout[-3000:] + r.stderr[-3000:]


@pytest.fixture(scope="session")
def rerun_under_mpirun():
    """``rerun_under_mpirun(__file__)``: the file's serial tests again on 2 ranks."""
    return _rerun_under_mpirun


@pytest.fixture(scope="session")
def needs_mpirun_forwarding_sigterm():
    """``needs_mpirun_forwarding_sigterm()`` skips a test that stops a run by SIGTERM to
    ``mpirun`` where ``mpirun`` does not pass SIGTERM on to the ranks.

    MPICH's Hydra does; Open MPI's (PRRTE, 6.0 measured) ends the ranks at once on SIGTERM and
    SIGINT, with no grace period, and forwards SIGUSR1 (docs/checkpoint.md, "Signals").
    """
    from mpi4py import MPI

    def need() -> None:
        if "Open MPI" in MPI.Get_library_version():
            pytest.skip("this mpirun ends the ranks at once on SIGTERM (Open MPI): SIGUSR1 is "
                        "its stop request (docs/checkpoint.md)")

    return need


def pytest_collection_modifyitems(config, items):
    """Tests marked ``hypre`` are skipped, with the reason, where this PETSc has no hypre (the
    PyPI wheels); the Docker image's PETSc has it (``make test-hypre``)."""
    from pilegroup.solver.presets import has_package

    if has_package("hypre"):
        return
    skip = pytest.mark.skip(reason="needs a PETSc with hypre (PyPI's has none): run in the "
                                   "Docker image, tools/container-smoke.sh")
    for item in items:
        if "hypre" in item.keywords:
            item.add_marker(skip)
