# sosdyn — one command per experiment. `make run` and `make test` work on a fresh clone.
PY      ?= python3
VENV    := .venv
BIN     := $(VENV)/bin
STAMP   := $(VENV)/.installed
PYTEST  := $(BIN)/python -m pytest
# Small-matrix workloads: a multi-threaded OpenBLAS spin-waits (10-100x slower on 2 cores).
export OPENBLAS_NUM_THREADS ?= 1

.PHONY: venv run test test-slow test-kernels wheel bench bench-sos fig1 fig2 fig3 fig4 lasa-all lasa-dsopt real-data second-order crossing-shapes crossing-letters winding winding-shapes warp-figure demo3d demo7d sweep report learner-table poses robot docs clean

venv: $(STAMP)
$(STAMP): pyproject.toml
	test -d $(VENV) || $(PY) -m venv $(VENV)
	$(BIN)/python -m pip install -q --upgrade pip
	$(BIN)/python -m pip install -q -e '.[all]'
	touch $(STAMP)

run: venv
	$(BIN)/python -m problems run

# The suite in TEST_JOBS processes (pytest-xdist), a test file's tests in one process (its module
# fixtures built once); the workers share the toy experiment's cache (tests/problems/conftest.py).
# `make test TEST_JOBS=0` runs it in one process.
TEST_JOBS ?= 2
XDIST    := $(if $(filter 0,$(TEST_JOBS)),,-n $(TEST_JOBS) --dist loadfile)

test: venv
	$(BIN)/lint-imports
	$(PYTEST) -q -m "not slow" $(XDIST)

# The suite under other OpenBLAS kernels (OPENBLAS_CORETYPE: each rounds differently), as on another
# machine's CPU; ~3 min per kernel. The suite must pass under every one of them.
KERNELS ?= Haswell Sandybridge Nehalem SkylakeX
test-kernels: venv
	@for k in $(KERNELS); do echo "== OPENBLAS_CORETYPE=$$k"; \
	  OPENBLAS_CORETYPE=$$k $(PYTEST) -q -m "not slow" $(XDIST) -p no:cacheprovider || exit 1; done

# Experiment-sized runs (quick versions of the experiments, benchmarks, the wheel): not in `make test`.
test-slow: venv
	$(PYTEST) -q -m slow $(XDIST)

# Build the wheel, install it into a fresh venv, run `sosdyn --version` and `sosdyn fit lasa:Sshape` (~1 min).
wheel: venv
	$(PYTEST) -q -m slow tests/test_wheel.py

bench: venv
	$(BIN)/python -m pip install -q -e '.[bench]'
	$(BIN)/python -m problems bench

bench-sos: venv
	$(BIN)/python -m pip install -q -e '.[bench]'
	$(BIN)/python -m problems bench-sos

fig1 fig2 fig3 fig4 lasa-all lasa-dsopt real-data second-order crossing-shapes crossing-letters winding winding-shapes warp-figure demo3d demo7d sweep report learner-table poses: venv
	$(BIN)/python -m problems $@

# CDSP and GMR drive a simulated Franka Panda (pybullet, the [robot] extra, in [all]): reports/robot/
robot: venv
	$(BIN)/python -m problems robot

docs: venv
	$(BIN)/mkdocs build --strict -d site

clean:
	rm -rf reports/cache reports/figures reports/index.html reports/report.pdf
