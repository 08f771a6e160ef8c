# Two entry points for a fresh machine:
#   make demo   set up .venv and run the representative rig demo (writes runs/demo/)
#   make test   set up .venv and run the test suite
PYTHON ?= python3
VENV := .venv
BIN := $(VENV)/bin

.PHONY: demo test test-all setup lint bench

$(BIN)/pneumaquad: pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet -e '.[dev]'
	touch $(BIN)/pneumaquad

setup: $(BIN)/pneumaquad

demo: setup
	$(BIN)/pneumaquad demo --output runs/demo

test: setup
	$(BIN)/ruff check .
	$(BIN)/python -m pytest -n 2 -m "not slow"

test-all: setup
	$(BIN)/python -m pytest -n 2

lint: setup
	$(BIN)/ruff check .

bench: setup
	$(BIN)/python benchmarks/kernel_cost.py
	$(BIN)/python benchmarks/rig_speed.py
	$(BIN)/python benchmarks/cost_table.py
	$(BIN)/python benchmarks/robot_speed.py
	$(BIN)/python benchmarks/network_latency.py
	$(BIN)/pneumaquad report --cost-table --output runs/bench-cost-table
