# Two entry points for a fresh machine:
#   make demo   set up .venv and run the representative rig demo (writes runs/demo/)
#   make test   set up .venv and run the test suite
#   make docs   build the documentation site into site/ (warnings are errors)
# Each installs the exact versions of requirements.lock; `make lock` refreshes it.
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin
LOCK := requirements.lock

.PHONY: demo test test-all setup lint bench lock docs

$(BIN)/pneumaquad: pyproject.toml $(LOCK)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet --constraint $(LOCK) -e '.[dev]'
	touch $(BIN)/pneumaquad

# Resolve pyproject.toml's ranges afresh in a throw-away venv and pin what was installed
# (the optional cluster extra too, so that installing it later gets pinned versions).
lock:
	rm -rf .lock-venv
	$(PYTHON) -m venv .lock-venv
	.lock-venv/bin/pip install --quiet --upgrade pip
	.lock-venv/bin/pip install --quiet -e '.[dev,cluster]'
	{ echo "# Exact versions for make setup/test/demo and .ci/run; refresh with make lock."; \
	  echo "# Resolved with $$(.lock-venv/bin/python -V) on $$(uname -sm)."; \
	  .lock-venv/bin/pip freeze --exclude-editable; } > $(LOCK)
	rm -rf .lock-venv

# The package's bytecode is written here once, so that each command starts without
# compiling the package's modules, also where PYTHONDONTWRITEBYTECODE is set (as in many
# containers; about 0.1-0.2 s a command). Up-to-date files are skipped.
setup: $(BIN)/pneumaquad
	$(BIN)/python -m compileall -q src

demo: setup
	$(BIN)/pneumaquad demo --output runs/demo

test: setup
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -n 2 -m "not slow"

test-all: setup
	$(BIN)/python -m pytest -n 2

lint: setup
	$(BIN)/ruff check .

# The documentation site (mkdocs.yml): guide pages, API reference from the docstrings and
# the parameter reference from the schema, into site/; any warning fails the build.
docs: setup
	NO_MKDOCS_2_WARNING=1 $(BIN)/mkdocs build --strict --site-dir site

bench: setup
	$(BIN)/python benchmarks/kernel_cost.py
	$(BIN)/python benchmarks/rig_speed.py
	$(BIN)/python benchmarks/cost_table.py
	$(BIN)/python benchmarks/robot_speed.py
	$(BIN)/python benchmarks/network_latency.py
	$(BIN)/python benchmarks/gym_speed.py
	$(BIN)/python benchmarks/end_to_end.py
	$(BIN)/pneumaquad report --cost-table --output runs/bench-cost-table
