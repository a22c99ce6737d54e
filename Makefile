# The two commands: `make demo` (the main job) and `make test` (the whole suite).
# Each creates the virtual environment it needs.
PYTHON ?= python3
VENV   ?= .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed

.PHONY: demo figures test bench devices extension clean

$(STAMP): pyproject.toml
	test -x $(PY) || $(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --upgrade pip
	$(PY) -m pip install -e '.[test,blender]'
	touch $@

demo: $(STAMP)
	$(PY) -m holo_addon.demo -o out

figures: $(STAMP)
	$(PY) -m holo_core demo -o out

test: $(STAMP)
	$(PY) -m pytest

bench: $(STAMP)
	$(PY) bench/propagation.py
	$(PY) bench/record.py
	$(PY) bench/render.py

devices: $(STAMP)
	$(PY) -m holo_core devices

extension: $(STAMP)
	$(PY) -m holo_addon.build -o dist

clean:
	rm -rf $(VENV) out build dist *.egg-info
