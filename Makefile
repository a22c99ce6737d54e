# The two commands: `make demo` (the main job) and `make test` (the whole suite).
# Each creates the virtual environment it needs; `make docs` and `make lint` use the same one.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo demo-plate figures test test-numpy2 docs lint fuzz test-runtimes bench bench-runtimes bench-quality devices extension check-lts clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --upgrade pip
	$(PY) -m pip install -e '.[test,blender,bench,dev]'
	touch $@

demo: $(STAMP)
	$(PY) -m holo_addon.demo -o out

# The demo scene from a plate recorded once (Plate mode): README, "Plates that serve a shot"
demo-plate: $(STAMP)
	$(PY) -m holo_addon.demo --mode PLATE -o out/plate

figures: $(STAMP)
	$(PY) -m holo_core demo -o out

# Two processes: Blender's native libraries (its TBB, its LLVM) must never meet an OpenCL
# driver's, so the core's tests run where bpy is never imported (as the add-on's worker does).
# tests/core holds test_examples.py: every public name's docstring Examples, run as doctests.
test: $(STAMP)
	$(PY) -m pytest tests/core
	$(PY) -m pytest tests/addon
	$(MAKE) test-numpy2

# The core's tests again under NumPy 2, as a Python user's environment without bpy installs
# them (bpy's wheels pin NumPy 1 in .venv): a virtual environment of its own
VENV2 ?= .venv-numpy2
test-numpy2:
	test -x $(VENV2)/bin/python || $(PYTHON) -m venv $(VENV2)
	$(VENV2)/bin/python -m pip install -q -e '.[test]' 'numpy>=2'
	$(VENV2)/bin/python -m pytest tests/core

# The documentation (docs/): Sphinx with the tutorials executed, warnings as errors, every
# cross-reference resolved, offline; open docs/_build/html/index.html. The tree's holo_core is
# the one documented and run; FFTW plans by estimate (no timing: the figures stay the same).
docs: $(STAMP)
	PYTHONPATH=$(CURDIR) HOLO_FFTW_PLANNER=estimate $(PY) -m sphinx -W --keep-going -n -q \
	  -b html docs docs/_build/html

# ruff's rules and its formatting over the whole tree (pyproject.toml, [tool.ruff]);
# `ruff format .` writes what the second check asks for
lint: $(STAMP)
	$(PY) -m ruff check .
	$(PY) -m ruff format --check .

# The readers' fuzz suite at 5000 cases each (make test runs 300; about 4 minutes).
FUZZ_CASES ?= 5000
fuzz: $(STAMP)
	HOLO_FUZZ_CASES=$(FUZZ_CASES) $(PY) -m pytest -s tests/core/io/test_fuzz.py

# The core's suite once per usable CPU OpenCL driver (python -m holo_core devices lists them).
RUNTIMES ?= intel portable
test-runtimes: $(STAMP)
	set -e; for r in $(RUNTIMES); do 	  echo "== HOLO_DEVICE=$$r"; HOLO_DEVICE=$$r $(PY) -m pytest -q tests/core; 	done

bench: $(STAMP)
	$(PY) bench/propagation.py
	$(PY) bench/record.py
	$(PY) bench/render.py
	$(PY) bench/sweep.py

bench-runtimes: $(STAMP)
	$(PY) bench/runtimes.py

# The pass against Cycles at 640x480, 1280x720, 1920x1080 (about 25 minutes on 2 cores).
bench-quality: $(STAMP)
	$(PY) bench/quality.py

devices: $(STAMP)
	$(PY) -m holo_core devices

extension: $(STAMP)
	$(PY) -m holo_addon.build -o dist

# The built extension in Blender's LTS releases, each through its bpy module (370 MB each, in
# .venv-bpy<version>) on the Python that bpy needs: 3.11 for 4.2 and 4.5, 3.13 for 5.2, named by
# PYTHON311= / PYTHON313= or found as python3.X on the PATH or in pyenv's versions (a release
# whose Python is found nowhere is skipped, with a line saying what to install). Installed,
# registered, recorded, rendered and composited, then the add-on's tests on that release, with
# the installed extension's packages on the path (tools/blender_lts.py).
LTS ?= 4.2.0 4.5.15 5.2.3
check-lts: $(STAMP)
	PYTHON311="$(PYTHON311)" PYTHON313="$(PYTHON313)" $(PY) tools/blender_lts.py $(LTS)

clean:
	rm -rf $(VENV) .venv-bpy* out build dist *.egg-info docs/_build docs/reference/generated
