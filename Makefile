# workbench: `make demo` and `make test` each set up .venv on a fresh machine, then run.
# `make test-fast` is the quick tier while developing; CI runs `make test`.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
# .venv holds the runtime package (RUNTIME: all `make demo` needs), or the package with its
# test, verify and docs extras (STAMP: every other target). Either order works: the extras go on
# top of the runtime, and an install with them counts as the runtime's too.
RUNTIME := $(VENV)/.installed-runtime
STAMP := $(VENV)/.installed
OUT ?= out

.PHONY: demo test test-generic test-fast lint format studies chaos-maps data notebooks docs benchmarks clean

$(PY):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip

$(RUNTIME): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e .
	touch $(RUNTIME)

$(STAMP): pyproject.toml | $(PY)
	$(PY) -m pip install --quiet -e ".[test,verify,docs]"
	touch $(STAMP) $(RUNTIME)

# The default scene run long enough and recorded finely enough for its figures (studies/demo.toml:
# 50 points in its Poincare sections, impacts resolved in its phase portraits).
demo: $(RUNTIME)
	$(VENV)/bin/workbench run studies/demo.toml -o $(OUT)/ninebar.nc --figures $(OUT)/figures --overwrite
	@echo "demo: netCDF run in $(OUT)/ninebar.nc, figures in $(OUT)/figures/"

# ruff, and numpydoc's validation of the public API's docstrings (docs/docstrings.py; the checks
# in pyproject.toml's [tool.numpydoc_validation]).
lint: $(STAMP)
	$(VENV)/bin/ruff check workbench tests benchmarks studies docs/hooks.py docs/docstrings.py
	$(VENV)/bin/ruff format --check workbench tests benchmarks studies docs/hooks.py docs/docstrings.py
	$(PY) docs/docstrings.py

format: $(STAMP)
	$(VENV)/bin/ruff format workbench tests benchmarks studies docs/hooks.py
	$(VENV)/bin/ruff check --fix workbench tests benchmarks studies docs/hooks.py

# What CI runs: ruff, the whole suite (hard cases and exudyn included), the package's doctests,
# every python block of README.md and of the docs' pages (tests/docs/test_readme.py, test_docs.py),
# the docs site built with warnings as errors, and the notebooks checked against the code; then
# the chaotic and statistical tests once more as another processor would (test-generic).
# The suite's files are shared among TEST_WORKERS processes (pytest-xdist; one file stays in
# one process, so a module's fixtures are computed once): the suite's CPU time is about 26 min,
# and CI has 2 cores.
TEST_WORKERS ?= 2
test: lint
	$(PY) -m pytest -q --timeout=900 -n $(TEST_WORKERS) --dist loadfile --durations=15 --doctest-modules tests workbench
	$(MAKE) --no-print-directory test-generic

# The tests that assert chaotic or statistical numbers (marker `chaotic`) once more as another
# processor would run them: kernels compiled for numba's generic CPU (in a cache folder of
# their own), OpenBLAS's Nehalem kernels and, on x86-64, glibc's math without its AVX2 and FMA
# variants. A chaotic run rounded differently follows another trajectory within a few periods,
# so these tests assert values within their errors, never digits; this tier keeps them honest.
GENERIC_CPU := NUMBA_CPU_NAME=generic WORKBENCH_CACHE_DIR=$(CURDIR)/.cache/generic-cpu
ifeq ($(shell uname -m),x86_64)
GENERIC_CPU += OPENBLAS_CORETYPE=Nehalem GLIBC_TUNABLES=glibc.cpu.hwcaps=-AVX2,-FMA
endif
test-generic: $(STAMP)
	$(GENERIC_CPU) $(PY) -m pytest -q --timeout=900 -n $(TEST_WORKERS) --dist loadfile -m chaotic tests

# The fast tier while developing: no slow, hard-case or exudyn tests (doctests included).
test-fast: $(STAMP)
	$(PY) -m pytest -q --timeout=900 --doctest-modules -m "not slow and not hard and not verify" tests workbench

# Every study of the paper (archives and figures in $(OUT)/studies), then studies/REPORT.md,
# and the key figures the docs site shows beside the report (docs/studies/figures/).
studies: $(STAMP)
	$(VENV)/bin/workbench study all -o $(OUT)/studies
	$(PY) docs/hooks.py $(OUT)/studies

# Chaos indicators of the nine-bar over (omega, c) and (c, c_f): campaigns whose workers measure
# the strobe period, 0-1 K and largest exponent (what their corner points cost: `python
# benchmarks/continuation.py --parts chaos_maps`, recorded in benchmarks/RESULTS.md). Each map
# runs under GNU time (its CPU, with the load before and after) and its indicators go to
# data/<map>_map.nc (docs/continuation.md quotes them; tests/records/test_data.py checks the quotes),
# its figure to docs/figures/chaos-map-<map>.png (shown on the site). Then the end of the
# periodic motion per clearance, in steps of 0.01 pi up and down (data/periodic_end.nc), drawn
# over the (omega, c) map's figure.
MAPS := omega_clearance clearance_friction
chaos-maps: $(STAMP)
	mkdir -p $(OUT)/chaos_maps
	for m in $(MAPS); do \
		uptime > $(OUT)/chaos_maps/$$m.log && \
		/usr/bin/time -v $(VENV)/bin/workbench chaos-map studies/chaos_maps/$$m.toml --workers 2 \
			-q -o $(OUT)/chaos_maps/$$m.nc --figure $(OUT)/chaos_maps/$$m.png \
			>> $(OUT)/chaos_maps/$$m.log 2>&1 && \
		uptime >> $(OUT)/chaos_maps/$$m.log && \
		$(PY) data/regenerate.py --chaos-map $(OUT)/chaos_maps/$$m.nc $(OUT)/chaos_maps/$$m.log && \
		cp $(OUT)/chaos_maps/$$m.png docs/figures/chaos-map-$$m.png || exit 1; \
	done
	$(PY) data/regenerate.py --periodic-end
	$(PY) data/regenerate.py --periodic-end-hunt-crossley
	$(PY) data/regenerate.py --map-figure

# The small archives the notebooks open (tests/records/test_data.py fails when they are stale), and the
# notebooks executed in place on them (committed with their outputs: the site shows them).
data: $(STAMP)
	$(PY) data/regenerate.py

notebooks: $(STAMP)
	$(PY) -m nbconvert --to notebook --execute --inplace notebooks/*.ipynb

# The documentation site, into site/ (every warning an error).
docs: $(STAMP)
	$(VENV)/bin/mkdocs build --strict -d site

benchmarks: $(STAMP)
	$(PY) benchmarks/solver_reference.py
	$(PY) benchmarks/ninebar_speed.py
	$(PY) benchmarks/work_precision.py
	$(PY) benchmarks/campaign.py
	$(PY) benchmarks/lle.py

clean:
	rm -rf $(VENV) $(OUT) site .cache .pytest_cache .ruff_cache
