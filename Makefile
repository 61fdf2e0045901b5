# bikerider developer tasks.  Every target creates the virtual environment it needs.
PYTHON ?= python3
VENV ?= .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed

.PHONY: setup demo serve test derive bench docs clean

# The editable install of this layout (generated/ mapped into the package) goes through a meta path
# finder, after which setuptools always prints an informational "Editable installation" notice about
# folders named like the package in the working directory (the project has none): silenced by name.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	PYTHONWARNINGS="ignore:Editable installation:UserWarning" $(PY) -m pip install --quiet -e '.[test]'
	touch $(STAMP)

setup: $(STAMP)

## demo: run the whole method on the paper's bicycle and rider (the embedded default)
demo: $(STAMP)
	$(VENV)/bin/bikerider estimate
	@echo
	@echo "bikerider is installed in $(VENV): run $(VENV)/bin/bikerider --help, or . $(VENV)/bin/activate to put it on the PATH"

## serve: the local web page at http://127.0.0.1:8050/ (bikerider serve; docs/app.md); Ctrl+C stops it
serve: $(STAMP)
	$(VENV)/bin/bikerider serve

## test: lint and format check (ruff, pyproject.toml's settings), then the full test suite
test: $(STAMP)
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .
	$(PY) -m pytest -q

## derive: regenerate generated/ from the SymPy derivations in derive/
derive: $(STAMP)
	$(PY) -m derive

## bench: speed and memory benchmarks against baselines measured in the same run
## (BicycleParameters goes into its own venv, bench/.venv-baseline; without it the bench says so and goes on)
BASELINE_VENV := bench/.venv-baseline
bench: $(STAMP)
	@test -f $(BASELINE_VENV)/.installed || { $(PYTHON) -m venv $(BASELINE_VENV) \
	  && $(BASELINE_VENV)/bin/python -m pip install --quiet 'bicycleparameters==1.5.2' \
	  && touch $(BASELINE_VENV)/.installed; } \
	  || echo "bench: could not install BicycleParameters into $(BASELINE_VENV); running without that baseline"
	$(PY) bench/run.py

## docs: regenerate the documents that scripts produce (the gap validation takes a few minutes)
docs: $(STAMP)
	$(PY) docs/scripts/reproduction.py
	$(PY) docs/scripts/sensitivity_report.py
	$(PY) docs/scripts/gap_real_data.py
	$(PY) docs/scripts/gallery.py
	$(PY) docs/scripts/measurement_figure.py
	$(PY) docs/scripts/gap_validation.py
	$(PY) docs/scripts/gap_sbw_checks.py
	$(PY) docs/scripts/gap_sbw_next.py

clean:
	rm -rf $(VENV) build *.egg-info src/*.egg-info .pytest_cache
