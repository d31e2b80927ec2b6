# symkin developer commands.  `make demo` and `make test` work on a fresh machine with
# python3 (>= 3.10) and a C compiler: they create .venv and install what they need.

PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.symkin-installed
BENCH_STAMP := $(VENV)/.symkin-bench-installed
MODELS := $(wildcard models/*.yaml)
PYTEST_WORKERS ?= 2

.PHONY: setup demo test generate check-generated bench clean

$(STAMP): pyproject.toml requirements/constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c requirements/constraints.txt -e '.[test]'
	touch $(STAMP)

## setup: create .venv and install symkin (editable) with its test tools
setup: $(STAMP)

## demo: derive every example model into generated/ and print what was derived
demo: setup
	$(BIN)/symkin derive $(MODELS) -o generated

## test: run the whole test suite
test: setup
	$(BIN)/python -m pytest -n $(PYTEST_WORKERS) -q

## generate: rewrite generated/ from the example models (the "update" switch of the golden tests)
generate: demo

$(BENCH_STAMP): $(STAMP)
	$(BIN)/python -m pip install --quiet -c requirements/constraints.txt -e '.[test,bench]'
	touch $(BENCH_STAMP)

## bench: run every benchmarks/bench_*.py (figures printed; speed is never asserted in tests);
## the SymForce column also needs a C++ compiler and the Eigen headers (apt-get install g++ libeigen3-dev)
bench: $(BENCH_STAMP)
	@for script in benchmarks/bench_*.py; do echo "== $$script"; $(BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) build dist *.egg-info .pytest_cache
