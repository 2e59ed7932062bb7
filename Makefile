# Two entry points: `make demo` and `make test`. Both create .venv and install first.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
ROOT   ?= evoeye-data
N      ?=
WORKERS ?= 2
MONITOR_ROOT ?= evoeye-data-demo-monitors
MONITOR_RUNS ?= 500

.PHONY: demo demo-monitors test install bench lint clean

$(BIN)/python:
	$(PYTHON) -m venv $(VENV)

# torch first, from its exact CPU pin: an unpinned torch would pull several GB of CUDA wheels.
$(STAMP): pyproject.toml | $(BIN)/python
	$(BIN)/pip install --quiet torch==2.13.0
	$(BIN)/pip install --quiet -e '.[test]'
	touch $(STAMP)

install: $(STAMP)

# Without PREFECT_API_URL the flow starts one temporary Prefect server first (flows/__init__.py
# gives it 300 s on a busy machine); `prefect server start` + PREFECT_API_URL skips that wait.
demo: $(STAMP)
	@echo "make demo: fresh runs of both scenarios; the shipped monitor against the rule-based baselines; one evolution round"
	$(BIN)/python -m flows.demo --root $(ROOT) --workers $(WORKERS) $(if $(N),--n $(N))

# The FusionMonitors shipped for the demo (evoeye/monitor/pretrained/), trained on runs of
# their own seed: what `make demo` measures on fresh runs.
demo-monitors: $(STAMP)
	$(BIN)/python -m evoeye.results.demo_monitors --root $(MONITOR_ROOT) --runs $(MONITOR_RUNS) --workers $(WORKERS)

# the import contracts in pyproject.toml (layers, a pure search, Prefect only in flows/) first
test: $(STAMP)
	$(BIN)/lint-imports --no-logo
	$(BIN)/python -m pytest -q -n 2 --dist loadgroup

bench: $(STAMP)
	$(BIN)/python -m benchmarks

lint: $(STAMP)
	$(BIN)/ruff check evoeye flows tests benchmarks

clean:
	rm -rf $(VENV) build *.egg-info
