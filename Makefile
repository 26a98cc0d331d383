# dentalux: every set-up step lives here. `make demo` and `make test` work on a fresh machine.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
STAMP := $(VENV)/.deps-stamp
export PATH := $(abspath $(VENV))/bin:$(PATH)

.PHONY: readme-figures demo test setup build-dev build-prod lint fmt rust-test py-test validate bench clean

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip
	$(PIP) install --quiet "maturin>=1.5,<2"
	touch $(STAMP)

setup: $(STAMP)

# Release build of the extension, installed into the venv (editable Python sources).
# maturin also installs the dependencies declared in pyproject.toml (with the test and
# cluster extras), so pyproject.toml is the one list of Python dependencies.
build-prod: setup
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --release --quiet --extras test,cluster

build-dev: setup
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --quiet --extras test,cluster

# The main job: the paper's figures at preview quality (a few minutes on 2 cores).
demo: build-prod
	$(VENV)/bin/dentalux demo --photons 200000
	$(VENV)/bin/dentalux figures --out figures --quality preview

# Regenerate the PNGs the README shows (docs/figures/) from a preview render.
readme-figures: build-prod
	$(VENV)/bin/dentalux figures --out figures --quality preview
	mkdir -p docs/figures && cp figures/*.png docs/figures/

lint: setup
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings
	$(VENV)/bin/ruff check python tests benchmarks

fmt:
	cargo fmt --all
	$(VENV)/bin/ruff check --fix python tests benchmarks

rust-test:
	cargo test --workspace

py-test: build-prod
	$(VENV)/bin/pytest -q

test: build-prod lint rust-test py-test

validate: build-prod
	$(VENV)/bin/pytest -q -m slow

bench: build-prod
	$(VENV)/bin/python benchmarks/slab.py
	$(VENV)/bin/python benchmarks/inverse.py
	$(VENV)/bin/python benchmarks/scaling.py

clean:
	cargo clean
	rm -rf $(VENV)
