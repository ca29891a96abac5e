# Two entry points for a fresh machine with Python 3.11+ and make:
#   make demo   - install gadgetctl into .venv and run it on the bundled simulated devices
#   make test   - install with the test extras and run the whole test suite
#   make fuzz   - fuzz every parser and driver decoder for SECONDS (default 600) on WORKERS (2),
#                 then drive each whole path (serve, monitor vrpn:, UDP and serial drivers) for
#                 PATH_SECONDS (20) each with memory and time caps: about 17 minutes in all
PYTHON ?= python3
VENV ?= .venv
BIN := $(VENV)/bin

.PHONY: demo test lint bench fuzz completions clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install --quiet --upgrade pip

$(VENV)/.installed: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e .
	$(BIN)/python -m compileall -q src drivers >/dev/null
	touch $@

$(VENV)/.installed-test: $(BIN)/python pyproject.toml
	$(BIN)/python -m pip install --quiet -e '.[test]'
	$(BIN)/python -m compileall -q src drivers >/dev/null
	touch $@ $(VENV)/.installed

demo: $(VENV)/.installed
	$(BIN)/gadgetctl demo

test: $(VENV)/.installed-test
	$(BIN)/python -m ruff check .
	$(BIN)/python -m pytest -q

lint: $(VENV)/.installed-test
	$(BIN)/python -m ruff check .
	$(BIN)/python -m ruff format --check .

bench: $(VENV)/.installed-test
	$(BIN)/python bench/run.py

SECONDS ?= 600
WORKERS ?= 2
PATH_SECONDS ?= 20
fuzz: $(VENV)/.installed-test
	$(BIN)/python tests/fuzz/campaign.py --seconds $(SECONDS) --workers $(WORKERS) --path-seconds $(PATH_SECONDS)

completions: $(VENV)/.installed
	$(BIN)/python -m gadgetctl.cli.completions completions
	$(BIN)/python -m gadgetctl.cli.roothelp

clean:
	rm -rf $(VENV) build dist
