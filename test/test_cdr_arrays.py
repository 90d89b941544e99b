"""gerotor_twin.io.cdr_arrays: mcap_ros2's numeric arrays read in one struct call (behaviour / closed form).

The values written by mcap_ros2's own encoder come back exactly, with the fields after each array where
mcap_ros2's element-by-element readers put them (alignment after a 1-byte field, empty and fixed-size arrays);
a big-endian payload built by hand reads to its values; a payload cut short raises as mcap_ros2's does; another
mcap-ros2-support release is left alone.
"""
from __future__ import annotations

import struct

import numpy as np
import pytest
from mcap_ros2 import _dynamic

from gerotor_twin.io import cdr_arrays, reader  # noqa: F401 - reader applies it on import

SCHEMA = """uint8 a
float64[] d
uint8 b
float32[] f
int16[3] h
uint8 c
uint64[] q
int8[] i8
byte[] by
uint16[] u16
int32[] i32
float64[] empty
uint8 tail"""

NAME = "test_msgs/msg/Arrays"


def _message(rng):
    return {"a": 7, "d": list(rng.normal(size=13)), "b": 3, "f": [float(np.float32(v)) for v in rng.normal(size=5)],
            "h": [-3, 0, 32000], "c": 1, "q": [2 ** 63 + 5, 0, 17], "i8": [-128, 127, 0], "by": [0, 255, 9],
            "u16": [65535, 1], "i32": [-(2 ** 31), 2 ** 31 - 1], "empty": [], "tail": 200}


def _decode(payload, original: bool, monkeypatch):
    if original:
        table = dict(_dynamic.ARRAY_PARSERS)
        for name in cdr_arrays.FORMATS:
            table[name] = getattr(_dynamic.CdrReader, f"{'int8' if name == 'char' else name}_array")
        monkeypatch.setattr(_dynamic, "ARRAY_PARSERS", table)
    return _dynamic.generate_dynamic(NAME, SCHEMA)[NAME](payload)


def test_installed_on_the_pinned_release():
    assert cdr_arrays.applied()


def test_values_and_following_fields_as_written(monkeypatch):
    msg = _message(np.random.default_rng(3))
    payload = _dynamic.serialize_dynamic(NAME, SCHEMA)[NAME](msg)
    fast = _decode(payload, False, monkeypatch)
    for key, value in msg.items():
        got = getattr(fast, key)
        assert (list(got) if isinstance(value, list) else got) == value, key
    slow = _decode(payload, True, monkeypatch)
    for key in msg:
        assert getattr(fast, key) == getattr(slow, key), key


def test_big_endian_payload_built_by_hand():
    values = [1.5, -2.25, 1e300]
    # CDR_BE header, the length, 4 bytes to align the doubles on 8 (counted after the header), the doubles
    payload = b"\x00\x00\x00\x00" + struct.pack(">I", 3) + bytes(4) + struct.pack(">3d", *values)
    schema = "float64[] d"
    msg = _dynamic.generate_dynamic("t/msg/D", schema)["t/msg/D"](payload)
    assert msg.d == values


def test_a_payload_cut_short_raises_like_mcap_ros2(monkeypatch):
    payload = _dynamic.serialize_dynamic(NAME, SCHEMA)[NAME](_message(np.random.default_rng(1)))
    cut = payload[:40]
    with pytest.raises(struct.error):
        _decode(cut, False, monkeypatch)
    with pytest.raises(struct.error):
        _decode(cut, True, monkeypatch)


def test_another_release_is_left_alone(monkeypatch):
    table = dict(_dynamic.ARRAY_PARSERS)
    table["float64"] = _dynamic.CdrReader.float64_array
    monkeypatch.setattr(_dynamic, "ARRAY_PARSERS", table)
    monkeypatch.setattr(cdr_arrays, "_release", lambda: (9, 9))
    assert not cdr_arrays.apply()
    assert table["float64"] is _dynamic.CdrReader.float64_array
