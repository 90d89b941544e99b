"""On-disk cache of the tight reference revolutions of ``gerotor-twin bench accuracy``.

A reference (:func:`.accuracy.reference_revolution`) is the dearest part of an accuracy point: an
output step 16× finer and a tolerance of 1e-8.  It depends on the pump, the operating point, the
outer-gear model and the code that runs it, never on the numerics under test, so an A/B of the
twin's own numerics (a tolerance, a step-control constant) over the whole family needs each
reference once.  The key of a cached revolution is the SHA-256 of

* the whole configuration the reference runs (:func:`.accuracy.reference_numerics` applied: every
  field of the pump, its oil and its reference numerics),
* the operating point (speed [rpm], delivery pressure [bar gauge]) and the gear model,
* the source of every module the reference's code imports (:func:`code_digest`), so that a changed
  kernel, bearing, geometry or steady-state driver invalidates it by itself.

Files are ``<key>.npz`` (:meth:`.accuracy.Revolution.save`) in :func:`default_directory`.
"""
from __future__ import annotations

import dataclasses
import functools
import hashlib
import json
import os
from pathlib import Path

__all__ = ["default_directory", "code_digest", "reference_key", "cached_revolution"]


def default_directory() -> Path:
    """Where ``bench accuracy`` keeps references: ``$GEROTOR_TWIN_CACHE/references``, else
    ``$XDG_CACHE_HOME/gerotor_twin/references``, else ``~/.cache/gerotor_twin/references``."""
    base = os.environ.get("GEROTOR_TWIN_CACHE")
    if base:
        return Path(base) / "references"
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(xdg) / "gerotor_twin" / "references"


@functools.lru_cache(maxsize=1)
def code_digest() -> str:
    """SHA-256 of the sources a reference revolution runs: :mod:`.accuracy` and every module of the
    package it imports, transitively (:func:`gerotor_twin._jit.import_closure`)."""
    from .. import _jit
    return _jit.source_digest(files=_jit.import_closure([Path(__file__).resolve().with_name("accuracy.py")]))


def _plain(obj):
    """JSON form of what a configuration holds besides numbers and strings (arrays, paths, tuples)."""
    if hasattr(obj, "tolist"):
        return obj.tolist()
    return str(obj)


def reference_key(ref_cfg, rpm: float, bar: float, model: str) -> str:
    """The cache key of the reference run of ``ref_cfg`` (reference numerics already applied) at
    ``rpm`` [rpm], ``bar`` [bar gauge] with gear model ``model``."""
    text = json.dumps({"config": dataclasses.asdict(ref_cfg), "rpm": float(rpm), "bar": float(bar),
                       "model": model, "code": code_digest()}, sort_keys=True, default=_plain)
    return hashlib.sha256(text.encode()).hexdigest()


def cached_revolution(directory, key: str, compute, load):
    """The revolution stored under ``key`` in ``directory`` (read by ``load(path)``, e.g.
    :meth:`.accuracy.Revolution.load`), or ``compute()`` stored there first (its ``save(path, key=…)``).
    ``directory`` None: no cache, ``compute()`` only.  Returns (revolution, hit)."""
    if directory is None:
        return compute(), False
    path = Path(directory) / f"{key}.npz"
    if path.is_file():
        try:
            return load(path)[0], True
        except (OSError, ValueError, KeyError):      # a torn or foreign file: recompute and replace it
            pass
    rev = compute()
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")
    rev.save(tmp, key=key)
    os.replace(tmp, path)                            # whole or absent, also beside a parallel run
    return rev, False
