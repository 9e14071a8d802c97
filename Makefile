# workbench: `make demo` and `make test` each set up .venv on a fresh machine, then run.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: demo test lint format studies data benchmarks clean

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e ".[test,verify]"
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/workbench run studies/ninebar.toml -o $(OUT)/ninebar.nc --figures $(OUT)/figures
	@echo "demo: netCDF run in $(OUT)/ninebar.nc, figures in $(OUT)/figures/"

lint: $(STAMP)
	$(VENV)/bin/ruff check workbench tests benchmarks studies
	$(VENV)/bin/ruff format --check workbench tests benchmarks studies

format: $(STAMP)
	$(VENV)/bin/ruff format workbench tests benchmarks studies
	$(VENV)/bin/ruff check --fix workbench tests benchmarks studies

test: lint
	$(PY) -m pytest -q --timeout=900

# Every study of the paper (archives and figures in $(OUT)/studies), then studies/REPORT.md.
studies: $(STAMP)
	$(VENV)/bin/workbench study all -o $(OUT)/studies

# The small archives the notebooks open.
data: $(STAMP)
	$(PY) data/regenerate.py

benchmarks: $(STAMP)
	$(PY) benchmarks/solver_reference.py
	$(PY) benchmarks/ninebar_speed.py
	$(PY) benchmarks/work_precision.py
	$(PY) benchmarks/campaign.py
	$(PY) benchmarks/lle.py

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .ruff_cache
