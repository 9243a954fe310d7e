# The README's first two commands are `make demo` and `make test`; both set up everything
# on a fresh machine (virtual environment, Python packages, Icarus Verilog and yosys).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.rvsm-installed
OUT ?= out
# pytest-xdist workers: the machine has 2 cores.
JOBS ?= 2

.PHONY: setup demo test regress bench lint clean

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/install-system-deps.sh
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip
	$(BIN)/python -m pip install --quiet -e ".[dev]"
	scripts/install-system-deps.sh
	touch $(STAMP)

demo: setup
	$(BIN)/rvsm demo -o $(OUT)

test: setup
	$(BIN)/python -m pytest -n $(JOBS) -q

regress: setup
	$(BIN)/python -m pytest -n $(JOBS) -q -m "slow or not slow"

bench: setup
	$(BIN)/python scripts/benchmark.py

lint: setup
	$(BIN)/ruff check .

clean:
	rm -rf $(OUT) build sim_build .pytest_cache
