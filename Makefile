# bikerider developer tasks.  Every target creates the virtual environment it needs.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: setup demo test derive bench docs clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

## demo: run the whole method on the paper's bicycle and rider (the embedded default)
demo: $(STAMP)
	$(VENV)/bin/bikerider estimate

## test: the full test suite
test: $(STAMP)
	$(PY) -m pytest -q

## derive: regenerate generated/ from the SymPy derivations in derive/
derive: $(STAMP)
	$(PY) -m derive

## bench: speed and memory benchmarks against baselines measured in the same run
bench: $(STAMP)
	$(PY) bench/run.py

## docs: regenerate the documents that scripts produce
docs: $(STAMP)
	$(PY) docs/scripts/reproduction.py

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache
