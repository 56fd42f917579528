# Two commands work on a fresh clone: `make demo` and `make test`. Both create .venv on first use.
PY ?= python3
VENV := .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.installed

DOCS_STAMP := $(VENV)/.docs-installed

.PHONY: demo test test-user-install test-all lint bench docs clean

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

# The documentation site: docs/_build/html/index.html. Strict (-W: any warning, a broken
# reference or a code block that raises, fails it) and offline; -E reads every page again, so
# every code block runs on every build; then the checks that read the built site (tests/docs).
# Environment animations are rendered once and cached in docs/_build/gallery-cache/.
$(DOCS_STAMP): $(STAMP) requirements/docs.txt
	$(BIN)/pip install --quiet -r requirements/docs.txt
	touch $(DOCS_STAMP)

docs: $(DOCS_STAMP)
	MUJOCO_GL=egl $(BIN)/python -m sphinx -b html -E -W --keep-going -n -q docs docs/_build/html
	PALAESTRA_DOCS_BUILT=1 $(BIN)/python -m pytest -q -p no:cacheprovider -m "slow or not slow" tests/docs

bench: $(STAMP)
	$(BIN)/python benchmarks/env_step.py

clean:
	rm -rf $(VENV) build src/*.egg-info docs/_build docs/api docs/envs
