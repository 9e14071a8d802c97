# workbench: `make demo` and `make test` each set up .venv on a fresh machine, then run.
# `make test-fast` is the quick tier while developing; CI runs `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: demo test test-fast lint format studies chaos-maps data benchmarks clean

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

# What CI runs: ruff, the whole suite (hard cases and exudyn included), the package's doctests
# and every code block of README.md (tests/test_readme.py).
test: lint
	$(PY) -m pytest -q --timeout=900 --doctest-modules tests workbench

# The fast tier while developing: no slow, hard-case or exudyn tests (doctests included).
test-fast: $(STAMP)
	$(PY) -m pytest -q --timeout=900 --doctest-modules -m "not slow and not hard and not verify" tests workbench

# Every study of the paper (archives and figures in $(OUT)/studies), then studies/REPORT.md.
studies: $(STAMP)
	$(VENV)/bin/workbench study all -o $(OUT)/studies

# Chaos indicators of the nine-bar over (omega, c) and (c, c_f) (docs/continuation.md states
# their cost): campaigns whose workers measure the strobe period, 0-1 K and largest exponent.
chaos-maps: $(STAMP)
	$(VENV)/bin/workbench chaos-map studies/chaos_maps/omega_clearance.toml --workers 2 -q \
		-o $(OUT)/chaos_maps/omega_clearance.nc --figure $(OUT)/chaos_maps/omega_clearance.png
	$(VENV)/bin/workbench chaos-map studies/chaos_maps/clearance_friction.toml --workers 2 -q \
		-o $(OUT)/chaos_maps/clearance_friction.nc --figure $(OUT)/chaos_maps/clearance_friction.png

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
