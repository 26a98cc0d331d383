# dentalux: every set-up step lives here. `make demo` and `make test` work on a fresh machine.
SHELL := /bin/bash
VENV ?= .venv
PY := $(VENV)/bin/python
PIP := $(VENV)/bin/pip
STAMP := $(VENV)/.deps-stamp
export PATH := $(abspath $(VENV))/bin:$(PATH)

.PHONY: readme-figures demo test docs setup build-dev build-prod lint fmt rust-test py-test validate bench clean \
	wheel wheel-test browser

$(STAMP): pyproject.toml
	python3 -m venv $(VENV)
	$(PIP) install --quiet --upgrade pip
	$(PIP) install --quiet "maturin>=1.5,<2"
	touch $(STAMP)

setup: $(STAMP)

# Release build of the extension, installed into the venv (editable Python sources).
# maturin also installs the dependencies declared in pyproject.toml (with the test, cluster
# and docs extras), so pyproject.toml is the one list of Python dependencies.
build-prod: setup
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --release --quiet --extras test,cluster,docs

build-dev: setup
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin develop --quiet --extras test,cluster,docs

# Release wheel (maturin) in dist/: the extension and the Python package with its data files,
# scenes and report template. `pip install dist/dentalux-*.whl` is the install a lab makes.
wheel: setup
	rm -f dist/dentalux-*.whl
	VIRTUAL_ENV=$(abspath $(VENV)) $(VENV)/bin/maturin build --release --quiet --out dist

# The wheel installed into a throwaway venv and used from outside the checkout.
wheel-test: wheel
	PIP=$(abspath $(PIP)) tests/wheel_smoke.sh dist/dentalux-*.whl

# Headless Chromium for the report's browser test (tests/test_report.py): Debian's package,
# installed only when missing and only as root; without it that test skips, saying why.
browser:
	@command -v chromium >/dev/null || { \
	  if [ "$$(id -u)" = 0 ] && command -v apt-get >/dev/null; then \
	    apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq \
	      --no-install-recommends chromium fonts-liberation; \
	  else echo "browser: no chromium and not root: the report's browser test will skip"; fi; }

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

# The documentation site (mkdocs.yml) into site/, offline, warnings as errors: a broken link,
# a page missing from the nav or a docstring the API reference cannot read fails it. The
# command-line reference page is generated from the typer app at this build. (Not --quiet:
# it hides the warnings from --strict, and a broken link would pass.)
docs: build-prod
	NO_MKDOCS_2_WARNING=1 $(VENV)/bin/mkdocs build --strict

py-test: build-prod
	$(VENV)/bin/pytest -q

test: build-prod browser lint docs rust-test py-test wheel-test

validate: build-prod
	$(VENV)/bin/pytest -q -m slow

bench: build-prod
	$(VENV)/bin/python benchmarks/slab.py
	$(VENV)/bin/python benchmarks/inverse.py
	$(VENV)/bin/python benchmarks/scaling.py

clean:
	cargo clean
	rm -rf $(VENV)
