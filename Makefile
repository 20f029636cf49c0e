# Entry points: make check (install + validate the bundled spec + run the demo
# scenarios), make test (install + every test). Both create .venv on their own.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed

.PHONY: check test deep generate bench install deps-system deps-node deps-spin lint lint-run clean

$(STAMP): pyproject.toml
	@test -x $(BIN)/python || $(PYTHON) -m venv $(VENV)
	@echo "installing motionchart and its dependencies into $(VENV) (log: $(VENV)/install.log)"
	@$(BIN)/python -m pip install --disable-pip-version-check -e ".[test]" >$(VENV)/install.log 2>&1 \
	  || { tail -n 30 $(VENV)/install.log; echo "pip install failed; full log in $(VENV)/install.log"; exit 1; }
	@$(BIN)/python -c "import statecharts, checker, motionchart_spec"
	@touch $(STAMP)

install: $(STAMP) deps-system deps-node deps-spin

# Graphviz's `dot` renders diagrams: Debian's package when we are root, else the
# graphviz-pure wheel (no root needed). Never fatal: text artefacts need no binary.
deps-system:
	@if ! command -v dot >/dev/null 2>&1 && ! test -x $(BIN)/graphviz-pure; then \
	  if [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing graphviz (apt-get)"; \
	    (apt-get update -qq >/dev/null 2>&1; DEBIAN_FRONTEND=noninteractive apt-get install -y -qq graphviz >/dev/null 2>&1) \
	      || $(BIN)/python -m pip install --quiet graphviz-pure 2>&1 | grep -v "^WARNING: Location" || true; \
	  else \
	    $(BIN)/python -m pip install --quiet graphviz-pure 2>&1 | grep -v "^WARNING: Location" || true; \
	  fi; \
	fi

# Node.js runs the example implementation of examples/adapters/ in the conformance tests:
# Debian's package when we are root; without it those tests are skipped with the reason.
deps-node:
	@if ! command -v node >/dev/null 2>&1 && ! command -v nodejs >/dev/null 2>&1; then \
	  if [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing nodejs (apt-get)"; \
	    (apt-get update -qq >/dev/null 2>&1; DEBIAN_FRONTEND=noninteractive apt-get install -y -qq nodejs >/dev/null 2>&1) || true; \
	  fi; \
	fi

# SPIN and a C compiler run `motionchart check --engine spin`: Debian's packages when we
# are root. Never fatal: without them the SPIN engine reports that it is missing and its
# tests are skipped with the reason.
deps-spin:
	@if ! command -v spin >/dev/null 2>&1 || ! { command -v cc >/dev/null 2>&1 || command -v gcc >/dev/null 2>&1; }; then \
	  if [ "$$(id -u)" = "0" ] && command -v apt-get >/dev/null 2>&1; then \
	    echo "installing spin and gcc (apt-get)"; \
	    (apt-get update -qq >/dev/null 2>&1; DEBIAN_FRONTEND=noninteractive apt-get install -y -qq spin gcc >/dev/null 2>&1) || true; \
	  fi; \
	fi

check: install
	@$(BIN)/motionchart validate
	@$(BIN)/motionchart simulate --summary scenarios $(filter-out %.check.yaml,$(wildcard examples/programs/*.yaml))
	@$(BIN)/motionchart check
	@$(BIN)/motionchart check --system aoi

test: install
	@$(BIN)/python -m pytest

# Diagrams, reference docs and SCXML in generated/, rebuilt from the spec.
generate: install
	@$(BIN)/motionchart generate
	@$(BIN)/python tools/write_sources_doc.py

# Start-up times of the CLI (--help, one diagram) beside the interpreter's own, then checker
# speed against a hand-written reference BFS, then the mutation score of the vector suite
# (prints figures beside their targets; not a test, so a figure below its target does not
# stop the run).
bench: install
	@$(BIN)/python benchmarks/startup.py
	@$(BIN)/python benchmarks/bench.py
	@$(BIN)/python benchmarks/spin_bench.py
	@$(BIN)/motionchart vectors -q -o .bench/vectors >/dev/null
	@$(BIN)/motionchart mutate --score --quiet --min-score 0 --vectors .bench/vectors

# What make test leaves out: every parametrisation of the long explorations (make test
# runs a fast sample of them), longer property-based runs, the larger checks.
deep: install
	@$(BIN)/python -m pytest -m deep
	@$(BIN)/python tests/fuzzing.py --specs 10000 --scenarios 10000 --systems 1000 --properties 1000
	@HYPOTHESIS_PROFILE=deep $(BIN)/python -m pytest tests/test_laws.py
	@$(BIN)/motionchart check --system cip
	@$(BIN)/motionchart check --system aoi --max-changes 3
	@$(BIN)/motionchart vectors -o .deep/vectors
	@$(BIN)/motionchart conform --adapter "$(BIN)/motionchart adapter" --vectors .deep/vectors -q -j 2
	@if command -v node >/dev/null 2>&1; then $(BIN)/motionchart conform --adapter "node examples/adapters/node/noncip.js" \
	  --vectors .deep/vectors -q --known-failures examples/adapters/node/known-failures.txt; \
	  else echo "node not found: the JavaScript example implementation is not run"; fi

# ruff (rules in pyproject.toml), mypy --strict (statecharts/, checker/, conformance/, motionchart/)
# and the project's own rules (tools/lint_rules.py: a reason for every `type: ignore` and
# `noqa`, no private names used across modules); fails on any finding. lint-run is the
# checks alone (tests/test_lint.py runs it on a copy of the sources with planted defects).
lint: install
	@$(MAKE) --no-print-directory lint-run

lint-run:
	@status=0; \
	$(BIN)/python -m ruff check --no-cache . || status=1; \
	$(BIN)/python -m mypy || status=1; \
	$(BIN)/python tools/lint_rules.py . || status=1; \
	exit $$status

clean:
	rm -rf $(VENV) .pytest_cache .hypothesis .mypy_cache .ruff_cache build *.egg-info .bench .deep
