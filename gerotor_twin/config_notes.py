"""Notes on a pump file's keys: a value far from its default, a key whose meaning changed, a removed key.

A pump file written for an older version of the package can hold a key whose
unit or meaning has changed since (``numerics.tolerance`` was an error on
ln ρ, about 5e-5; it is now a fraction of the pressure scale max(p_d − p_s, 1 bar, the chamber
pressures' range), default a few 1e-2) or
one that is no longer used.  Neither is an error: the file still loads, and
:func:`gerotor_twin.config.load_config` says each note once, in one line
(the CLI on stderr, the node on its console and ``/diagnostics``).

* **Sensible range** (:func:`far_from_default`): a number given for a key of a
  checked section (``numerics``) that is :data:`SENSIBLE_FACTOR` (100) times
  or more away from that key's default, in either direction, is named with
  its value, its default and the range ``[default / 100, default × 100]``.
  The defaults are read from the section's dataclass, where they are defined.
  0 ("off") and keys whose default is 0 are not checked; a key whose default
  holds only with another key at its default (:data:`DEFAULT_DEPENDS_ON`:
  ``tolerance``'s default is that of the default ``error_measure``) is checked
  only then.
* **Changed or removed keys** (:data:`KEY_NOTES`): a changed key's one-line
  hint is added to its range note; a removed key is taken out of the file
  before validation (so it is not an "unknown key" error) with a one-line
  notice that it is ignored and why.
"""
from __future__ import annotations

from dataclasses import MISSING, dataclass, fields
from typing import Any

__all__ = ["KeyNote", "KEY_NOTES", "SENSIBLE_FACTOR", "DEFAULT_DEPENDS_ON", "drop_removed_keys",
           "far_from_default"]

#: A value this many times (or more) away from its key's default, either way, is named [-].
SENSIBLE_FACTOR = 100.0


@dataclass(frozen=True)
class KeyNote:
    """What changed about a key: ``kind`` ``"changed"`` (unit or meaning) or ``"removed"``, and the hint."""
    kind: str
    hint: str


#: ``section.key`` -> what changed (one line).  A removed key goes here instead of being refused.
KEY_NOTES: dict[str, KeyNote] = {
    "numerics.tolerance": KeyNote(
        "changed", "numerics.tolerance is a fraction of the pressure scale max(p_d - p_s, 1 bar, chamber pressure range) "
                   "(error_measure: pressure, the default); in older pump files it was an error on ln(rho), about 5e-5: remove the key to use the default, "
                   "or set error_measure: log_density for the old meaning"),
    "numerics.rate_fraction": KeyNote(
        "removed", "the sub-step cap it set is covered by numerics.closing_tolerance, which holds the chambers whose "
                   "delivery port closes or has just opened (docs/numerics.md)"),
    "numerics.top_tolerance": KeyNote(
        "removed", "the bound on a pressure top hidden inside a sub-step is covered by numerics.closing_tolerance "
                   "(docs/numerics.md)"),
}

#: ``section.key`` -> ``section.other``: the key's default holds only with ``other`` at its default.
DEFAULT_DEPENDS_ON: dict[str, str] = {"numerics.tolerance": "numerics.error_measure"}


def drop_removed_keys(raw: dict) -> tuple[dict, list[str]]:
    """``raw`` without the keys :data:`KEY_NOTES` lists as removed, and a notice for each one found.

    ``raw`` is not modified (a section that loses a key is copied).
    """
    out, notes = dict(raw), []
    for dotted, note in KEY_NOTES.items():
        section, _, key = dotted.partition(".")
        sec = out.get(section)
        if note.kind == "removed" and isinstance(sec, dict) and key in sec:
            out[section] = {k: v for k, v in sec.items() if k != key}
            notes.append(f"{dotted} is no longer used and is ignored (= {sec[key]!r}): {note.hint}")
    return out, notes


def far_from_default(section: str, given: dict, obj: Any) -> list[str]:
    """Notes for the numbers ``given`` in ``section`` that are far from the defaults of ``obj``'s dataclass.

    Parameters
    ----------
    section : str
        Section name (``"numerics"``).
    given : dict
        The keys as written in the file (only these are checked).
    obj : dataclass instance
        The parsed section; its fields' defaults are the reference.
    """
    defaults = {f.name: f.default for f in fields(obj) if f.default is not MISSING}
    notes = []
    for key in given:
        value, default = getattr(obj, key, None), defaults.get(key)
        if not _is_number(value) or not _is_number(default) or value == 0 or default == 0:
            continue
        other = DEFAULT_DEPENDS_ON.get(f"{section}.{key}", "").partition(".")[2]
        if other and getattr(obj, other) != defaults.get(other):
            continue
        ratio = abs(value / default)
        if SENSIBLE_FACTOR > ratio > 1.0 / SENSIBLE_FACTOR:
            continue
        lo, hi = abs(default) / SENSIBLE_FACTOR, abs(default) * SENSIBLE_FACTOR
        note = KEY_NOTES.get(f"{section}.{key}")
        notes.append(f"{section}.{key} = {value:g} is far outside its sensible range [{lo:g}, {hi:g}] "
                     f"(default {default:g}; {SENSIBLE_FACTOR:g}x either way)"
                     + (f"; {note.hint}" if note is not None and note.kind == "changed" else ""))
    return notes


def _is_number(x: Any) -> bool:
    return isinstance(x, (int, float)) and not isinstance(x, bool)
