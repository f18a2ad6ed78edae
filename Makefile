# utamp_gym: `make demo` runs the main job, `make test` the tests. Both build the venv first.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= out
export MUJOCO_GL ?= egl

.PHONY: venv demo test test-all bench lint clean

venv: $(STAMP)

# torch is installed first and pinned to the CPU build (2.13.0's CPU wheel is on this
# machine's disk); otherwise stable-baselines3 would pull a multi-GB CUDA build.
$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet "torch==2.13.0"
	$(BIN)/pip install --quiet -e ".[rl,dm,dev,ray]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/python examples/planner_policy.py --out $(OUT)/demo

test: $(STAMP)
	$(BIN)/python -m pytest -m "not slow" -q

test-all: $(STAMP)
	$(BIN)/python -m pytest -q

bench: $(STAMP)
	$(BIN)/python benchmarks/planning.py
	$(BIN)/python benchmarks/env_throughput.py
	$(BIN)/python benchmarks/physics_suite.py --seeds 1

lint: $(STAMP)
	$(BIN)/ruff check utamp_gym tests benchmarks examples

clean:
	rm -rf $(VENV) $(OUT) .pytest_cache .ruff_cache
