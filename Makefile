PY ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: run test lint bench clean

$(BIN)/python:
	$(PY) -m venv $(VENV)
	$(BIN)/pip install -q --upgrade pip

$(VENV)/.installed: pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q -e .
	touch $@

$(VENV)/.installed-test: pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q -e '.[test]'
	touch $@ $(VENV)/.installed

# The main job: a reference cable-routing plan, compiled and run on the simulated cell.
RUN_PLAN ?= cells/cable_routing/plan_two_turns.yaml
run: $(VENV)/.installed
	$(BIN)/cellengine run $(RUN_PLAN) --out run

test: $(VENV)/.installed-test
	$(BIN)/python -m pytest

lint: $(VENV)/.installed-test
	$(BIN)/ruff check cellengine skills tests
	$(BIN)/ruff format --check cellengine skills tests
	$(BIN)/mypy

$(VENV)/.installed-bench: pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q -e '.[test,bench]'
	touch $@ $(VENV)/.installed $(VENV)/.installed-test

bench: $(VENV)/.installed-bench
	$(BIN)/python bench/validate_speed.py
	$(BIN)/python bench/bench_x3d.py
	$(BIN)/python bench/run_all.py

clean:
	rm -rf $(VENV) build *.egg-info
