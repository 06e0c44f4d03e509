"""BLAS threads: pilegroup's choice (docs/solver.md) reaches the BLAS libraries it loads."""

import os
import subprocess
import sys

import pytest

# Import what a run imports, then ask every OpenBLAS mapped into the process for its pool size.
PROBE = r"""
import ctypes, os
import pilegroup
import numpy, scipy.linalg
import dolfinx
from petsc4py import PETSc
paths = sorted({line.split()[-1] for line in open("/proc/self/maps")
                if "openblas" in line.split()[-1].lower() and ".so" in line})
print("OMP_NUM_THREADS", os.environ.get("OMP_NUM_THREADS"))
for p in paths:
    lib = ctypes.CDLL(p)
    for get, config in (("openblas_get_num_threads", "openblas_get_config"),
                        ("scipy_openblas_get_num_threads64_", "scipy_openblas_get_config64_"),
                        ("scipy_openblas_get_num_threads", "scipy_openblas_get_config")):
        if hasattr(lib, get):
            getattr(lib, config).restype = ctypes.c_char_p
            single = b"SINGLE_THREADED" in getattr(lib, config)()
            print("threads", getattr(lib, get)(), int(single), p)
            break
"""
BLAS_VARS = ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "GOTO_NUM_THREADS", "MKL_NUM_THREADS")


def _probe(**env_set) -> tuple[str | None, list[tuple[int, bool]]]:
    """OMP_NUM_THREADS in the process, and (pool size, single-threaded build) per OpenBLAS."""
    env = {k: v for k, v in os.environ.items()
           if k not in BLAS_VARS and not k.startswith(("PMI_", "OMPI_COMM_WORLD"))}
    env.update(env_set)
    r = subprocess.run([sys.executable, "-c", PROBE], capture_output=True, text=True, env=env,
                       timeout=300)
    assert r.returncode == 0, r.stderr[-3000:]
    omp, threads = None, []
    for line in r.stdout.splitlines():
        key, value, *_ = line.split()
        if key == "OMP_NUM_THREADS":
            omp = None if value == "None" else value
        elif key == "threads":
            threads.append((int(value), line.split()[2] == "1"))
    return omp, threads


@pytest.mark.parametrize("launcher", [{}, {"PMI_SIZE": "2"}, {"OMPI_COMM_WORLD_SIZE": "2"}],
                         ids=["serial", "mpich-rank", "openmpi-rank"])
def test_one_blas_thread_when_unset(launcher):
    omp, threads = _probe(**launcher)
    assert omp == "1"
    assert all(n == 1 for n, _ in threads), threads


def test_an_explicit_value_is_kept():
    """OMP_NUM_THREADS=2 is passed on; OpenBLAS caps its pool at the machine's cores."""
    omp, threads = _probe(OMP_NUM_THREADS="2")
    assert omp == "2"
    pool = min(2, os.cpu_count() or 1)
    assert all(n == (1 if single else pool) for n, single in threads), threads
