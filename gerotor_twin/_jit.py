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
    import, :func:`invalidate_stale_cache` hashes the *kernel sources*
    (:func:`kernel_sources`: every module of the package that imports this one,
    and every module of the package those import, transitively, found from the
    import statements without importing anything) and, when the hash changed
    since the cache was written, deletes the package's numba cache files
    (``*.nbi``, ``*.nbc``, wherever numba keeps them: ``__pycache__`` beside the
    sources, ``$NUMBA_CACHE_DIR`` or the user-wide cache) so that everything
    recompiles once.  A module the compiled code cannot reach (the report, the
    ROS node, the CLI) is not hashed: editing it keeps the cache.

Inlining
    The kernel's helpers are inlined at numba's IR level (``inline="always"``);
    :mod:`gerotor_twin._numba_inline` spares numba two copies of each inlined
    callee, which were two thirds of the first compile.

Reference counting off (``_nrt=False``)
    numba's runtime (NRT) counts references to the arrays compiled code holds: an increment and a decrement,
    atomic, around every use of an array that its pruning pass (``RefPrunePass``) cannot prove redundant.  The
    kernels allocate nothing (the stepper works in the preallocated ``Workspace``, its callers own every array
    it touches), so those counts keep nothing alive; they cost about a third of an output step's time and a
    sixth of the install's compile (measured side by side: docs/performance.md, "Why the kernel is built as
    it is").  So :func:`njit` compiles without the runtime by default.  A kernel
    that allocates an array (``np.empty``, an array expression) does not compile without it (numba refuses
    at type inference, loudly) and opts in with ``njit(_nrt=True)``; numba refuses as loudly a kernel without
    it that returns anything but an array it was given.  A kernel without the runtime must not call one with
    it that returns a new array: nobody would free it.

Argument types
    numba compiles one specialisation per tuple of argument *types*; an ``int``
    where the kernel usually gets a ``float`` (a YAML ``1`` instead of ``1.0``)
    would compile the whole stepper again (≈ 40 s).  :func:`typed` casts the
    scalar fields of the kernel's named tuples to their declared types, so every
    pump hits the same compiled code (``python -m gerotor_twin.precompile``
    builds it at install).
"""
from __future__ import annotations

import ast
import fcntl
import functools
import hashlib
import os
from pathlib import Path

import numba

from . import _numba_inline

__all__ = ["njit", "invalidate_stale_cache", "import_closure", "kernel_sources", "source_digest", "typed"]

_PACKAGE = Path(__file__).resolve().parent
_STAMP = "numba_sources.sha256"


# ------------------------------------------------------------------ the kernel's sources
def _module_file(package: Path, dotted: list[str]) -> Path | None:
    """The file of module ``dotted`` (parts below the package) in ``package``, or None."""
    base = package.joinpath(*dotted)
    for f in (base.with_suffix(".py"), base / "__init__.py"):
        if f.is_file():
            return f
    return None


def _imports(package: Path, f: Path) -> set[Path]:
    """The package's modules that ``f`` imports (anywhere in the file, relative or absolute)."""
    name = package.name
    here = list(f.relative_to(package).parent.parts)       # the package ``f`` belongs to
    out = set()
    for node in ast.walk(ast.parse(f.read_bytes(), filename=str(f))):
        if isinstance(node, ast.Import):
            targets = [a.name.split(".") for a in node.names]
            out.update(m for t in targets if t[0] == name for m in [_module_file(package, t[1:])] if m)
            continue
        if not isinstance(node, ast.ImportFrom):
            continue
        if node.level:
            parts = here[:len(here) - (node.level - 1)] if node.level - 1 <= len(here) else None
            if parts is None:
                continue
            mod = parts + (node.module.split(".") if node.module else [])
        elif node.module and node.module.split(".")[0] == name:
            mod = node.module.split(".")[1:]
        else:
            continue
        m = _module_file(package, mod)
        if m:
            out.add(m)
        for a in node.names:                  # ``from . import kernel``: a submodule
            sub = _module_file(package, mod + [a.name])
            if sub:
                out.add(sub)
    return out


def import_closure(roots, package: Path | None = None) -> list[Path]:
    """``roots`` and every module of ``package`` they import, transitively, sorted.

    Read from the import statements (:mod:`ast`, imports inside functions included); nothing is
    imported.  ``roots``: source files of the package; ``package``: its directory (default: this one).
    """
    package = Path(package) if package is not None else _PACKAGE
    todo, seen = [Path(f) for f in roots], set()
    while todo:
        f = todo.pop()
        if f not in seen:
            seen.add(f)
            todo.extend(_imports(package, f))
    return sorted(seen)


def kernel_sources(package: Path | None = None) -> list[Path]:
    """The source files the compiled code can depend on, sorted.

    The modules of ``package`` that import ``_jit`` (they define the compiled
    functions), this module, and every module of the package they import,
    transitively (:func:`import_closure`).  ``package``: the package directory (default: this one).
    """
    package = Path(package) if package is not None else _PACKAGE
    jit = package / "_jit.py"
    users = [f for f in sorted(package.rglob("*.py")) if b"_jit" in f.read_bytes() and jit in _imports(package, f)]
    return import_closure([jit] + users, package)


def source_digest(package: Path | None = None, files=None) -> str:
    """SHA-256 of source files, their paths (relative to ``package``) and contents.

    ``files``: the files to hash (default: the kernel sources, :func:`kernel_sources`).
    """
    package = Path(package) if package is not None else _PACKAGE
    h = hashlib.sha256()
    for f in (kernel_sources(package) if files is None else sorted(files)):
        h.update(f.relative_to(package).as_posix().encode())
        h.update(b"\0")
        h.update(f.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


# ------------------------------------------------------------------ numba's cache files
def _numba_cache_dir(py_file: Path) -> Path | None:
    """The directory numba caches the functions of ``py_file`` in (numba's own locators, in its order)."""
    from numba.core import caching
    impl = getattr(caching, "CacheImpl", None) or getattr(caching, "_CacheImpl")
    for cls in impl._locator_classes:
        try:
            loc = cls.from_function(_numba_cache_dir, str(py_file))   # only the line number of the function is read
        except Exception:                     # noqa: BLE001 - IPython/zip locators: not ours
            loc = None
        if loc is not None:
            return Path(loc.get_cache_path())
    return None


def _cache_files() -> list[Path]:
    """The package's numba cache files (``*.nbi``, ``*.nbc``), wherever numba keeps them: the cache
    directories of the kernel sources' directories (numba keeps one per source directory)."""
    one_per_dir = {f.parent: f for f in kernel_sources()}.values()
    dirs = {_numba_cache_dir(f) for f in one_per_dir}
    return [f for d in sorted(x for x in dirs if x and x.is_dir()) for pat in ("*.nbi", "*.nbc") for f in d.glob(pat)]


def _package_digest() -> str:
    """SHA-256 of every source file of the package (a quick test that nothing changed at all)."""
    h = hashlib.sha256()
    for f in sorted(_PACKAGE.rglob("*.py")):
        h.update(f.relative_to(_PACKAGE).as_posix().encode())
        h.update(b"\0")
        h.update(f.read_bytes())
        h.update(b"\0")
    return h.hexdigest()


def invalidate_stale_cache() -> bool:
    """Delete the package's numba cache if a kernel source changed since it was written.

    The stamp in numba's cache directory of this module holds the digest of
    the whole package (≈ 3 ms: nothing changed, nothing more to do) and that of
    the kernel sources (:func:`source_digest`, ≈ 0.1 s: only computed when some
    file changed); the cache is deleted when the latter differs.  Returns True if
    the cache was reset.  Silent where the cache is not writable.
    """
    root = _numba_cache_dir(_PACKAGE / "_jit.py")
    if root is None:
        return False
    package = _package_digest()
    try:
        root.mkdir(parents=True, exist_ok=True)
        with open(root / (_STAMP + ".lock"), "a") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX)
            stamp = root / _STAMP
            old = stamp.read_text().split() if stamp.exists() else []
            if old[:1] == [package]:
                return False
            kernel = source_digest()
            reset = old[1:2] != [kernel]
            if reset:
                for f in _cache_files():
                    f.unlink(missing_ok=True)
            tmp = stamp.with_suffix(".tmp")
            tmp.write_text(f"{package}\n{kernel}\n")
            os.replace(tmp, stamp)
            return reset
    except OSError:
        return False


# ------------------------------------------------------------------ consistent argument types
@functools.lru_cache(maxsize=None)
def _casts(cls) -> tuple:
    """Per field of the named tuple class ``cls``: ``float``/``int``/``bool`` to cast to, or None."""
    kinds = {"float": float, "int": int, "bool": bool}

    def name(a):                              # a class, a string (postponed annotations) or a ForwardRef
        return getattr(a, "__forward_arg__", None) or getattr(a, "__name__", None) or str(a)
    return tuple(kinds.get(name(cls.__annotations__[f])) for f in cls._fields)


def typed(nt):
    """``nt`` (a named tuple the compiled code takes) with each scalar field cast to its declared type.

    Fields annotated ``float``, ``int`` or ``bool`` are cast; named-tuple fields
    are treated alike, recursively; others (arrays) are kept.  The values are
    unchanged (an integer-valued ``int`` becomes the same ``float``), only the
    numba type is made the one the cache was built for.
    """
    vals = []
    for v, c in zip(nt, _casts(type(nt))):
        if c is not None and type(v) is not c:
            v = c(v)
        elif isinstance(v, tuple) and hasattr(v, "_fields"):
            v = typed(v)
        vals.append(v)
    return type(nt)(*vals)


if os.environ.get("NUMBA_DISABLE_JIT", "0") in ("0", ""):
    invalidate_stale_cache()
    _numba_inline.apply()                     # the first compile about halves (module docstring)


def njit(*args, **kwargs):
    """:func:`numba.njit` with the project's defaults (``cache=True``, ``nogil=True``, ``error_model="numpy"``,
    ``_nrt=False``: no reference counting, above)."""
    kwargs.setdefault("cache", True)
    kwargs.setdefault("nogil", True)
    kwargs.setdefault("error_model", "numpy")
    kwargs.setdefault("_nrt", False)
    return numba.njit(*args, **kwargs)
