# Two commands do all the set-up on a fresh machine: `make demo` and `make test`.
# Each creates or refreshes .venv and installs what it needs.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
PIP    := $(PY) -m pip install --quiet --disable-pip-version-check
# torch 2.13.0 is a CPU build that installs in seconds here; an unpinned torch
# pulls a multi-gigabyte CUDA build.
TORCH  := torch==2.13.0
OUT    ?= runs/demo

.PHONY: demo test lint typecheck pytest slow train-deps clean

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.runtime: pyproject.toml | $(VENV)/bin/python
	$(PIP) -e .
	touch $@

# The tests check the environments with stable-baselines3 too, so they need the
# training extra (with the CPU torch pinned above).
$(VENV)/.dev: pyproject.toml $(VENV)/.runtime
	$(PIP) $(TORCH) -e '.[dev,train]'
	touch $@

$(VENV)/.train: pyproject.toml $(VENV)/.runtime
	$(PIP) $(TORCH) -e '.[train]'
	touch $@

demo: $(VENV)/.runtime
	$(VENV)/bin/graspenv demo --out $(OUT)

test: $(VENV)/.dev lint typecheck pytest

lint: $(VENV)/.dev
	$(VENV)/bin/ruff check graspenv tests agents
	$(VENV)/bin/ruff format --check graspenv tests agents

typecheck: $(VENV)/.dev
	$(VENV)/bin/mypy

pytest: $(VENV)/.dev
	$(PY) -m pytest -q -n 2 --dist loadfile

# Long runs live behind their own targets.
slow: $(VENV)/.dev
	$(PY) -m pytest -q -m slow

train-deps: $(VENV)/.train

clean:
	rm -rf $(VENV) runs .pytest_cache .mypy_cache .ruff_cache
