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
POLICY ?= agents/policies/TurnInPlace-bc
EPISODES ?= 100

.PHONY: demo test lint typecheck pytest slow train-deps baselines compare speed serve latency clean

$(VENV)/bin/python:
	$(PYTHON) -m venv $(VENV)

$(VENV)/.runtime: pyproject.toml | $(VENV)/bin/python
	$(PIP) -e .
	touch $@

# The tests check the environments with stable-baselines3 too, and read back a short
# run's TensorBoard log, so they need the training extra (stable-baselines3,
# tensorboard, tqdm and rich, with the CPU torch pinned above). Both targets depend
# on pyproject.toml: a changed package layout (agents/ installs as graspenv_agents)
# reinstalls.
$(VENV)/.dev: pyproject.toml $(VENV)/.runtime
	$(PIP) $(TORCH) -e '.[dev,train,serve,ray]'
	touch $@

# The live table's browser test drives Debian's chromium (Playwright cannot download
# browsers here): installed as root where it is missing. Without it the test says it
# is skipped and why (and fails in CI, which must run it).
$(VENV)/.browser: | $(VENV)/bin/python
	@if command -v chromium >/dev/null 2>&1; then touch $@; \
	elif [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then \
		apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium \
		&& touch $@; \
	else echo "note: chromium is missing and this is not root: the browser test will be skipped"; fi

$(VENV)/.train: pyproject.toml $(VENV)/.runtime
	$(PIP) $(TORCH) -e '.[train]'
	touch $@

# The pipeline demo, then a scripted and a learned agent on the same five episodes
# (the agents need the training extra: stable-baselines3 and the CPU torch).
demo: $(VENV)/.train
	$(VENV)/bin/graspenv demo --out $(OUT)
	$(VENV)/bin/graspenv eval --agent scripted:pinch-and-turn --episodes 5 \
		--out $(OUT)/scripted --video $(OUT)/scripted/episode.mp4
	$(VENV)/bin/graspenv eval --agent $(POLICY) --episodes 5 \
		--out $(OUT)/learned --video $(OUT)/learned/episode.mp4

test: $(VENV)/.dev lint typecheck pytest

lint: $(VENV)/.dev
	$(VENV)/bin/ruff check graspenv tests agents
	$(VENV)/bin/ruff format --check graspenv tests agents

typecheck: $(VENV)/.dev
	$(VENV)/bin/mypy

pytest: $(VENV)/.dev $(VENV)/.browser
	$(PY) -m pytest -q -n 2 --dist loadfile

# Long runs live behind their own targets.
slow: $(VENV)/.dev
	$(PY) -m pytest -q -m slow

train-deps: $(VENV)/.train

# The learned baselines in the README (behaviour clones, about half a minute each:
# see README "Learned baselines").
baselines: $(VENV)/.train
	$(VENV)/bin/graspenv train --env graspenv/TurnInPlace-v0 --algo sac --seed 0
	$(VENV)/bin/graspenv train --env graspenv/SqueezeSlide-v0 --algo sac --seed 0
	$(VENV)/bin/graspenv train --env graspenv/SqueezeHold-v0 --algo sac --seed 0

# The speed table in the README: whole-run speeds, env steps/s beside panda-gym (in
# the dev extra), resets, frame cost against contacts, compile times (about 2 min).
speed: $(VENV)/.dev
	$(VENV)/bin/graspenv bench --speed --out runs/speed

# The strategy benchmark in the README.
compare: $(VENV)/.train
	$(VENV)/bin/graspenv compare --episodes $(EPISODES) --out runs/compare

# The live table: a page to touch at http://127.0.0.1:8000/ and TUIO on UDP 3333.
serve: $(VENV)/.dev
	$(VENV)/bin/graspenv serve --tuio 3333

# The live table's latency and frame time in the README.
latency: $(VENV)/.dev
	$(PY) -m graspenv.bench.live_latency

clean:
	rm -rf $(VENV) runs .pytest_cache .mypy_cache .ruff_cache
