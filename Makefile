# gripopt — build, test, run and benchmark. Needs only the Rust toolchain (cargo) and
# python3 (for the independent MCAP reader, installed into .venv by `make venv`).
CARGO   ?= cargo
PROBLEM ?= problems/bottle-1l.toml
OUT     ?= results/bottle-1l
BIN     := target/release/gripopt

.PHONY: all build test run bench clean

all: build

build:
	$(CARGO) build --release --locked

# Correctness tests (unit, integration, property). The test profile is optimised (opt-level 2).
test:
	$(CARGO) test --locked

# The main job on the default problem: a short NSGA-II optimisation (pop 100, 40
# generations, ~4 000 designs through all four stages) writing results/bottle-1l/.
POP ?= 100
GENERATIONS ?= 40
SEED ?= 1
run: build
	@mkdir -p results
	@if [ -e $(OUT)/checkpoint.json ]; then echo "$(OUT) holds an earlier run: moving it to $(OUT).previous"; rm -rf $(OUT).previous; mv $(OUT) $(OUT).previous; fi
	$(BIN) optimise $(PROBLEM) --out $(OUT) --pop $(POP) --generations $(GENERATIONS) --seed $(SEED)
	$(BIN) evaluate $(PROBLEM) --json > $(OUT)/nominal.json
	@echo "Pareto front: $(OUT)/pareto.csv; plots: $(OUT)/pareto_matrix.svg, $(OUT)/hypervolume.svg"

# Speed figures (see docs/benchmarks.md). Not tests.
bench: build
	$(BIN) bench static $(PROBLEM)
	$(BIN) bench work-precision $(PROBLEM)
	$(BIN) bench nsga
	$(BIN) moo-test all --seeds 1-11

clean:
	$(CARGO) clean
