# gerotor_twin — the two commands a newcomer needs:
#   make demo   set up .venv, install everything, run the main job
#   make test   same set-up, then the whole test suite on every core (pytest-xdist)
# `make setup` also compiles the model's numba kernels once (python -m gerotor_twin.precompile: the
# mobility and fixed-centre models, about 30 s on 2 cores, beside the install) into the on-disk cache, so no first
# start of those models compiles (short, fdm and gear_coupling: stages compile on first use, 5-12 s, with a line saying so);
# the cache holds only the argument types, so it serves every pump, table size and fluid model.
PYTHON ?= python3
VENV   := .venv
PY     := $(VENV)/bin/python
STAMP  := $(VENV)/.installed
# what the kernels' compile imports (the pins of requirements.txt): installed first, so the compile runs on one
# core while the rest installs on the other (docs/performance.md, "First compile")
KERNEL_REQS := $(shell grep -E '^(numpy|scipy|numba|PyYAML)==' requirements.txt)
# ... installed without their byte code (6 s instead of 13 s before the compile can start); the compile writes the
# byte code of what it imports, and compileall the rest of these packages' on the other core after the install
KERNEL_PKGS := numpy scipy numba llvmlite yaml _yaml
KERNEL_DIRS := import os, sys, sysconfig; s = sysconfig.get_paths()["purelib"]; \
  print(" ".join(d for d in (os.path.join(s, n) for n in sys.argv[1:]) if os.path.isdir(d)))
export AMENT_PREFIX_PATH := $(CURDIR)/$(VENV)
export PYTHONDONTWRITEBYTECODE :=

.PHONY: demo demo-model demo-calibrate demo-diagnose demo-sweep test test-fast setup precompile bench bench-accuracy bags clean chromium

setup: $(STAMP)

$(STAMP): requirements.txt setup.py
	$(PYTHON) -m venv $(VENV)
	$(PY) -m pip install --quiet --upgrade pip
	$(PY) -m pip install --quiet --no-compile $(KERNEL_REQS)
	$(PY) -m gerotor_twin.precompile > $(VENV)/precompile.log 2>&1 & compile=$$!; \
	  $(PY) -m pip install --quiet -r requirements.txt && $(PY) -m pip install --quiet --no-deps -e . && \
	  $(PY) -m compileall -q $$($(PY) -c '$(KERNEL_DIRS)' $(KERNEL_PKGS)); installed=$$?; \
	  wait $$compile; compiled=$$?; cat $(VENV)/precompile.log; test $$installed -eq 0 -a $$compiled -eq 0
	touch $(STAMP)

# the numba cache again (after `git pull`, say; a kernel source changed: its first start would compile)
precompile: $(STAMP)
	$(PY) -m gerotor_twin.precompile

# the nominal twin node fed by a replayed bench recording (real time) and the twin calibrated on the map
# recording (calibrate + run-bag, in the background meanwhile), then one HTML report of both (< 1 min)
demo: $(STAMP)
	$(PY) -m gerotor_twin.ros.demo_live --out out/demo

# the model alone: efficiency table and plots
demo-model: $(STAMP)
	$(VENV)/bin/gerotor-twin demo --out out/demo-model

# calibration from the bundled map bag, then the health monitor over the wear bag (about 4 min on 2 cores)
demo-calibrate: $(STAMP)
	$(VENV)/bin/gerotor-twin calibrate --bench bags/bench_map.mcap -o out/demo-calibrate/pump_fitted.yaml \
	    --json out/demo-calibrate/fit.json --report out/demo-calibrate/fit.html --overwrite --oil-sensor-tau 3
	$(VENV)/bin/gerotor-twin run-bag bags/bench_wear.mcap -o out/demo-calibrate/wear_twin.mcap \
	    --config out/demo-calibrate/pump_fitted.yaml --overwrite --quiet --oil-sensor-tau 3
	$(VENV)/bin/gerotor-twin health out/demo-calibrate/wear_twin.mcap --every 4

# a fault named: a 20 s bench recording (the built-in diagnosis profile) of a pump whose tooth-tip clearance
# opens to 2.5 x over the run, the twin (config/pump.yaml) over it with the health monitor, then its alarms,
# each with the fault the classifier named and its probability, and the report with the fault timeline beside
# the health plots (out/demo-diagnose/report.html; about 40 s on 2 cores)
DIAGNOSE := out/demo-diagnose
demo-diagnose: $(STAMP)
	$(VENV)/bin/gerotor-twin synth-bench --profile diagnosis --clearance-factor 1.0 \
	    --fault tip_wear --fault-to 2.5 --seed 1 -o $(DIAGNOSE)/bench_tip_wear.mcap --overwrite
	$(VENV)/bin/gerotor-twin run-bag $(DIAGNOSE)/bench_tip_wear.mcap -o $(DIAGNOSE)/twin.mcap --overwrite --quiet \
	    --health window_s=0.5 --health settle_s=0.5
	$(VENV)/bin/gerotor-twin report --bench $(DIAGNOSE)/bench_tip_wear.mcap --twin $(DIAGNOSE)/twin.mcap \
	    -o $(DIAGNOSE)/report.html > /dev/null 2>&1 && echo "wrote $(DIAGNOSE)/report.html (the fault timeline beside the health plots)"
	$(VENV)/bin/gerotor-twin health $(DIAGNOSE)/twin.mcap --json $(DIAGNOSE)/health.json

# a small design study on the embedded Dask cluster (all cores): writes out/demo-sweep/summary.html, opens nothing
demo-sweep: $(STAMP)
	rm -rf out/demo-sweep
	$(VENV)/bin/gerotor-twin sweep config/sweep_demo.yaml -o out/demo-sweep

# the figures of docs/performance.md (first compile, real time of the default pump and the family, the gear
# models' cost), measured again and written in place: about 5 min on 2 cores, 2.5 of them the compile
BENCH_ARGS ?= --seconds 3 --repeats 3 --compile
bench: $(STAMP)
	$(VENV)/bin/gerotor-twin bench all $(BENCH_ARGS) --json out/bench/all.json --write-doc docs/performance.md
	$(VENV)/bin/gerotor-twin bench parts --family --json out/bench/parts.json --write-doc docs/performance.md

# the bundled recordings and the config calibrated on the map, written again (bags/README.md: after a change of the
# emulated pump's physics, Method 1 or the flows, the bags' golden test fails until this runs; about 3 min on 2
# cores: the map on one, the transient and the wear recordings on the other, then the calibration)
GT := $(VENV)/bin/gerotor-twin
bags: $(STAMP)
	$(GT) synth-bench --profile map -o bags/bench_map.mcap --overwrite --quiet & map=$$!; \
	  $(GT) synth-bench --profile transient --speed-rate 200 --pressure-rate 200 -o bags/bench_transient.mcap \
	    --overwrite --quiet && \
	  $(GT) synth-bench --profile wear --wear-to 1.25 --wear-start 8 -o bags/bench_wear.mcap --overwrite --quiet; \
	  other=$$?; wait $$map && test $$other -eq 0
	$(GT) calibrate --bench bags/bench_map.mcap -o bags/pump_fitted_bench_map.yaml --oil-sensor-tau 3 --overwrite

# the accuracy table of docs/numerics.md, measured again and written in place (seconds with the reference
# cache filled; each reference computed afresh costs minutes)
bench-accuracy: $(STAMP)
	$(VENV)/bin/gerotor-twin bench accuracy --rpm 1000,2000,3000 --bar 5,15,27.5 --models mobility,fixed \
	    --json out/bench/accuracy.json --write-doc docs/numerics.md

# the suite on every core (pytest-xdist, one worker per core; a test file stays on one worker, so its module
# fixtures are built once); `make test XDIST=` runs it in one process
XDIST ?= -n auto --dist loadfile
test: $(STAMP) chromium
	$(PY) -m pytest -q $(XDIST) --durations=15 test

# headless Chromium for the report-rendering test (Debian package; installed when root)
chromium:
	@command -v chromium >/dev/null 2>&1 || { if [ "$$(id -u)" = 0 ]; then \
	  apt-get update -qq && DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium >/dev/null; \
	  else echo "note: chromium missing (sudo apt-get install chromium); its report test is skipped"; fi; }

test-fast: $(STAMP)
	$(PY) -m pytest -q $(XDIST) -m "not slow" test

clean:
	rm -rf $(VENV) out build *.egg-info
