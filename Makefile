# The two commands: `make demo` (the main job) and `make test` (the whole suite).
# Each creates the virtual environment it needs.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo figures test fuzz test-runtimes bench bench-runtimes bench-quality devices extension check-lts clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --upgrade pip
	$(PY) -m pip install -e '.[test,blender]'
	touch $@

demo: $(STAMP)
	$(PY) -m holo_addon.demo -o out

figures: $(STAMP)
	$(PY) -m holo_core demo -o out

# Two processes: Blender's native libraries (its TBB, its LLVM) must never meet an OpenCL
# driver's, so the core's tests run where bpy is never imported (as the add-on's worker does).
test: $(STAMP)
	$(PY) -m pytest tests/core
	$(PY) -m pytest tests/addon

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

# The built extension in Blender's LTS releases (bpy modules for Python 3.11, 370 MB each):
# installed, registered, recorded, rendered and composited (tools/blender_lts.py), then the
# add-on's tests on that release (the installed extension's packages on the path).
LTS ?= 4.2.0 4.5.15
check-lts: $(STAMP)
	rm -rf build/lts && $(PY) -m holo_addon.build --platform linux-x64 --python 3.11 -o build/lts
	set -e; for v in $(LTS); do \
	  test -x .venv-bpy$$v/bin/python || \
	    { $(PYTHON) -m venv .venv-bpy$$v && .venv-bpy$$v/bin/pip install "bpy==$$v" "numpy<2"; }; \
	  .venv-bpy$$v/bin/python -m pytest --version >/dev/null 2>&1 || \
	    .venv-bpy$$v/bin/pip install pytest; \
	  mkdir -p build/lts/$$v; \
	  BLENDER_USER_RESOURCES=$$PWD/build/lts/$$v/user PYTHONNOUSERSITE=1 \
	    .venv-bpy$$v/bin/python tools/blender_lts.py build/lts/holo-*.zip build/lts/$$v; \
	  PYTHONPATH=$$PWD/build/lts/$$v/user/extensions/.local/lib/python3.11/site-packages \
	    PYTHONNOUSERSITE=1 .venv-bpy$$v/bin/python -m pytest -q -p no:cacheprovider tests/addon; \
	done

clean:
	rm -rf $(VENV) .venv-bpy* out build dist *.egg-info
