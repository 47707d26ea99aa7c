# skyfall: `make demo` and `make test` do all set-up on a fresh machine (venv, pip packages,
# release build of the Rust extension). `make bench` writes benches/results/, `make lint` checks.
SHELL := /bin/bash
.DEFAULT_GOAL := help

VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.deps-stamp
OUT    ?= out
# The Rust build of the extension (cargo test, clippy) uses the venv's interpreter.
export PYO3_PYTHON := $(abspath $(PY))
export VIRTUAL_ENV := $(abspath $(VENV))
# Vulkan loaders complain on stderr without a runtime dir; give them a private one.
export XDG_RUNTIME_DIR ?= $(abspath $(VENV))/xdg-runtime

.PHONY: help setup vulkan build wheel demo test test-rust test-python fuzz lint bench bench-ab device clean

help:
	@echo "make demo   build, then render the demo outputs into $(OUT)/"
	@echo "make test   build, then cargo test, clippy, stub check and pytest (notebooks included)"
	@echo "make bench  build, then write benches/results/"
	@echo "make bench-ab BASE=<rev>  A/B of the bench rows, BASE (default HEAD~1) against the working tree"
	@echo "make fuzz   build, then the property-based harness (tests/test_fuzz.py) at FUZZ_EXAMPLES cases per target"
	@echo "make lint   cargo clippy and mypy"
	@echo "make wheel  the abi3 wheel (Python >= 3.11) in dist/, for benches/device.sh on a GPU machine"

$(PY):
	@command -v cargo >/dev/null || { echo "cargo not found: install Rust (https://rustup.rs) first" >&2; exit 1; }
	@python3 -m venv $(VENV) || { \
	  echo "python3 -m venv failed; installing python3-venv" >&2; \
	  if [ "$$(id -u)" = 0 ]; then apt-get update -qq && apt-get install -y -qq python3-venv && python3 -m venv $(VENV); \
	  else echo "run: sudo apt-get install python3-venv" >&2; exit 1; fi; }

$(STAMP): requirements-dev.txt | $(PY)
	$(PY) -m pip install -q --upgrade pip
	$(PY) -m pip install -q -r requirements-dev.txt
	@touch $@

setup: $(STAMP)
	@mkdir -p -m 700 $(XDG_RUNTIME_DIR)

# The GPU backend's tests run on any Vulkan driver; without one, install Mesa's lavapipe
# (software Vulkan) when we are root, else say what to install.
vulkan:
	@if ls /usr/share/vulkan/icd.d/*.json >/dev/null 2>&1 && ldconfig -p | grep -q 'libvulkan\.so\.1'; then :; \
	elif [ "$$(id -u)" = 0 ]; then \
	  echo "installing Mesa's software Vulkan driver (lavapipe)"; \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq mesa-vulkan-drivers libvulkan1 >/dev/null; \
	else echo "GPU tests need a Vulkan driver: sudo apt-get install mesa-vulkan-drivers libvulkan1" >&2; exit 1; fi

# The extension is abi3 (_core.abi3.so): a _core.cpython-*.so left by an older build would be
# imported before it, so it goes.
build: setup
	rm -f python/skyfall/_core.cpython-*.so
	$(VENV)/bin/maturin develop --release --locked -q

# One wheel for Python 3.11 and later (pyo3's abi3): what benches/device.sh installs on a GPU
# machine without Rust. Reuses the release build's artifacts (seconds after `make build`).
wheel: build
	rm -f dist/skyfall-*.whl
	$(VENV)/bin/maturin build --release --locked -q --out dist

# The GPU check on this machine's Vulkan driver: benches/results/gpu.md and gpu.json.
device: wheel vulkan
	PYTHON=$(abspath $(PY)) bash benches/device.sh

demo: build
	$(PY) -m skyfall._demo --out $(OUT)

test-rust: setup vulkan
	cargo fmt --all --check
	cargo test --workspace --locked
	cargo clippy --workspace --all-targets --locked -- -D warnings

# Python's fault dump on a crash (tests/conftest.py); printed when pytest dies of a signal.
CRASH_LOG := $(abspath .pytest-crash.txt)

test-python: build wheel vulkan
	$(PY) -m mypy.stubtest skyfall._core
	$(PY) -m mypy
	@rm -f $(CRASH_LOG) $(CRASH_LOG).test
	SKYFALL_CRASH_LOG=$(CRASH_LOG) $(PY) -m pytest -p no:faulthandler --nbmake tests notebooks || { \
	  s=$$?; if [ -s $(CRASH_LOG) ]; then echo "== pytest crashed in: $$(cat $(CRASH_LOG).test 2>/dev/null)"; \
	  head -n 2 $(CRASH_LOG); grep -A25 -m1 "^Current thread" $(CRASH_LOG) || head -c 2500 $(CRASH_LOG); fi; exit $$s; }

test: test-rust test-python

# The harness of tests/test_fuzz.py, longer than make test's bounded run (12 cases per target);
# it prints the number of cases run.
FUZZ_EXAMPLES ?= 400
fuzz: build
	SKYFALL_FUZZ_EXAMPLES=$(FUZZ_EXAMPLES) $(PY) -m pytest -q -s -p no:randomly tests/test_fuzz.py

lint: setup
	cargo fmt --all --check
	cargo clippy --workspace --all-targets --locked -- -D warnings
	$(PY) -m mypy

bench: build vulkan
	$(PY) -m pip install -q -r requirements-bench.txt
	$(PY) benches/bench_physics.py
	$(PY) benches/bench_render.py
	$(PY) benches/bench_rain.py
	$(PY) benches/bench_sky.py
	$(PY) benches/clouds.py
	$(PY) benches/cloud_sky_light.py
	$(PY) benches/bench_windshield.py
	$(PY) benches/snow.py
	$(PY) benches/snow_cover.py
	$(PY) benches/srgb8_banded.py
	$(PY) benches/wet.py
	$(PY) benches/sweeps.py

# A/B of the bench rows against BASE, timed alternately in one run: benches/results/ab.md.
# BASE's wheel and venv are cached under .ab-cache/ by commit; BASE_WHEEL=<wheel of BASE> skips its build.
BASE ?= HEAD~1
bench-ab: build vulkan
	$(PY) benches/ab.py --base $(BASE) $(if $(BASE_WHEEL),--base-wheel $(BASE_WHEEL))

clean:
	rm -rf target $(VENV) $(OUT) dist
