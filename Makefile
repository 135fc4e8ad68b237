PY ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: run test fuzz browser lint bench clean

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

# the report's browser tests need Chromium: Debian's package, installed when none is on PATH
browser:
	bash .ci/browser

test: $(VENV)/.installed-test browser
	$(BIN)/python -m pytest

# nightly-style: the fuzz target (tests/fuzz/) with 500 random examples per input kind instead of
# CI's few fixed ones, about 40 minutes; FUZZ_EXAMPLES=N for another count
fuzz: $(VENV)/.installed-test
	CELLENGINE_FUZZ=long $(if $(FUZZ_EXAMPLES),CELLENGINE_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES)) $(BIN)/python -m pytest tests/fuzz

# report.html's scripts are checked with ESLint from npm, installed under .venv (git-ignored; the
# config is .ci/eslint.config.mjs); pinned so that a fresh clone lints as CI does
ESLINT_DIR := $(VENV)/eslint
ESLINT_PACKAGES := eslint@9.39.5 globals@16.5.0
REPORT_JS := $(wildcard cellengine/report/assets/*.js)

$(VENV)/.installed-eslint: Makefile | $(BIN)/python
	npm install --prefix $(ESLINT_DIR) --no-save --no-audit --no-fund --loglevel=error $(ESLINT_PACKAGES)
	touch $@

lint: $(VENV)/.installed-test $(VENV)/.installed-eslint
	$(BIN)/ruff check cellengine skills tests
	$(BIN)/ruff format --check cellengine skills tests
	$(BIN)/mypy
	for f in $(REPORT_JS); do node --check $$f || exit 1; done
	$(ESLINT_DIR)/node_modules/.bin/eslint --config .ci/eslint.config.mjs --max-warnings 0 $(REPORT_JS)

$(VENV)/.installed-bench: pyproject.toml | $(BIN)/python
	$(BIN)/pip install -q -e '.[test,bench]'
	touch $@ $(VENV)/.installed $(VENV)/.installed-test

bench: $(VENV)/.installed-bench
	$(BIN)/python bench/validate_speed.py
	$(BIN)/python bench/bench_validate.py --cells
	$(BIN)/python bench/bench_lab.py
	$(BIN)/python bench/bench_lab_bench.py
	$(BIN)/python bench/bench_lab_soak.py
	$(BIN)/python bench/bench_locate.py
	$(BIN)/python bench/bench_x3d.py
	$(BIN)/python bench/run_all.py

clean:
	rm -rf $(VENV) build *.egg-info
