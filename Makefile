# Two commands: `make run` (main job on the bundled Pier 667 scenario) and `make test`.
# Both create .venv on first use with a Python >= 3.12 found by tools/find-python.sh and the
# pinned PyPI packages (requirements.lock). With SYSTEM_PACKAGES=1 (set in the Docker image)
# .venv is made over the system's packages instead (Debian's DOLFINx, PETSc, Open MPI, pytest):
# tools/system-venv.sh.
VENV   ?= .venv
PY     := $(VENV)/bin/python
OUT    ?= out/pier667
SYSTEM_PACKAGES ?=
ifeq ($(SYSTEM_PACKAGES),1)
STAMP  := $(VENV)/.installed-system
else
STAMP  := $(VENV)/.installed
endif

.PHONY: run run-mesh test test-slow test-hypre test-mpi lint bootstrap clean

ifeq ($(SYSTEM_PACKAGES),1)
$(STAMP): pyproject.toml
	tools/system-venv.sh $(VENV)
	@touch $(STAMP)
else
$(STAMP): pyproject.toml requirements.lock
	@! grep -qs '^include-system-site-packages = true' $(VENV)/pyvenv.cfg || { echo "$(VENV) was made with SYSTEM_PACKAGES=1: run 'make clean' first" >&2; exit 1; }
	@test -x $(PY) || { PYBIN=$$(tools/find-python.sh) && echo "creating $(VENV) with $$PYBIN" && $$PYBIN -m venv $(VENV); }
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c requirements.lock -e '.[fem,test]'
	@touch $(STAMP)
endif

bootstrap: $(STAMP)

# The main job: every stage of Pier 667 on 2 ranks (outputs in $(OUT), see README).
run: $(STAMP)
	$(VENV)/bin/mpirun -n 2 $(VENV)/bin/pilegroup run pier667 --out $(OUT)

# Validate and mesh only (quick look at the model).
run-mesh: $(STAMP)
	$(VENV)/bin/pilegroup run pier667 --out $(OUT) --stop-after mesh

test: $(STAMP)
	$(VENV)/bin/ruff check .
	$(PY) -m pytest -m "not slow" -q

test-slow: $(STAMP)
	$(PY) -m pytest -m slow -q

# the hypre preset's tests: they need a PETSc with hypre (the Docker image's; skipped elsewhere)
test-hypre: $(STAMP)
	$(PY) -m pytest -m hypre -q -rs

lint: $(STAMP)
	$(VENV)/bin/ruff check .

clean:
	rm -rf $(VENV) out build *.egg-info
