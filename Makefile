# facemech: the two set-up commands of the README are `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: demo test lint bench clean chromium docs docs-check

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e ".[dev]"
	touch $(STAMP)

# a headless browser for the viewer's test (tests/test_viewer.py): installed with apt-get only
# when no chromium is on the PATH, so running it again costs nothing
chromium:
	@command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || { \
	  echo "installing chromium (Debian package) for the viewer test"; \
	  $(SUDO) apt-get update -q && \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium; }

demo: $(STAMP)
	$(BIN)/facemech demo -o demo-output
	$(BIN)/facemech view demo-output/result.nc -o demo-output/view.html

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks tools

test: $(STAMP) chromium lint
	MPLBACKEND=Agg $(BIN)/python -m pytest -q

# the numeric tables of docs/*.md, regenerated in place from the commands that produce them
# (tools/docs_tables.py; 15-40 minutes on 2 shared cores, Powell's Experiment 1 and
# benchmarks/realism.py the longest); docs-check only compares (exit 1 if a table is stale)
docs: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python tools/docs_tables.py

docs-check: $(STAMP)
	MPLBACKEND=Agg $(BIN)/python tools/docs_tables.py --check

bench: $(STAMP)
	$(BIN)/python benchmarks/forward.py

clean:
	rm -rf $(VENV) demo-output .pytest_cache
