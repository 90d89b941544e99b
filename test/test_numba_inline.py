"""gerotor_twin._numba_inline: numba's IR inlining without the two copies of a callee used once.

Behaviour tests: it is installed on the pinned numba and by nothing else than a checked release; nested
``inline="always"`` helpers inlined at several call sites (loops, branches, the same helper twice in one
expression) compile to what the plain Python functions compute (closed form: integer arithmetic). The compiled
model's outputs with and without it are the same bit for bit (docs/performance.md: a benchmark, two compiles of
the stepper, too long for a test).
"""
from __future__ import annotations

import types

import numba
import pytest
from numba.core import inline_closurecall as icc

from gerotor_twin import _jit, _numba_inline  # noqa: F401 - _jit applies it on import


def test_installed_on_the_pinned_numba():
    """requirements.txt pins a checked numba release: the first compile gets the faster inlining."""
    assert _numba_inline.applied()


def test_another_numba_release_is_left_alone(monkeypatch):
    def sentinel(*a, **k):
        raise AssertionError("not called")
    monkeypatch.setattr(icc.InlineWorker, "inline_function", sentinel)
    monkeypatch.setattr(numba, "__version__", "0.99.0")
    assert not _numba_inline.apply()
    assert icc.InlineWorker.inline_function is sentinel


@numba.njit(inline="always")
def _step(a, k):
    s = 0
    for i in range(k):                  # a callee of several blocks
        s += a * i if i % 2 else -i
    return s


@numba.njit(inline="always")
def _twice(a, k):
    return _step(a, k) + _step(a + 1, k)          # the same callee twice in one expression


@numba.njit(inline="always")
def _branch(a, k):
    if a > 3:
        return _twice(a, k) - _step(a, 2 * k)
    return _step(k, a)


@numba.njit
def _sites(n):
    t = 0
    for a in range(n):
        t += _branch(a, 5) + _twice(a, 3) * 2 + _step(a, a)
    return t


def _plain(dispatchers):
    """The dispatchers' Python functions, each calling the others' Python functions (no compiled code)."""
    ns = {"range": range}
    for name, d in dispatchers.items():
        ns[name] = types.FunctionType(d.py_func.__code__, ns, name)
    return ns


def test_nested_helpers_inlined_at_many_sites_compute_what_python_does():
    plain = _plain({"_step": _step, "_twice": _twice, "_branch": _branch, "_sites": _sites})
    for n in (1, 4, 9):
        assert _sites(n) == plain["_sites"](n)
    assert plain["_sites"](9) != 0 and _sites.signatures     # a value that says something, compiled
