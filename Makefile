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

# The main job on the default problem: evaluation of the nominal design and its grasp.
run: build
	@mkdir -p results
	$(BIN) evaluate $(PROBLEM)
	$(BIN) evaluate $(PROBLEM) --json > results/nominal.json
	$(BIN) simulate $(PROBLEM) --csv results/nominal_grasp.csv
	@echo "results written to results/nominal.json and results/nominal_grasp.csv"

# Speed figures (see docs/benchmarks.md). Not tests.
bench: build
	$(BIN) bench static $(PROBLEM)

clean:
	$(CARGO) clean
