"""Where the suite's time goes: a pytest plugin (a measurement, not a test) and its summary.

``PYTHONPATH=test .venv/bin/python -m pytest -q -p time_breakdown -n auto --dist loadfile test`` records, per
worker, into ``$GEROTOR_TWIN_SUITE_TIME`` (default ``out/suite_time``) a JSON file:

* ``compile``: numba's ``numba:compile`` events of every function, as ``[test, function, own s, total s]``
  (own: without the compiles nested inside it);
* ``calls``: the wall time [s] inside each of :data:`TIMED` (the outermost call; a call inside another timed
  one is counted in both).

``python test/time_breakdown.py [DIR]`` prints the totals over the workers, the tests that compiled most and
the functions compiled on more than one worker (docs/tests.md, "How the suite runs").
"""
from __future__ import annotations

import collections
import functools
import importlib
import json
import os
import sys
import time
from pathlib import Path

#: (module, attribute) of the calls timed: the product's work and the waits on other processes (not
#: ``time.sleep``: background threads sleep too, and their sleeps would count as the test's)
TIMED = (("gerotor_twin.bench_emulator.emulator", "synthesize"), ("gerotor_twin.offline.run_bag", "run_bag"),
         ("gerotor_twin.model.steady", "run_steady"), ("gerotor_twin.model.pump", "PumpModel.advance"),
         ("subprocess", "Popen.communicate"), ("subprocess", "Popen.wait"))

_calls: dict = collections.defaultdict(float)
_compiles: list = []
_test = {"id": None}


def _out_dir() -> Path:
    return Path(os.environ.get("GEROTOR_TWIN_SUITE_TIME", "out/suite_time"))


def _timed(key: str, f):
    depth = [0]

    @functools.wraps(f)
    def timed(*args, **kwargs):
        depth[0] += 1
        t0 = time.perf_counter()
        try:
            return f(*args, **kwargs)
        finally:
            depth[0] -= 1
            if depth[0] == 0:
                _calls[key] += time.perf_counter() - t0
    return timed


def _wrap_everywhere(module: str, name: str) -> None:
    """Replace ``module.name`` (``Class.method`` allowed) by its timed version, and every module's binding of the
    same function object (a ``from module import name`` made before)."""
    mod = importlib.import_module(module)
    owner, attr = (getattr(mod, name.split(".")[0]), name.split(".")[1]) if "." in name else (mod, name)
    original = getattr(owner, attr)
    new = _timed(f"{module}.{name}", original)
    setattr(owner, attr, new)
    if owner is mod:
        for other in list(sys.modules.values()):
            if getattr(other, attr, None) is original:
                setattr(other, attr, new)


def pytest_configure(config):
    from numba.core import event
    stack = []

    class _Compiles(event.Listener):
        def on_start(self, ev):
            f = ev.data["dispatcher"].py_func
            stack.append([f"{f.__module__}.{f.__qualname__}", time.perf_counter(), 0.0])

        def on_end(self, ev):
            name, t0, nested = stack.pop()
            total = time.perf_counter() - t0
            if stack:
                stack[-1][2] += total
            _compiles.append((_test["id"], name, total - nested, total))

    event.register("numba:compile", _Compiles())


def pytest_collection_finish(session):
    for module, name in TIMED:
        _wrap_everywhere(module, name)


def pytest_runtest_setup(item):
    _test["id"] = item.nodeid


def pytest_unconfigure(config):
    out = _out_dir()
    out.mkdir(parents=True, exist_ok=True)
    worker = os.environ.get("PYTEST_XDIST_WORKER", "main")
    (out / f"{worker}.json").write_text(json.dumps({"calls": _calls, "compile": _compiles}))


def summary(directory: Path) -> str:
    """The totals over the workers' files in ``directory`` (module doc)."""
    runs = {p.stem: json.loads(p.read_text()) for p in sorted(directory.glob("*.json"))}
    runs = {w: r for w, r in runs.items() if r["calls"] or r["compile"]}
    lines = [f"workers: {', '.join(runs)}"]
    calls = collections.Counter()
    for r in runs.values():
        calls.update(r["calls"])
    lines += [f"{v:8.1f} s  in {k}" for k, v in calls.most_common()]
    own = {w: collections.Counter() for w in runs}
    per_test = collections.Counter()
    for w, r in runs.items():
        for test, name, own_s, total_s in r["compile"]:
            own[w][name] += own_s
            per_test[test] += own_s
    lines.append(f"{sum(sum(c.values()) for c in own.values()):8.1f} s  compiling (numba), by test:")
    lines += [f"{v:8.1f} s    {k}" for k, v in per_test.most_common(10)]
    twice = [n for n in set.intersection(*(set(c) for c in own.values()))] if len(own) > 1 else []
    lines.append("compiled on more than one worker: " + (", ".join(
        f"{n} ({' / '.join(f'{c[n]:.1f}' for c in own.values())} s)"
        for n in sorted(twice, key=lambda n: -min(c[n] for c in own.values()))[:5]) or "nothing"))
    return "\n".join(lines)


if __name__ == "__main__":
    where = Path(sys.argv[1]) if len(sys.argv) > 1 else _out_dir()
    if not any(where.glob("*.json")):
        sys.exit(f"error: no worker files in {where} (run the suite with `-p time_breakdown` first)")
    print(summary(where))
