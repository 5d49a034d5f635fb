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

.PHONY: install test bench lint clean install-check

install: $(STAMP)

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -e '.[dev]'
	touch $(STAMP)

test: $(STAMP)
	MUJOCO_GL=egl TORQUEBENCH_HYPOTHESIS=full $(PY) -m pytest -q -n 2

bench: $(STAMP)
	MUJOCO_GL=egl $(VENV)/bin/torquebench bench --out $(OUT) $(ARGS)

# the wheel in a fresh venv, run from outside the checkout (also in CI)
install-check:
	bash .ci/install-check

lint: $(STAMP)
	$(VENV)/bin/ruff check harness identification planning tests

clean:
	rm -rf $(VENV) $(OUT)
