# breakwater: `make run` runs the default Goda case, `make test` runs the test suite.
# Both create the virtual environment (.venv) and install breakwater into it when missing.

PYTHON ?= $(shell command -v python3.12 2>/dev/null || ls $(HOME)/.pyenv/versions/3.12*/bin/python3.12 2>/dev/null | tail -n 1)
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed
NP ?= 2
CASE ?=
ARGS ?=

.PHONY: install run test test-serial test-mpi lint clean

$(STAMP): pyproject.toml
	@test -n "$(PYTHON)" || { echo "python3.12 not found (set PYTHON=/path/to/python3.12)"; exit 1; }
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e '.[fenicsx,viz,test,dev]'
	touch $(STAMP)

install: $(STAMP)

run: $(STAMP)
	$(BIN)/python -m breakwater run $(CASE) $(ARGS)

test: test-serial test-mpi

test-serial: $(STAMP)
	$(BIN)/python -m pytest -q tests

test-mpi: $(STAMP)
	timeout 1800 $(BIN)/mpiexec -n $(NP) $(BIN)/python -m pytest -q -m "not serial" tests

lint: $(STAMP)
	$(BIN)/ruff check breakwater forms meshes tests notebooks/make_notebooks.py
	$(BIN)/mypy breakwater forms meshes

clean:
	rm -rf $(VENV) results
