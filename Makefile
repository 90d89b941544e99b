# gerotor_twin — the two commands a newcomer needs:
#   make demo   set up .venv, install everything, run the main job
#   make test   same set-up, then the whole test suite
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
export AMENT_PREFIX_PATH := $(CURDIR)/$(VENV)
export PYTHONDONTWRITEBYTECODE :=

.PHONY: demo test test-fast setup clean

setup: $(STAMP)

$(STAMP): requirements.txt setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet -r requirements.txt
	$(PY) -m pip install --quiet --no-deps -e .
	touch $(STAMP)

demo: $(STAMP)
	$(VENV)/bin/gerotor-twin demo --out out/demo

test: $(STAMP)
	$(PY) -m pytest -q test

test-fast: $(STAMP)
	$(PY) -m pytest -q -m "not slow" test

clean:
	rm -rf $(VENV) out build *.egg-info
