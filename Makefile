# Every target sets up .venv on its own: `make demo` and `make test` work on a fresh clone
# (with the h1 extra, so the Unitree H1 tests run in CI).
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed-stamp
# The versions the suite last passed with (.ci/constraints.txt); `make setup UNPINNED=1` takes the newest instead.
CONSTRAINTS := $(if $(UNPINNED),,-c .ci/constraints.txt)

.PHONY: setup demo test bench clean

$(STAMP): pyproject.toml .ci/constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet $(CONSTRAINTS) -e '.[test,bench,h1]'
	touch $(STAMP)

setup: $(STAMP)

## The main job: closed-loop walking run (prints metrics, writes plots under runs/).
demo: $(STAMP)
	$(VENV)/bin/wbmpc demo --out runs/demo

## The test suite (what CI runs through .ci/run): the layer contracts, ruff, then pytest.
test: $(STAMP)
	$(VENV)/bin/lint-imports
	$(VENV)/bin/ruff check .
	$(PY) -m pytest -q

bench: $(STAMP)
	$(VENV)/bin/wbmpc bench sequencer

clean:
	rm -rf $(VENV) runs build *.egg-info
