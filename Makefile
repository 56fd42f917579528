# Two commands work on a fresh clone: `make demo` and `make test`. Both create .venv on first use.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

.PHONY: demo test test-user-install test-all lint bench clean

$(STAMP): requirements/dev.txt requirements/dev-no-deps.txt pyproject.toml
	$(PY) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -r requirements/dev.txt
	$(BIN)/pip install --quiet --no-deps -r requirements/dev-no-deps.txt
	$(BIN)/pip install --quiet --no-deps -e .
	touch $(STAMP)

# The main job: train DQN on MountainCar-v0 with the tuned preset (~30 s), evaluate it, and
# write the learning curve and a GIF of the agent to runs/demo/ (replaced on each run).
demo: $(STAMP)
	rm -rf runs/demo
	$(BIN)/palaestra train dqn MountainCar-v0 --seed 0 --out runs/demo
	$(BIN)/palaestra record runs/demo --out runs/demo/mountain_car.gif

# The default suite, then the user-install check: a fresh venv from a clone of the committed
# tree with only the README's own-environment install (no gymnasium/SB3/dev tools), smoke-run.
test: $(STAMP)
	$(BIN)/python -m pytest -q -p no:cacheprovider
	bash tests/userinstall/check.sh

test-user-install:
	bash tests/userinstall/check.sh

test-all: $(STAMP)
	$(BIN)/python -m pytest -q -p no:cacheprovider -m "slow or not slow"

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks
	$(BIN)/ruff format --check src tests benchmarks
	$(BIN)/mypy

bench: $(STAMP)
	$(BIN)/python benchmarks/env_step.py

clean:
	rm -rf $(VENV) build src/*.egg-info
