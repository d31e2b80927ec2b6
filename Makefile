# symkin developer commands.  `make demo` and `make test` work on a fresh machine with
# python3 (>= 3.10) and a C compiler: they create .venv and install what they need.

PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.symkin-installed
# Benchmarks get a venv of their own: SymForce (a bench-only competitor) ships its own fork of
# symengine's wrapper into the symengine package, which changes the order of CSE output, so a
# venv holding it would no longer regenerate generated/ byte for byte.
BENCH_VENV ?= .venv-bench
BENCH_BIN := $(BENCH_VENV)/bin
BENCH_STAMP := $(BENCH_VENV)/.symkin-bench-installed
MODELS := $(wildcard models/*.yaml)
PYTEST_WORKERS ?= 2

.PHONY: setup demo test generate bench clean screenshots

$(STAMP): pyproject.toml requirements/constraints.txt
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -c requirements/constraints.txt -e '.[test]'
	touch $(STAMP)

## setup: create .venv and install symkin (editable) with its test tools
setup: $(STAMP)

## demo: derive every example model into generated/ and print what was derived;
## draw seed Fig. 8.19 (2-DoF workspaces) and 1/kappa maps (planar arm, DELTA) into out/figures/, and the
## seed's haptic scenario (Figs. 8.21, 8.22: torques, TCP forces, CSV) into out/figures/seed-haptic-scenario/, and the
## DELTA's haptic wall and gravity compensation (1 kHz loop, felt forces) and its datasheet (symkin rate) into
## out/figures/delta-*/
demo: setup
	$(BIN)/symkin derive $(MODELS) -o generated
	$(BIN)/symkin workspace generated/planar_2r --design l1=0.1,l2=0.1 --design l1=0.2,l2=0.2 --unit cm \
	    --title "Seed Fig. 8.19: 2-DoF arm, 0 <= theta1, theta2 <= 90 deg" \
	    -o out/figures/fig-8-19-workspace.png --map out/figures/planar_2r-inverse-condition.png
	$(BIN)/symkin workspace generated/delta --unit mm -o out/figures/delta-workspace.png --map out/figures/delta-inverse-condition.png
	$(BIN)/symkin simulate generated/planar_2r --scenario sine --design l1=0.1,l2=0.1 --design l1=0.2,l2=0.2 -o out/figures/seed-haptic-scenario
	$(BIN)/symkin simulate generated/delta --scenario haptic-wall -o out/figures/delta-haptic-wall
	$(BIN)/symkin simulate generated/delta --scenario gravity-compensation -o out/figures/delta-gravity-compensation
	$(BIN)/symkin rate generated/delta -o out/figures/delta-datasheet

# The numerics-sensitive tests run a second time on foreign arithmetic (tests/conftest.py): numpy's
# wide SIMD loops off, generated C with FMA contraction.  x86-64 feature names; elsewhere only the C flags.
FOREIGN_SIMD := $(if $(filter x86_64,$(shell uname -m)),NPY_DISABLE_CPU_FEATURES="X86_V3 X86_V4 AVX512_ICL AVX512_SPR")
FOREIGN_ARITHMETIC := SYMKIN_TEST_ARITHMETIC=foreign $(FOREIGN_SIMD) SYMKIN_CFLAGS="-O2 -march=native -ffp-contract=fast"

# One BLAS thread per test worker: the workers already take every core, and on symkin's small matrices OpenBLAS's
# threads cost more than they win (tests/identification ran in 78 s with them, 48 s without, on 2 cores).
ONE_BLAS_THREAD := OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1

# Bytecode under the venv, not beside the sources (tests/conftest.py): every test worker and every command the suite
# runs (a few hundred) would otherwise compile symkin and pytest would rewrite the tests' asserts again in each.
BYTECODE := env -u PYTHONDONTWRITEBYTECODE PYTHONPYCACHEPREFIX=$(abspath $(VENV))/pycache

# The two passes share the sampled states and sympy references of tests/backends/test_backends_agree.py
# (tests/reference_store.py): a folder made for one run, removed after it.
## test: run the whole test suite, then its numerics-sensitive part again on foreign arithmetic
test: setup
	store=$$(mktemp -d) && trap 'rm -rf "$$store"' EXIT && \
	$(ONE_BLAS_THREAD) $(BYTECODE) SYMKIN_TEST_REFERENCES=$$store \
	    $(BIN)/python -m pytest -n $(PYTEST_WORKERS) --dist loadgroup -q --durations=25 && \
	$(ONE_BLAS_THREAD) $(BYTECODE) SYMKIN_TEST_REFERENCES=$$store $(FOREIGN_ARITHMETIC) \
	    $(BIN)/python -m pytest -n $(PYTEST_WORKERS) --dist loadgroup -q -m numerics

## generate: rewrite generated/ from the example models (the "update" switch of the golden tests)
generate: demo

$(BENCH_STAMP): pyproject.toml requirements/constraints.txt
	$(PYTHON) -m venv $(BENCH_VENV)
	$(BENCH_BIN)/python -m pip install --quiet --upgrade pip
	$(BENCH_BIN)/python -m pip install --quiet -c requirements/constraints.txt -e '.[test,bench]'
	touch $(BENCH_STAMP)

## bench: run every benchmarks/bench_*.py in .venv-bench (figures printed; speed is never asserted
## in tests); the SymForce column also needs a C++ compiler and the Eigen headers (apt-get install g++ libeigen3-dev)
bench: $(BENCH_STAMP)
	@for script in benchmarks/bench_*.py; do echo "== $$script"; $(BENCH_BIN)/python $$script || exit 1; done

clean:
	rm -rf $(VENV) $(BENCH_VENV) build dist *.egg-info .pytest_cache

## screenshots: the pictures of docs/viewer.md, taken in headless Chromium (Debian's chromium)
screenshots: setup
	$(BIN)/python tests/browser.py docs/images generated
