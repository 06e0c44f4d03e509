#!/usr/bin/env bash
# Make VENV (default .venv) over the system's Python packages: `make bootstrap SYSTEM_PACKAGES=1`
# (set in the Docker image). DOLFINx, PETSc, MPI, pytest and hypothesis come from the system
# (Debian's python3-dolfinx and friends, see Dockerfile); pilegroup is installed into the venv in
# editable mode without dependencies, and the system's mpirun and ruff are linked into the venv's
# bin/, where the tests and the Makefile look for them (as in the venv of PyPI wheels).
set -euo pipefail
venv=${1:-.venv}
py=$(command -v python3) || { echo "SYSTEM_PACKAGES=1 needs python3 on PATH" >&2; exit 1; }
if ! "$py" -c 'import sys; assert sys.version_info >= (3, 12); import dolfinx, petsc4py, mpi4py' \
    2>/dev/null; then
  echo "SYSTEM_PACKAGES=1 needs the system's python3 (>= 3.12) with dolfinx, petsc4py and" \
       "mpi4py (Debian: python3-dolfinx; the packages are listed in the Dockerfile)" >&2
  exit 1
fi
for tool in mpirun ruff; do
  command -v "$tool" >/dev/null || { echo "SYSTEM_PACKAGES=1 needs $tool on PATH" >&2; exit 1; }
done
if [ -e "$venv/pyvenv.cfg" ] && ! grep -q '^include-system-site-packages = true' "$venv/pyvenv.cfg"
then
  echo "$venv holds PyPI's packages (made without SYSTEM_PACKAGES=1): run 'make clean' first" >&2
  exit 1
fi
if [ ! -x "$venv/bin/python" ]; then
  echo "creating $venv over the system's $py (--system-site-packages)"
  "$py" -m venv --system-site-packages "$venv"
fi
"$venv/bin/python" -m pip install --quiet --no-deps --no-build-isolation --no-index -e .
ln -sf "$(command -v mpirun)" "$venv/bin/mpirun"
ln -sf "$(command -v ruff)" "$venv/bin/ruff"
