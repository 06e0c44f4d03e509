#!/usr/bin/env bash
# Make VENV (default .venv) over the system's Python packages: `make bootstrap SYSTEM_PACKAGES=1`
# (set in the Docker image). DOLFINx, PETSc, MPI, pytest and hypothesis come from the system
# (Debian's python3-dolfinx and friends, see Dockerfile); pilegroup is installed into the venv in
# editable mode without dependencies, and the system's mpirun and ruff are linked into the venv's
# bin/, where the tests and the Makefile look for them (as in the venv of PyPI wheels).
set -euo pipefail
venv=${1:-.venv}
# The system's tools: PATH without the venv's own bin/ (the image puts it first).
venv_bin=$(mkdir -p "$venv" && cd "$venv" && pwd)/bin
sys_path=$(printf '%s' "$PATH" | tr ':' '\n' | grep -vxF "$venv_bin" | paste -sd: -)
find_tool() { (PATH=$sys_path; command -v "$1") || { echo "SYSTEM_PACKAGES=1 needs $1 on PATH" >&2; exit 1; }; }
py=$(find_tool python3)
if ! "$py" -c 'import sys; assert sys.version_info >= (3, 12); import dolfinx, petsc4py, mpi4py' \
    2>/dev/null; then
  echo "SYSTEM_PACKAGES=1 needs the system's python3 (>= 3.12) with dolfinx, petsc4py and" \
       "mpi4py (Debian: python3-dolfinx; the packages are listed in the Dockerfile)" >&2
  exit 1
fi
mpirun=$(find_tool mpirun)
ruff=$(find_tool ruff)
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
ln -sf "$mpirun" "$venv/bin/mpirun"
ln -sf "$ruff" "$venv/bin/ruff"
