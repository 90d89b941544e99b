"""mcap_ros2's numeric array fields read with one ``struct`` call per array instead of one per element.

``mcap_ros2`` decodes a ``float64[]`` field element by element (``CdrReader.float64_array``: a list of
``float64()`` calls, each an alignment test and a ``struct.unpack_from``) [1]_.  A twin log's waveform
messages (chamber pressures, peaks and gaps at every output step) make that most of the time a report spends
reading: 5.4 million such calls for the two 20 MB logs of ``make demo`` (2026-12-05, cProfile of
``report.build.build_report``: 7.1 of its 14.2 s profiled in decoding).

CDR [2]_ aligns a primitive to its own size, counted from the end of the 4-byte encapsulation header; after
the first element of an array of one primitive type the others are contiguous and aligned.  So one alignment
(the reader's own ``_align``) and one ``struct.unpack_from(f"<{n}d", ...)`` read the same values in the same
order, with the same error (``struct.error``) where the payload ends early.  An empty array reads nothing and
aligns nothing, as ``mcap_ros2`` does.  ``uint8``/``byte`` arrays (already one slice, as ``bytes``), boolean,
string and wide-string arrays keep ``mcap_ros2``'s own readers.

:func:`apply` puts these readers in ``mcap_ros2._dynamic.ARRAY_PARSERS`` (which the decoder looks up per field at
decode time), for the ``mcap-ros2-support`` releases they were checked against (:data:`CHECKED`); with any
other it does nothing.  Applied by :mod:`gerotor_twin.io.reader` and :mod:`gerotor_twin.io.decode` on import:
everything read back through ``mcap_ros2`` (logs, recordings, reports) and what the node decodes with it (the
bench inputs themselves are decoded at fixed offsets by :mod:`gerotor_twin.io.fastcdr`).  Measured
(2026-12-05, the demo's 20 MB node log, fastest of 3): :func:`gerotor_twin.io.reader.read_topics` 2.17 → 1.51 s;
the demo's report 4.97 → 4.37 s.

References
----------
.. [1] mcap-ros2-support 0.6.0, ``mcap_ros2/_cdr.py`` (``CdrReader``) and ``mcap_ros2/_dynamic.py``
   (``ARRAY_PARSERS``, ``_read_complex_type``).
.. [2] Object Management Group, *Common Object Request Broker Architecture (CORBA) 3.4, Part 2:
   Interoperability*, sec. 9.3 (CDR: primitive types aligned on their natural boundaries).
"""
from __future__ import annotations

import struct
from importlib import metadata

__all__ = ["CHECKED", "FORMATS", "apply", "applied"]

#: mcap-ros2-support releases whose ``CdrReader`` this was read against (major, minor).
CHECKED = ((0, 6),)

#: ``struct`` format character and size [bytes] of each ROS 2 numeric type (``char`` is ``int8`` there).
FORMATS = {"float64": ("d", 8), "float32": ("f", 4), "int64": ("q", 8), "uint64": ("Q", 8),
           "int32": ("i", 4), "uint32": ("I", 4), "int16": ("h", 2), "uint16": ("H", 2),
           "int8": ("b", 1), "char": ("b", 1)}


def _array_reader(char: str, size: int):
    """A reader ``(reader, length) -> list`` of ``length`` values of one numeric type, in one ``struct`` call."""
    def read(reader, length: int) -> list:
        if length <= 0:
            return []
        if size > 1:
            reader._align(size)
        values = struct.unpack_from(("<" if reader.little_endian else ">") + f"{length}{char}",
                                    reader.data, reader.offset)
        reader.offset += size * length
        return list(values)
    read.__name__ = f"read_{char}_array"
    read._gerotor_twin = True
    return read


def _release() -> tuple[int, int] | None:
    try:
        major, minor = metadata.version("mcap-ros2-support").split(".")[:2]
        return int(major), int(minor)
    except (metadata.PackageNotFoundError, ValueError):
        return None


def apply() -> bool:
    """Install the readers in ``mcap_ros2``'s table if it is a :data:`CHECKED` release; returns :func:`applied`."""
    from mcap_ros2 import _dynamic
    table = getattr(_dynamic, "ARRAY_PARSERS", None)
    if isinstance(table, dict) and _release() in CHECKED and not applied():
        for name, (char, size) in FORMATS.items():
            if name in table:
                table[name] = _array_reader(char, size)
    return applied()


def applied() -> bool:
    """True if ``mcap_ros2`` reads ``float64[]`` fields with this module's reader."""
    from mcap_ros2 import _dynamic
    return getattr(getattr(_dynamic, "ARRAY_PARSERS", {}).get("float64"), "_gerotor_twin", False)
