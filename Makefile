# pound: the two commands of the README, plus helpers.
#   make studies   regenerate every table and figure in results/
#   make test      run the whole test suite
#   make robustness  the long robustness sweep over every record (results/robustness)
#   make yielding-strong  the yielding study of a stronger pair (results/yielding-strong)
#   make opensees  the cross-checks against OpenSees (installs OpenSeesPy in target/; not in CI)
#   make bench-table  the README's speed table from BENCH_RUNS (6) criterion runs (not in CI)
#   make doc       the API documentation, warnings as errors (CI runs it after make clippy)
# Nothing else is needed on a fresh machine than a Rust toolchain (cargo): plots use a font
# committed in data/fonts, so no system font or fontconfig package is required.

CARGO ?= cargo
JOBS ?= $(shell nproc 2>/dev/null || echo 2)

.PHONY: all build test studies robustness yielding-strong opensees bench bench-table fmt clippy doc clean

all: build

build:
	$(CARGO) build --release --workspace

test:
	$(CARGO) test --release --workspace

studies: build
	./target/release/pound studies run --all --fresh --out results

# The long robustness sweep: 60 records x 4 gaps x 3 c_r x 4 solvers. Not in CI.
robustness: build
	./target/release/pound studies run robustness --fresh --out results

# The yielding study with the strength at the median elastic demand at 0.40 g instead of
# 0.15 g (studies/yielding-strong.toml): the pair pounds before it yields. Not in CI.
yielding-strong: build
	./target/release/pound studies run yielding-strong --fresh --out results

# The cross-checks against OpenSees (docs/cli.md): OpenSeesPy (and pandas, for the README's
# Python example) in a virtual environment under target/ (OpenSees' Linux library needs
# Debian's libblas3 and liblapack3, installed if missing), then the three opt-in tests that
# run the exported scripts and the docs test that runs the README's example. Needs the
# network; not in CI.
OPENSEES_VERSION ?= 3.7.1.2
OPENSEES_VENV := target/opensees-venv
opensees: build
	@if command -v dpkg >/dev/null && ! dpkg -s libblas3 liblapack3 >/dev/null 2>&1; then \
		$(if $(filter 0,$(shell id -u)),,sudo) sh -c "apt-get update -qq && apt-get install -y -qq libblas3 liblapack3"; fi
	test -x $(OPENSEES_VENV)/bin/python3 || python3 -m venv $(OPENSEES_VENV)
	$(OPENSEES_VENV)/bin/pip install -q openseespy==$(OPENSEES_VERSION) pandas
	PATH="$(abspath $(OPENSEES_VENV))/bin:$$PATH" $(CARGO) test --release -p studies \
		--test export --test wall_cli --test yield_opensees -- --ignored
	PATH="$(abspath $(OPENSEES_VENV))/bin:$$PATH" $(CARGO) test --release -p studies \
		--test docs python_example

bench:
	$(CARGO) bench -p solvers

# The README's speed table: the paper_scene group BENCH_RUNS times (machines are noisy: the
# table gives fastest-of-N times and within-run ratios), each run's criterion files kept in
# target/bench-runs/N (criterion writes them to CRITERION_HOME, set here so that a run's copy
# is always its own), then the table of the runs, into target/bench-table.md and on screen.
BENCH_RUNS ?= 6
BENCH_HOME := $(CURDIR)/target/bench-criterion
bench-table:
	rm -rf target/bench-runs target/bench-table.md
	mkdir -p target/bench-runs
	for i in $$(seq 1 $(BENCH_RUNS)); do \
		rm -rf $(BENCH_HOME) && \
		CRITERION_HOME=$(BENCH_HOME) $(CARGO) bench -p solvers --bench paper_scene && \
		cp -r $(BENCH_HOME)/paper_scene target/bench-runs/$$i || exit 1; \
	done
	$(CARGO) run --release -q -p solvers --example bench_table -- \
		$$(ls -d target/bench-runs/* | sort -t/ -k3 -n) > target/bench-table.tmp
	mv target/bench-table.tmp target/bench-table.md
	cat target/bench-table.md

fmt:
	$(CARGO) fmt --all

# Clippy with warnings as errors (CI runs it); the lints allowed workspace-wide, with the
# reason, are in Cargo.toml's [workspace.lints.clippy]. In its own target folder, and in CI
# after the tests: on a clean clone, a cargo test run right after clippy had its first
# compiler probe (`rustc -`, cached in target/.rustc_info.json) read stray compiler output
# as its source and stop (three times of four; deleting that file mends it).
clippy:
	$(CARGO) clippy --release --workspace --all-targets --target-dir target/clippy -- -D warnings

# The API documentation (target/clippy/doc/solvers/index.html) with warnings as errors (CI
# runs it): a doc link to an item that was renamed or never existed fails, as do math indices
# such as φ[i] that rustdoc would take for links (write φ\[i\]). Twice: with the private
# items (their docs' links checked too), then as published (no public doc linking a private
# item). In clippy's target folder (the same dependencies, checked once).
doc:
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --workspace --no-deps --document-private-items --target-dir target/clippy
	RUSTDOCFLAGS="-D warnings" $(CARGO) doc --workspace --no-deps --target-dir target/clippy

clean:
	$(CARGO) clean
