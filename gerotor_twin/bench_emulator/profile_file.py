"""A user's bench profile from a YAML file (``gerotor-twin synth-bench --profile-file F``).

The file (read with :func:`gerotor_twin.yaml_safe.load_yaml_file`: size and alias expansion
bounded) is a mapping::

    name: warm_start            # optional: letters, digits, _ and - (default: the file's stem)
    description: free text      # optional
    segments:                   # at least one; the first one's set-point is where the run starts
      - {duration_s: 2.0, rpm: 1000, bar: 5, oil_temperature_c: 40}
      - {duration_s: 1.0, rpm: 2000, bar: 10, ramp: true}
      - {duration_s: 3.0, rpm: 2000, bar: 10}

Each segment: ``duration_s`` [s], ``rpm`` [rpm], ``bar`` [bar gauge], optional ``ramp``
(true: ramp linearly from the previous set-point over the segment; false, the default: step
at its start, then hold) and optional ``oil_temperature_c`` [°C] (the bench's oil
temperature set-point, which the sump approaches with its warm-up time constant;
:func:`~gerotor_twin.bench_emulator.emulator.oil_bath`).  Speeds and pressures must lie in
the pump's ``range``.  Every problem is one :class:`~gerotor_twin.errors.InputError` naming
the file, ``segments[i].<field>``, the value and the allowed range.
"""
from __future__ import annotations

import math
import re
from pathlib import Path

from gerotor_twin.config import OperatingRange
from gerotor_twin.errors import InputError

from .profiles import MAX_PROFILE_S, MIN_SEGMENT_S, OIL_RANGE_C, REFERENCE_RANGE, Profile, Segment

__all__ = ["load_profile_file", "parse_profile", "name_and_description"]

_TOP_KEYS = ("name", "description", "segments")
_SEGMENT_KEYS = ("duration_s", "rpm", "bar", "ramp", "oil_temperature_c")
_NAME = re.compile(r"^[A-Za-z0-9_-]{1,64}$")
_MAX_DESCRIPTION = 200


def _number(value, field: str, allowed: str) -> float:
    """``value`` as a finite float (a YAML int or float, not a bool or a string), else InputError."""
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise InputError(field, value, allowed, "not a finite number" if value is not None else "missing key")
    return float(value)


def _segment(raw, i: int, where: str, limits: OperatingRange) -> Segment:
    """One segment of the file (types only; the ranges are checked by :class:`Profile`)."""
    f = f"{where}segments[{i}]"
    if not isinstance(raw, dict):
        raise InputError(f, raw, f"a mapping with keys {', '.join(_SEGMENT_KEYS)}")
    unknown = sorted(str(k) for k in raw if k not in _SEGMENT_KEYS)
    if unknown:
        raise InputError(f"{f}.{unknown[0]}", raw.get(unknown[0]), f"one of the keys {', '.join(_SEGMENT_KEYS)}",
                         "unknown key")
    ramp = raw.get("ramp", False)
    if not isinstance(ramp, bool):
        raise InputError(f"{f}.ramp", ramp, "true | false")
    oil = raw.get("oil_temperature_c")
    return Segment(
        duration_s=_number(raw.get("duration_s"), f"{f}.duration_s", f"[{MIN_SEGMENT_S:g}, {MAX_PROFILE_S:g}] s"),
        rpm=_number(raw.get("rpm"), f"{f}.rpm", f"[0, {limits.max_speed_rpm:g}] rpm"),
        bar=_number(raw.get("bar"), f"{f}.bar", f"[0, {limits.max_delivery_bar:g}] bar gauge"),
        ramp=ramp,
        oil_temperature_c=None if oil is None else _number(
            oil, f"{f}.oil_temperature_c", f"[{OIL_RANGE_C[0]:g}, {OIL_RANGE_C[1]:g}] °C"))


def parse_profile(raw, name: str, limits: OperatingRange = REFERENCE_RANGE, where: str = "",
                  source: str = "") -> Profile:
    """A :class:`Profile` from the parsed YAML document ``raw``.

    Parameters
    ----------
    raw : Any
        The document (a mapping with ``segments``, optional ``name`` and ``description``).
    name : str
        Name used when the document has none.
    limits : OperatingRange
        The pump's range ([rpm], [bar]) the set-points are checked against.
    where : str
        Prefix of the field names in errors (the file, ``"F.yaml: "``).
    source : str
        Text of the file, kept in the profile (and so in the recording's metadata).

    Returns
    -------
    Profile
    """
    if not isinstance(raw, dict):
        raise InputError(f"{where}(document)", raw, f"a mapping with keys {', '.join(_TOP_KEYS)}")
    unknown = sorted(str(k) for k in raw if k not in _TOP_KEYS)
    if unknown:
        raise InputError(f"{where}{unknown[0]}", raw.get(unknown[0]), f"one of the keys {', '.join(_TOP_KEYS)}",
                         "unknown key")
    name, description = name_and_description(raw, name, where, _MAX_DESCRIPTION, " (it names the default output file)")
    segs = raw.get("segments")
    if not isinstance(segs, list) or not segs:
        raise InputError(f"{where}segments", segs, "a list of at least one segment",
                         "missing key" if segs is None else "")
    return Profile(name, tuple(_segment(s, i, where, limits) for i, s in enumerate(segs)),
                   description, limits, where, source)


def name_and_description(raw: dict, name: str, where: str, max_description: int, name_use: str = "") -> tuple[str, str]:
    """The ``name`` (default ``name``) and ``description`` (default empty) of an emulator file's document
    ``raw``, validated: a name of 1-64 letters, digits, _ or -, a description of at most ``max_description``
    characters.  ``where``: prefix of the field names in errors; ``name_use``: what the name is for, said in
    its error."""
    name = raw.get("name", name)
    if not isinstance(name, str) or not _NAME.match(name):
        raise InputError(f"{where}name", name, "1-64 letters, digits, _ or -" + name_use)
    description = raw.get("description", "")
    if not isinstance(description, str) or len(description) > max_description:
        raise InputError(f"{where}description", description, f"a text of at most {max_description} characters")
    return name, description


def load_profile_file(path: str | Path, limits: OperatingRange = REFERENCE_RANGE) -> Profile:
    """Read a profile file (format: module docstring), checked against the pump's range ``limits``.

    Parameters
    ----------
    path : str or Path
        The YAML file.
    limits : OperatingRange
        The pump's range ([rpm], [bar]), e.g. ``load_config(...).range``.

    Returns
    -------
    Profile
        Named after the file's ``name`` or stem; ``source`` holds the file's text.
    """
    from gerotor_twin.yaml_safe import load_yaml_file

    p = Path(path)
    raw = load_yaml_file(p, "--profile-file")
    stem = re.sub(r"[^A-Za-z0-9_-]", "_", p.stem)[:64] or "profile"
    return parse_profile(raw, stem, limits, f"{p}: ", p.read_text(encoding="utf-8"))
