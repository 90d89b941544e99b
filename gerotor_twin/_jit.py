"""One place that decides how the hot loop is compiled.

``njit`` is :func:`numba.njit` with an on-disk cache (so a warm start does not
recompile) and ``fastmath`` off (results must match the pure-NumPy reference
path bit-for-bit in spirit, to round-off).  Set ``NUMBA_DISABLE_JIT=1`` to run
every kernel as plain Python/NumPy: that is the reference path the tests can
use to check the compiled one.
"""
from __future__ import annotations

import numba

__all__ = ["njit"]


def njit(*args, **kwargs):
    """:func:`numba.njit` with the project's defaults (``cache=True``)."""
    kwargs.setdefault("cache", True)
    kwargs.setdefault("nogil", True)
    return numba.njit(*args, **kwargs)
