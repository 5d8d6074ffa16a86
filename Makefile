# facemech: the two set-up commands of the README are `make demo` and `make test`.
PYTHON ?= python3
VENV   ?= .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
# the pinned versions of every package (constraints.txt); the lowest that pyproject allows
# (constraints-lowest.txt) for `make test-lowest`, in a venv of its own
CONSTRAINTS ?= constraints.txt
LOW_VENV := .venv-lowest
LOW_BIN  := $(LOW_VENV)/bin
LOW_STAMP := $(LOW_VENV)/.installed
SUDO   := $(shell [ "$$(id -u)" = 0 ] || echo sudo)

.PHONY: demo test test-fast test-lowest test-portable lint bench clean chromium blender docs docs-check

# every package pinned, then the lip-reader's face-mesh model, kept from the mediapipe 0.10.21
# wheel (pip download; facemech.io.face_mesh): that wheel pins numpy < 2 and is not installed;
# then numba's kernels compiled and cached once (facemech.warmup), so that no command waits
$(STAMP): pyproject.toml $(CONSTRAINTS)
	$(PYTHON) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -c $(CONSTRAINTS) -e ".[dev]"
	$(BIN)/python -m facemech.io.face_mesh
	$(BIN)/python -m facemech.warmup
	touch $(STAMP)

$(LOW_STAMP): pyproject.toml constraints-lowest.txt
	$(PYTHON) -m venv $(LOW_VENV)
	$(LOW_BIN)/python -m pip install -q --upgrade pip
	$(LOW_BIN)/python -m pip install -q -c constraints-lowest.txt -e ".[dev]"
	$(LOW_BIN)/python -m facemech.io.face_mesh
	NUMBA_CACHE_DIR=$(LOW_VENV)/numba-cache $(LOW_BIN)/python -m facemech.warmup
	touch $(LOW_STAMP)

# a headless browser for the viewer's test (tests/viz/test_viewer.py): installed with apt-get only
# when no chromium is on the PATH, so running it again costs nothing
chromium:
	@command -v chromium >/dev/null 2>&1 || command -v chromium-browser >/dev/null 2>&1 || { \
	  echo "installing chromium (Debian package) for the viewer test"; \
	  $(SUDO) apt-get update -q && \
	  $(SUDO) env DEBIAN_FRONTEND=noninteractive apt-get install -y -q chromium; }

# Blender as a Python module (bpy, about 375 MB) in a venv of its own, .venv-blender: the
# blendshape export's test opens the glTF in Blender's own importer (tests/io/test_blendshapes.py);
# bpy wants numpy < 2, so it cannot share .venv. Made once; running it again costs nothing.
blender:
	bash tools/blender_venv.sh $(PYTHON)

demo: $(STAMP)
	$(BIN)/facemech demo -o demo-output

lint: $(STAMP)
	$(BIN)/ruff check src tests benchmarks tools

# the suite on two worker processes (pytest-xdist): under 15 minutes on 2 cores. Each worker is
# a process of its own with conftest's one thread for the force kernels, so the numbers are those
# of a plain `pytest` run; a module's tests that share a module-scoped fixture stay on one worker
# (conftest's xdist_group, --dist loadgroup). JOBS=0 runs it in one process.
JOBS   ?= 2
XDIST  := -n $(JOBS) --dist loadgroup

test: $(STAMP) chromium blender lint
	MPLBACKEND=Agg $(BIN)/python -m pytest -q $(XDIST) --durations=20

# the suite less the tests marked slow (pyproject's `slow` marker: 20 s and more each),
# while working; `make test` runs them all. A folder alone: `make test-fast TESTS=tests/io`
TESTS ?= tests
test-fast: $(STAMP) lint
	MPLBACKEND=Agg $(BIN)/python -m pytest -q $(XDIST) --durations=20 -m "not slow" $(TESTS)

# the suite on the oldest versions that pyproject's ranges allow (constraints-lowest.txt), in
# .venv-lowest; no lint (an old ruff knows other rules); numba's cache apart, so that the two
# numba versions do not overwrite each other's compiled kernels in src/
test-lowest: $(LOW_STAMP) chromium
	NUMBA_CACHE_DIR=$(LOW_VENV)/numba-cache MPLBACKEND=Agg $(LOW_BIN)/python -m pytest -q $(XDIST)

# the numeric tests once more under another OpenBLAS kernel (CI runs it after `make test`):
# results must not hang on the last bit of the BLAS (docs/reproducibility.md)
PORTABLE_TESTS := $(addprefix tests/inverse/test_,inverse.py inversion_rolls.py inversion_steps.py \
	inversion_trust.py calibrate.py control_pick.py jaw_bone.py) \
	$(addprefix tests/analysis/test_,regions.py realism.py) \
	$(addprefix tests/speech/test_,speak.py visemes.py planning.py visible_speech.py) \
	tests/workflows/test_subject.py tests/docs/test_docs_tables.py tests/physics/test_lip_reach.py \
	tests/solvers/test_contacts.py
CORETYPE ?= Prescott
test-portable: $(STAMP)
	OPENBLAS_CORETYPE=$(CORETYPE) MPLBACKEND=Agg $(BIN)/python -m pytest -q $(XDIST) --durations=20 \
	  $(PORTABLE_TESTS)

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
	rm -rf $(VENV) $(LOW_VENV) demo-output .pytest_cache
