"""Errors a user can cause, and how they are worded.

Every bad input is reported as an :class:`InputError` naming the field, the
value and the allowed range, so the CLI can print one line (no traceback) and
the node can put the same text on ``/diagnostics``.
"""
from __future__ import annotations

import contextlib
import math
import reprlib
import sys
import warnings
from typing import Any, Iterator

__all__ = ["InputError", "check_range", "check_ranges", "check_int", "check_finite", "short_repr", "clip", "one_line", "MAX_ERROR_CHARS",
           "one_line_warnings", "path_error_line"]

#: Longest error line printed or put on /diagnostics [characters]; each part of an
#: :class:`InputError` (field, value, allowed, reason) is clipped to a share of it.
MAX_ERROR_CHARS = 600
_PART_CHARS = 120

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxlist, _REPR.maxtuple, _REPR.maxdict, _REPR.maxset = 2, 4, 4, 4, 4
_REPR.maxstring, _REPR.maxother, _REPR.maxlong = _PART_CHARS, _PART_CHARS, 40


def clip(text: str, limit: int = _PART_CHARS) -> str:
    """``text`` on one line, at most ``limit`` characters (a cut is marked with the full length)."""
    s = str(text)
    head = " ".join(s[:limit + 1].split()) if ("\n" in s[:limit + 1] or "\r" in s[:limit + 1]) else s[:limit + 1]
    if len(s) <= limit and len(head) <= limit:
        return head
    tail = f"... ({len(s)} chars)"
    return head[:max(0, limit - len(tail))] + tail


def short_repr(value: Any, limit: int = _PART_CHARS) -> str:
    """A bounded ``repr``: time and size bounded whatever the value (nested, shared, huge)."""
    try:
        text = _REPR.repr(value)
    except Exception:  # noqa: BLE001 - a repr that fails must not hide the error being reported
        text = f"<{type(value).__name__}>"
    return clip(text, limit)


def one_line(exc: BaseException | str, limit: int = MAX_ERROR_CHARS) -> str:
    """The message of ``exc`` as one bounded line (for ``error: ...`` and /diagnostics)."""
    return clip(str(exc), limit)


def path_error_line(exc: OSError) -> str:
    """``error: PATH: reason`` for an OSError on a path the user gave (a directory that is a file, a permission, a
    missing parent): one bounded line, as every command prints it (exit status 2)."""
    name = f" {exc.filename}" if getattr(exc, "filename", None) else ""
    return f"error:{clip(name)}: {clip(exc.strerror or str(exc))}"


def _own_category(category: type) -> bool:
    """Whether a warning class is one of the package's own (``TruncatedMcapWarning`` ...)."""
    return category.__module__.split(".")[0] == __name__.split(".")[0]


@contextlib.contextmanager
def one_line_warnings() -> Iterator[None]:
    """While active, the package's own warnings print as one line, ``warning: <message>``, on stderr.

    Python's default shows the file, line number, class and the source line that warned (``f =
    open_mcap(bag)``), which means nothing to a user of the command line.  Warnings of other packages
    keep the default form; ``warnings`` filters (``-W``, ``catch_warnings``) still apply.
    """
    previous = warnings.showwarning

    def show(message, category, filename, lineno, file=None, line=None):
        if not _own_category(category):
            previous(message, category, filename, lineno, file, line)
            return
        with contextlib.suppress(OSError):          # stderr gone: nothing to tell
            print(f"warning: {one_line(message)}", file=file or sys.stderr)

    warnings.showwarning = show
    try:
        yield
    finally:
        warnings.showwarning = previous


class InputError(ValueError):
    """A user-supplied value is invalid.

    Parameters
    ----------
    field : str
        Dotted name of the offending field (``"gears.lobe_radius_m"``).
    value : Any
        The value received.
    allowed : str
        Human-readable allowed range or set (``"(0, 0.05] m"``).
    reason : str, optional
        Extra explanation (e.g. why a profile is undercut).
    """

    def __init__(self, field: str, value: Any, allowed: str, reason: str = ""):
        self.field = field
        self.value = value
        self.allowed = allowed
        self.reason = reason
        msg = f"{clip(field)} = {short_repr(value)} is invalid; allowed: {clip(allowed)}"
        if reason:
            msg += f" ({clip(reason)})"
        super().__init__(msg)


def check_finite(field: str, value: float) -> float:
    """Return ``float(value)`` or raise :class:`InputError` if it is NaN/inf/not a number."""
    try:
        v = float(value)
    except (TypeError, ValueError):
        raise InputError(field, value, "a finite number") from None
    if not math.isfinite(v):
        raise InputError(field, value, "a finite number")
    return v


def check_range(field: str, value: float, lo: float | None = None, hi: float | None = None,
                *, lo_open: bool = False, hi_open: bool = False, unit: str = "") -> float:
    """Check ``lo <= value <= hi`` (open ends if asked); return the value as float.

    Raises
    ------
    InputError
        Naming ``field``, the value and the interval, e.g. ``(0, inf) m``.
    """
    v = check_finite(field, value)
    bad = (lo is not None and (v < lo or (lo_open and v == lo))) or \
          (hi is not None and (v > hi or (hi_open and v == hi)))
    if bad:
        left = "(" if (lo is None or lo_open) else "["
        right = ")" if (hi is None or hi_open) else "]"
        lo_s = "-inf" if lo is None else f"{lo:g}"
        hi_s = "inf" if hi is None else f"{hi:g}"
        raise InputError(field, value, f"{left}{lo_s}, {hi_s}{right}{(' ' + unit) if unit else ''}")
    return v


def check_int(field: str, value, lo: int, hi: int) -> int:
    """Check that ``value`` is an integer (not a bool) in ``[lo, hi]``; return it.

    Raises
    ------
    InputError
        Naming ``field``, the value and ``an integer in [lo, hi]``.
    """
    if isinstance(value, bool) or not isinstance(value, int) or not lo <= value <= hi:
        raise InputError(field, value, f"an integer in [{lo}, {hi}]")
    return value


def check_ranges(obj, prefix: str, ranges) -> None:
    """:func:`check_range` on each attribute of ``obj`` named in ``ranges`` ((name, lo, hi), ...), the error
    naming ``prefix + name``."""
    for name, lo, hi in ranges:
        check_range(f"{prefix}{name}", getattr(obj, name), lo, hi)
