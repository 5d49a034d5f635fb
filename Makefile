# `make bench` and `make test` set up a local virtual environment themselves.
PYTHON ?= python3
VENV := .venv
PY := $(VENV)/bin/python
STAMP := $(VENV)/.installed
OUT ?= bench-out
ARGS ?=

# Small matrices: single-threaded BLAS is faster than contended threads (see harness/cli.py).
export OPENBLAS_NUM_THREADS ?= 1
export OMP_NUM_THREADS ?= 1
export MKL_NUM_THREADS ?= 1

.PHONY: install test test-slow check-figures bench lint clean install-check lock-check

install: $(STAMP)

# uv, pinned, from PyPI like every other package (its own stamp: a new version is installed)
UV_VERSION := 0.13.9
UV := $(VENV)/bin/uv
UV_STAMP := $(VENV)/.uv-$(UV_VERSION)

$(UV_STAMP):
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet uv==$(UV_VERSION)
	touch $(UV_STAMP)

# exactly the versions in uv.lock (a package it lacks is removed; pip and uv stay), the project
# editable with its dev and sysid extras (mujoco.sysid: study sysid_peer, identify --refine
# rollout); refused if uv.lock does not match pyproject.toml (make lock-check). uv installs
# the wheels in parallel: about 25 s here against about 105 s for pip; `pip install .` works
# as well, with pyproject.toml's ranges (make install-check)
$(STAMP): pyproject.toml uv.lock $(UV_STAMP)
	UV_PROJECT_ENVIRONMENT=$(VENV) $(UV) sync --quiet --locked --extra dev --extra sysid
	touch $(STAMP)

# fails when uv.lock no longer matches pyproject.toml (also in CI); `.venv/bin/uv lock`
# updates it, keeping every locked version pyproject.toml still allows
lock-check: $(UV_STAMP)
	$(UV) lock --check

# the fast cross-checks (a few minutes); the slow ones (whole benches, sweeps, studies, arms
# planned end to end) are named, not skipped silently: `make test-slow` runs them, CI runs both
test: $(STAMP)
	MUJOCO_GL=egl TORQUEBENCH_HYPOTHESIS=full $(PY) -m pytest -q -n 2 -m "not slow"
	@echo "make test: the tests marked slow were left out (-m 'not slow'; '.venv/bin/pytest --collect-only -q -m slow' lists them); 'make test-slow' runs them (CI runs both)"

test-slow: $(STAMP)
	MUJOCO_GL=egl $(PY) -m pytest -q -n 2 -m slow

# the figures the README and docs state, read from their text with their commands, each command
# run and its figure compared to the stated digits (tests/test_figures.py: 27 plans, 4-5 min
# serially; slow, so make test-slow runs it with the rest)
check-figures: $(STAMP)
	MUJOCO_GL=egl $(PY) -m pytest -q tests/test_figures.py

bench: $(STAMP)
	MUJOCO_GL=egl $(VENV)/bin/torquebench bench --out $(OUT) $(ARGS)

# the wheel in a fresh venv, run from outside the checkout (also in CI)
install-check:
	bash .ci/install-check

lint: $(STAMP)
	$(VENV)/bin/ruff check harness identification planning tests

clean:
	rm -rf $(VENV) $(OUT)
