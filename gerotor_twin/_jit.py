"""One place that decides how the hot loop is compiled.

``njit`` is :func:`numba.njit` with an on-disk cache (so a warm start does not
recompile), ``nogil`` (a model thread runs beside the ROS executor),
``error_model="numpy"`` and ``fastmath`` off (results must match the pure-Python
path to round-off).

``error_model="numpy"``: a float division by zero gives ±inf/nan instead of
raising ``ZeroDivisionError``, so numba does not guard every division with a
branch.  The kernel's results are the same bit for bit (checked on four
operating points, both gear models), it is 4–8 % faster (docs/performance.md),
and a non-finite state is still caught: ``PumpModel.advance`` raises
``FloatingPointError`` on it (a solver failure, counted by the twin).  Set
``NUMBA_DISABLE_JIT=1`` to run every kernel as plain Python/NumPy: that is the
reference path the tests use to check the compiled one.

Stale caches
    numba checks a cached function against its own source file only.  The
    model's stepper inlines functions of other modules (flows, contact,
    hydraulics), so an edit there would leave a stale compiled stepper.  On
    import, :func:`invalidate_stale_cache` hashes every source file of the
    package and, when the hash changed since the cache was written, deletes the
    package's numba cache files (``*.nbi``, ``*.nbc``) so that everything
    recompiles once.
"""
from __future__ import annotations

import fcntl
import hashlib
import os
from pathlib import Path

import numba

__all__ = ["njit", "invalidate_stale_cache"]

_PACKAGE = Path(__file__).resolve().parent
_STAMP = "numba_sources.sha256"


def _cache_files():
    """The package's numba cache files: beside the sources, or under $NUMBA_CACHE_DIR."""
    env = os.environ.get("NUMBA_CACHE_DIR")
    if env:
        return [f for pat in ("*.nbi", "*.nbc") for f in Path(env).rglob(pat) if "gerotor_twin" in f.as_posix()]
    return [f for d in _PACKAGE.rglob("__pycache__") for pat in ("*.nbi", "*.nbc") for f in d.glob(pat)]


def invalidate_stale_cache() -> bool:
    """Delete the package's numba cache if any source file changed since it was written.

    Returns True if files were deleted.  Silent where the cache is not writable.
    """
    h = hashlib.sha256()
    for f in sorted(_PACKAGE.rglob("*.py")):
        h.update(f.relative_to(_PACKAGE).as_posix().encode())
        h.update(f.read_bytes())
    digest = h.hexdigest()
    root = Path(os.environ.get("NUMBA_CACHE_DIR") or _PACKAGE / "__pycache__")
    try:
        root.mkdir(parents=True, exist_ok=True)
        with open(root / (_STAMP + ".lock"), "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            stamp = root / _STAMP
            if stamp.exists() and stamp.read_text() == digest:
                return False
            for f in _cache_files():
                f.unlink(missing_ok=True)
            tmp = stamp.with_suffix(".tmp")
            tmp.write_text(digest)
            os.replace(tmp, stamp)
            return True
    except OSError:
        return False


if os.environ.get("NUMBA_DISABLE_JIT", "0") in ("0", ""):
    invalidate_stale_cache()


def njit(*args, **kwargs):
    """:func:`numba.njit` with the project's defaults (``cache=True``, ``nogil=True``, ``error_model="numpy"``)."""
    kwargs.setdefault("cache", True)
    kwargs.setdefault("nogil", True)
    kwargs.setdefault("error_model", "numpy")
    return numba.njit(*args, **kwargs)
