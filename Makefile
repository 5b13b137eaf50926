# gripopt — build, test, run and benchmark. Needs only the Rust toolchain (cargo) and
# python3 (for the independent MCAP reader and the Python package, installed into .venv by
# `make venv` / `make python`).
CARGO   ?= cargo
PROBLEM ?= problems/bottle-1l.toml
OUT     ?= results/bottle-1l
BIN     := target/release/gripopt

.PHONY: all build test run bench clean venv python python-test

all: build

build:
	$(CARGO) build --release --locked

VENV    := .venv
PYTHON  ?= python3

# The independent checks in a local venv: PyPI mcap (reference reader),
# mcap-protobuf-support (protobuf decoding), foxglove-schemas-protobuf (the official
# Foxglove descriptors to compare with), jsonschema, pandas (docs/python.md), and mujoco
# (the exported MJCF, docs/export.md: 3.17.0 is one self-contained wheel per platform);
# for the Python package (docs/python.md): maturin (its build), pymoo, dask[distributed],
# matplotlib (the docs' plot) and pytest (its suite).
VENV_STAMP := $(VENV)/.installed-5
VENV_PACKAGES := mcap mcap-protobuf-support foxglove-schemas-protobuf jsonschema pandas mujoco==3.17.0 \
	maturin==1.16.0 pymoo==0.6.2 'dask[distributed]==2026.8.0' matplotlib==3.11.2 pytest==9.2.0
$(VENV_STAMP):
	$(PYTHON) -m venv $(VENV)
	$(VENV)/bin/pip install --quiet --disable-pip-version-check $(VENV_PACKAGES)
	touch $@

venv: $(VENV_STAMP)

# The Python package `gripopt` (docs/python.md) into .venv: maturin builds its native module
# (crates/gripopt-py, release profile; cargo rebuilds only what changed) and installs it
# editable over python/gripopt. `pip install .` does the same on any machine with cargo.
python: $(VENV_STAMP)
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --release --locked --quiet

# The same package for the tests, built with the dev profile (opt-level 1, the test
# profile's settings): it reuses the dependencies `cargo test $(WORKSPACE)` compiled (the same
# profile and features) instead of building them again (CI minutes); `make python` installs
# the release build again.
python-test: $(VENV_STAMP)
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --profile dev --locked --quiet

# The crates `make test` builds and checks: the library and binary, and the Python
# extension (crates/gripopt-py), in one cargo invocation each, so that cargo resolves one set
# of dependency features for both and compiles every dependency once: maturin's build of the
# extension (make python-test) then reuses what `cargo test` compiled. (diffsol-bench, a
# benchmark with diffsol's own dependencies, is built by `make bench` only.) PYO3_PYTHON: the
# venv's interpreter, the one maturin builds for.
WORKSPACE := --workspace --exclude gripopt-diffsol-bench
PYO3_ENV  := PYO3_PYTHON=$(abspath $(VENV))/bin/python

# The habits CI enforces: rustfmt (rustfmt.toml) and clippy without warnings, on the library,
# the binary, the tests and the Python extension.
.PHONY: lint
lint: $(VENV_STAMP)
	$(CARGO) fmt --all --check
	$(PYO3_ENV) $(CARGO) clippy $(WORKSPACE) --all-targets --locked -- -D warnings

# Correctness tests (unit, integration, property, and the extension crate's unit tests; the
# test profile is optimised, opt-level 1), then the independent reader's self-test (it must
# reject the scene and layout defects it checks for), then two lanes side by side (`-j2`,
# each lane's output printed whole when it ends; a failure in either fails `make test`):
# - test-readers: the independent reader over every MCAP file and shipped layout the tests
#   wrote, and MuJoCo on the exported models (docs/export.md);
# - test-python: the Python package's build (make python-test: dev profile, every
#   dependency already compiled by `cargo test`), its pytest suite against the gripopt
#   command (exit code 5, no test collected, fails too), and every block of docs/python.md
#   (tools/check_python_docs.py) with the pandas example on a run the tests wrote.
# The readers need only Python while maturin compiles, so the lanes share the 2 cores of CI
# (docs/benchmarks.md "Test suite time").
test: $(VENV_STAMP) lint
	rm -rf target/mcap-check
	$(PYO3_ENV) $(CARGO) test $(WORKSPACE) --locked
	$(VENV)/bin/python tools/test_check_mcap.py
	$(MAKE) --no-print-directory -j2 --output-sync=target test-readers test-python

# The lanes of `make test` (they read what its `cargo test` wrote: run `make test`).
.PHONY: test-readers test-python
test-readers: $(VENV_STAMP)
	$(VENV)/bin/python tools/check_mcap.py target/mcap-check
	$(VENV)/bin/python tools/check_mjcf.py $${CARGO_TARGET_DIR:-target}/debug/gripopt problems/bottle-1l.toml target/mjcf-check --nominal

test-python: python-test
	GRIPOPT=$${CARGO_TARGET_DIR:-target}/debug/gripopt $(VENV)/bin/python -m pytest python/tests -q -p no:cacheprovider; \
	  rc=$$?; if [ $$rc -eq 5 ]; then echo "pytest collected no tests: failing"; exit 1; fi; exit $$rc
	MPLBACKEND=Agg $(VENV)/bin/python tools/check_python_docs.py target/mcap-check/robust-outputs $${CARGO_TARGET_DIR:-target}/debug/gripopt

# The main job on the default problem: a short NSGA-II optimisation (pop 60, 25
# generations, 1 500 designs through all four stages, every design and grasp recorded to
# MCAP) writing results/bottle-1l/. An earlier run there is moved aside (nothing is
# deleted) while holding its folder's lock (`flock`, util-linux: the lock gripopt takes on a
# run folder), so a run still in progress is never moved: `make run` then stops (exit 1).
POP ?= 60
GENERATIONS ?= 25
SEED ?= 1
# Move an earlier run folder $(1) aside (never deleted), unless a running gripopt holds it
# (its .lock, taken with flock where there is one): the canned recipe of `run` and `kitchen`.
define move_aside
	@mkdir -p results
	@if [ -e $(1) ]; then \
	  keep=$(1).$$(date +%Y%m%d-%H%M%S); \
	  if command -v flock >/dev/null 2>&1; then flock -n -E 75 $(1) mv $(1) $$keep; rc=$$?; \
	  elif $(BIN) show $(1) --json 2>/dev/null | grep -q '"status": "running"'; then rc=75; \
	  else mv $(1) $$keep; rc=$$?; fi; \
	  if [ $$rc = 75 ]; then echo "$(1) is in use by a running gripopt (pid $$(cat $(1)/.lock 2>/dev/null || echo unknown)): not moved; wait for it to end, or give another output folder" >&2; exit 1; fi; \
	  if [ $$rc != 0 ]; then exit $$rc; fi; \
	  echo "$(1) held an earlier run: moved it to $$keep (nothing is deleted)"; \
	fi
endef

run: build
	$(call move_aside,$(OUT))
	$(BIN) optimise $(PROBLEM) --out $(OUT) --pop $(POP) --generations $(GENERATIONS) --seed $(SEED)
	$(BIN) evaluate $(PROBLEM) --json > $(OUT)/nominal.json
	@echo "Pareto front: $(OUT)/pareto.csv; plots: $(OUT)/pareto_matrix.svg, $(OUT)/hypervolume.svg"
	@echo "Recording (import the layout $(OUT)/foxglove-layout.json in Foxglove or Lichtblick, then open a shard with its front file, see docs/recording.md): $(OUT)/recording/gen-NNNNN.mcap and front-NNNNN.mcap"
	@id=$$(grep -v "^#" $(OUT)/pareto.csv | sed -n 2p | cut -d, -f1); if [ -n "$$id" ]; then echo "Replay a Pareto design: $(BIN) replay $(OUT) --design $$id"; fi

# The robust multi-object job (docs/robust.md): problems/kitchen.toml — the 1 l bottle full
# and half full, a can and a 0.5 l bottle, 8 scenarios each of the uncertain grasp, in the
# free scene — optimised (pop 40, 25 generations), its front certified on fresh scenarios at the
# end of the run (pareto.csv: the certified front; search_pareto.csv: the search's;
# certification.json), then the certified front audited out of sample (`gripopt verify`: 128
# fresh scenarios per object, verify_robust.csv). About 4–5 minutes on 2 cores.
KITCHEN_OUT ?= results/kitchen
KITCHEN_PROBLEM ?= problems/kitchen.toml
KITCHEN_POP ?= 40
KITCHEN_GENERATIONS ?= 25
.PHONY: kitchen
kitchen: build
	$(call move_aside,$(KITCHEN_OUT))
	$(BIN) optimise $(KITCHEN_PROBLEM) --out $(KITCHEN_OUT) --pop $(KITCHEN_POP) --generations $(KITCHEN_GENERATIONS) --seed $(SEED)
	$(BIN) verify $(KITCHEN_OUT)
	@echo "Certified robust front: $(KITCHEN_OUT)/pareto.csv (per object NAME.p_stay, NAME.p_stay_lower, …; certification.json); out of sample: $(KITCHEN_OUT)/verify_robust.csv; show it: $(BIN) show $(KITCHEN_OUT)"
	@id=$$(grep -v "^#" $(KITCHEN_OUT)/pareto.csv | sed -n 2p | cut -d, -f1); if [ -n "$$id" ]; then echo "Replay a scenario of a front design: $(BIN) replay $(KITCHEN_OUT) --design $$id --scenario can:0"; fi

# Speed figures (see docs/benchmarks.md). Not tests.
# diffsol's solvers are compared by a cargo bench of the package crates/diffsol-bench (so the
# gripopt binary never depends on diffsol), which writes its own
# results/bench/work_precision_diffsol.csv and .svg next to work_precision.csv.
bench: build bench-instructions
	$(BIN) bench static $(PROBLEM)
	$(BIN) bench work-precision $(PROBLEM)
	$(BIN) bench nsga
	$(BIN) bench replay $(PROBLEM)
	$(BIN) moo-test all --seeds 1-11
	$(CARGO) bench --locked -p gripopt-diffsol-bench --bench diffsol -- $(PROBLEM)

# Instruction counts (valgrind's callgrind: repeatable on a noisy machine) of the nominal
# centred grasp and free scene (the default solver, RADAU5, auto at 1e-7), the kitchen front
# design of issue 40 (32 robust scenarios) and a one-thread `optimise --pop 128 --generations
# 10`, then the accuracy rule's table (`gripopt bench accuracy`: 40 grasp designs and 960
# kitchen scenarios against RADAU5 at 1e-10; minutes the first time, its reference cached)
# (scripts/bench-instructions.sh; docs/benchmarks.md). valgrind is installed with apt-get
# when missing and this runs as root; otherwise it says how.
.PHONY: bench-instructions
bench-instructions: build
	@command -v valgrind > /dev/null || { \
		if [ "$$(id -u)" = 0 ] && command -v apt-get > /dev/null; then \
			apt-get install -y valgrind || { apt-get update && apt-get install -y valgrind; }; \
		else echo "valgrind is missing: install it (Debian/Ubuntu: sudo apt-get install valgrind)"; exit 2; fi; }
	scripts/bench-instructions.sh

clean:
	$(CARGO) clean

# The thesis's chapter-4 parameter studies (figs 4.1-4.18) with `gripopt sweep`, into
# results/studies/ (see scripts/studies.sh and docs/thesis-comparison.md). One study:
# `scripts/studies.sh fig4_16`. `make figures` also copies the cited plots to docs/figures/.
# `make thesis-checks`: the studies behind rows 8, 12-14, 22, 24 and 25, the figures those rows
# quote (printed by scripts/thesis_checks.py) and row 14's α map with the ψ rule, into docs/figures/.
.PHONY: studies figures thesis-checks
studies: build
	scripts/studies.sh

figures: studies
	scripts/figures.sh

thesis-checks: build $(VENV_STAMP)
	scripts/studies.sh fig4_5 fig4_8a fig4_8l fig4_8r fig4_13e fig4_16 fig4_16e fig4_17
	$(VENV)/bin/python scripts/thesis_checks.py --figures docs/figures
