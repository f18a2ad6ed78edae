# utamp_gym: `make demo` runs the main job, `make test` the tests. Both build the venv first.
PYTHON ?= python3
VENV   := .venv
BIN    := $(VENV)/bin
STAMP  := $(VENV)/.installed
OUT    ?= out

MJ4    := .venv-mujoco4

.PHONY: venv demo test test-all test-mujoco4 bench lint docs clean

venv: $(STAMP)

# torch goes in first ($(TORCH), from $(TORCH_INDEX) when set), so that the rl extra's
# `torch>=2.2` finds it installed and pip adds no other torch. Which build that is depends on
# where pip looks:
# - pip's stock settings (PyPI only): PyPI's Linux x86_64 wheel, the CUDA build, with its
#   nvidia-* and cuda-* packages (a download of several GB; it runs on a CPU too);
# - `make venv TORCH_INDEX=https://download.pytorch.org/whl/cpu`: the CPU build (+cpu);
# - a pip configured with a find-links folder holding torch-2.13.0+cpu (as on the machine
#   this is developed on: PIP_FIND_LINKS=/opt/wheels): that CPU build, from disk.
TORCH       ?= torch==2.13.0
TORCH_INDEX ?=

$(STAMP): pyproject.toml
	$(PYTHON) -m venv $(VENV)
	$(BIN)/pip install --quiet --upgrade pip
	$(BIN)/pip install --quiet "$(TORCH)" $(if $(TORCH_INDEX),--index-url "$(TORCH_INDEX)")
	$(BIN)/pip install --quiet -e ".[rl,dm,video,dev,ray,docs,data,zoo]"
	touch $(STAMP)

demo: $(STAMP)
	$(BIN)/python examples/planner_policy.py --out $(OUT)/demo

test: $(STAMP)
	$(BIN)/python -m pytest -m "not slow" -q

test-all: $(STAMP)
	$(BIN)/python -m pytest -q

# The core package on mujoco 4 without the dm extra (only dm-control caps mujoco below 4):
# a second venv gets `pip install ".[dev]"` (a built wheel, not editable) and the physics
# tests run from tests/ against that installed copy (tests/test_dm_control.py skips).
MJ4_TESTS := test_extras.py test_robot_*.py test_sim_*.py test_closed_loop.py test_extra_suite.py \
	test_dm_control.py
test-mujoco4:
	test -x $(MJ4)/bin/python || $(PYTHON) -m venv $(MJ4)
	$(MJ4)/bin/pip install --quiet --upgrade pip
	$(MJ4)/bin/pip install --quiet ".[dev]" "mujoco>=4,<5"
	cd tests && $(abspath $(MJ4))/bin/python -c "import importlib.util as u, mujoco, utamp_gym; \
		assert mujoco.__version__.startswith('4.'), mujoco.__version__; \
		assert u.find_spec('dm_control') is None, 'dm_control must not be installed'; \
		assert 'site-packages' in utamp_gym.__file__, utamp_gym.__file__; \
		print('mujoco', mujoco.__version__, 'without dm_control;', utamp_gym.__file__)"
	cd tests && $(abspath $(MJ4))/bin/python -m pytest -m "not slow" -q -p no:cacheprovider $(MJ4_TESTS)

bench: $(STAMP)
	$(BIN)/python benchmarks/planning.py
	$(BIN)/python benchmarks/env_throughput.py
	$(BIN)/python benchmarks/physics_suite.py --seeds 1

# The documentation site: the scripts in docs/_scripts write the generated pages (one per env
# id, the CLI reference, figures from the code) into docs/_generated and docs/envs, then Sphinx
# builds build/docs/html with warnings as errors, and every local link of it must resolve
# (docs/_scripts/check_links.py). Nothing is fetched from the network.
DOCS_OUT ?= build/docs
docs: $(STAMP)
	$(BIN)/python docs/_scripts/generate.py
	$(BIN)/python -m sphinx -W --keep-going -q -b html docs $(DOCS_OUT)/html
	$(BIN)/python docs/_scripts/check_links.py $(DOCS_OUT)/html

lint: $(STAMP)
	$(BIN)/ruff check utamp_gym tests benchmarks examples

clean:
	rm -rf $(VENV) $(MJ4) $(OUT) .pytest_cache .ruff_cache build docs/_generated docs/envs
