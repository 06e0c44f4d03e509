# Two commands: `make run` (main job on the bundled Pier 667 scenario) and `make test`.
# Both create .venv on first use with a Python >= 3.12 found by tools/find-python.sh.
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
OUT    ?= out/pier667

.PHONY: run run-mesh test test-slow test-mpi lint bootstrap clean

$(STAMP): pyproject.toml requirements.lock
	@test -x $(PY) || { PYBIN=$$(tools/find-python.sh) && echo "creating $(VENV) with $$PYBIN" && $$PYBIN -m venv $(VENV); }
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -c requirements.lock -e '.[fem,test]'
	@touch $(STAMP)

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

lint: $(STAMP)
	$(VENV)/bin/ruff check .

clean:
	rm -rf $(VENV) out build *.egg-info
