# ccopt: two commands on a fresh machine.
#   make demo   creates .venv, installs ccopt, runs the main job
#   make test   creates .venv if needed, installs ccopt, runs the tests
# Both install the exact versions of constraints.txt (the figures the README shows were measured with them).
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: demo test lint bench clean

$(STAMP): pyproject.toml constraints.txt
	$(PYTHON) -m venv --clear $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet --constraint constraints.txt -e '.[test,bench,dask]'
	touch $(STAMP)

demo: $(STAMP)
	$(PY) -m ccopt.cli run --object paper-triangle --schedule paper --plant planar --seed 0 --out runs/demo --overwrite

test: $(STAMP)
	$(PY) -m ruff check .
	$(PY) -m pytest -q -n auto

lint: $(STAMP)
	$(PY) -m ruff check .

clean:
	rm -rf $(VENV) .pytest_cache .ruff_cache
