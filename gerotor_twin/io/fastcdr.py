"""Fast CDR for the node's hot messages: the outputs it publishes and the inputs it decodes.

Encoding: std_msgs/Float64MultiArray (NumPy ``tobytes`` for the data; the
generic encoder :func:`gerotor_twin.io.codec.encode` packs a 720 × 8 waveform
in ~5 ms, this one in ~0.05 ms), std_msgs/Float64, geometry_msgs/Vector3Stamped
and sensor_msgs/FluidPressure (~1 µs against 7–30 µs), sensor_msgs/JointState (the
names' bytes cached per name list).

Decoding: the bench inputs (sensor_msgs/JointState, FluidPressure,
Temperature, std_msgs/Float64) and Vector3Stamped by ``struct`` at fixed
offsets, ~1–3 µs against 8–14 µs for ``mcap_ros2``'s dynamic decoder, into
small slotted objects with the message's field names.  Anything that is not
little-endian CDR of the expected shape goes to the generic decoder
(:func:`gerotor_twin.io.decode.decode`), which gives the error message.

Both directions yield the same bytes / values as the generic codec and as
``mcap_ros2`` (tests: ``test/test_io_fastcdr.py``): little-endian CDR with the
4-byte encapsulation header, alignment relative to the end of that header [1]_.

References
----------
.. [1] OMG, "Extensible and Dynamic Topic Types for DDS" 1.3, sec. 7.4.3
   (XCDR version 1 encoding: primitive alignment to their size, strings as
   uint32 length including the NUL, sequences as uint32 count).
"""
from __future__ import annotations

import functools
import struct
from typing import Any, Callable

import numpy as np

from gerotor_twin.io import messages as m
from gerotor_twin.io.codec import encode as generic_encode

__all__ = ["encode_float64_multiarray", "encode", "decode_fast", "FAST_DECODERS", "FAST_ENCODERS"]

_LE = b"\x00\x01"              # encapsulation: CDR, little endian
_F64 = struct.Struct("<d")
_V3S_HEAD = struct.Struct("<iII")   # stamp.sec, stamp.nanosec, len(frame_id) + 1
_U32 = struct.Struct("<I")
_STAMP = struct.Struct("<iI")
_2F64 = struct.Struct("<2d")
_3F64 = struct.Struct("<3d")


def _pad(buf: bytearray, align: int) -> None:
    n = (len(buf) - 4) % align
    if n:
        buf.extend(b"\x00" * (align - n))


def encode_float64_multiarray(msg: dict) -> bytes:
    """CDR bytes of a :func:`gerotor_twin.io.messages.float64_multiarray` dict."""
    layout = msg["layout"]
    dims = tuple((str(d["label"]), int(d["size"]), int(d["stride"])) for d in layout["dim"])
    data = np.asarray(msg["data"], dtype="<f8")
    return _multiarray_head(dims, int(layout["data_offset"]), data.size) + data.tobytes()


@functools.lru_cache(maxsize=256)
def _multiarray_head(dims: tuple, data_offset: int, n: int) -> bytes:
    """Encapsulation, layout and data length of a Float64MultiArray (the periodic outputs repeat a few)."""
    buf = bytearray(b"\x00\x01\x00\x00")
    buf += struct.pack("<I", len(dims))
    for label, size, stride in dims:
        raw = label.encode("utf-8") + b"\x00"
        _pad(buf, 4)
        buf += struct.pack("<I", len(raw)) + raw
        _pad(buf, 4)
        buf += struct.pack("<II", size, stride)
    _pad(buf, 4)
    buf += struct.pack("<II", data_offset, n)
    if n:
        _pad(buf, 8)
    return bytes(buf)


def encode_float64(msg: dict) -> bytes:
    """CDR bytes of a :func:`gerotor_twin.io.messages.float64` dict."""
    return _LE + b"\x00\x00" + _F64.pack(float(msg["data"]))


def _encode_stamped(msg: dict, values: tuple) -> bytes:
    """CDR bytes of a std_msgs/Header followed by float64 fields ``values`` (in order)."""
    st = msg["header"]["stamp"]
    frame = str(msg["header"]["frame_id"]).encode("utf-8") + b"\x00"
    buf = bytearray(_LE + b"\x00\x00")
    buf += _V3S_HEAD.pack(int(st["sec"]), int(st["nanosec"]), len(frame)) + frame
    _pad(buf, 8)
    buf += struct.pack(f"<{len(values)}d", *values)
    return bytes(buf)


def encode_vector3_stamped(msg: dict) -> bytes:
    """CDR bytes of a :func:`gerotor_twin.io.messages.vector3_stamped` dict."""
    v = msg["vector"]
    return _encode_stamped(msg, (float(v["x"]), float(v["y"]), float(v["z"])))


def encode_fluid_pressure(msg: dict) -> bytes:
    """CDR bytes of a :func:`gerotor_twin.io.messages.fluid_pressure` dict (the per-chamber outputs)."""
    return _encode_stamped(msg, (float(msg["fluid_pressure"]), float(msg["variance"])))


@functools.lru_cache(maxsize=64)
def _names(names: tuple, offset: int) -> bytes:
    """The CDR string sequence ``names`` starting at ``offset`` bytes after the encapsulation header."""
    buf = bytearray(b"\x00" * (4 + offset))
    _pad(buf, 4)
    buf += _U32.pack(len(names))
    for name in names:
        raw = name.encode("utf-8") + b"\x00"
        _pad(buf, 4)
        buf += _U32.pack(len(raw)) + raw
    return bytes(buf[4 + offset:])


def _put_doubles(buf: bytearray, values) -> None:
    """Append a float64 sequence (count, then the values aligned to 8)."""
    data = np.asarray(values, dtype="<f8").ravel()
    _pad(buf, 4)
    buf += _U32.pack(data.size)
    if data.size:
        _pad(buf, 8)
        buf += data.tobytes()


def encode_joint_state(msg: dict) -> bytes:
    """CDR bytes of a :func:`gerotor_twin.io.messages.joint_state` dict (the named, stamped outputs)."""
    st = msg["header"]["stamp"]
    frame = str(msg["header"]["frame_id"]).encode("utf-8") + b"\x00"
    buf = bytearray(_LE + b"\x00\x00")
    buf += _V3S_HEAD.pack(int(st["sec"]), int(st["nanosec"]), len(frame)) + frame
    buf += _names(tuple(msg["name"]), len(buf) - 4)
    for key in ("position", "velocity", "effort"):
        _put_doubles(buf, msg[key])
    return bytes(buf)


#: The fast encoders by message type (each takes the dict of :mod:`gerotor_twin.io.messages`).
FAST_ENCODERS: dict[str, Callable[[dict], bytes]] = {
    m.FLOAT64_MULTIARRAY: encode_float64_multiarray, m.FLOAT64: encode_float64,
    m.VECTOR3_STAMPED: encode_vector3_stamped, m.FLUID_PRESSURE: encode_fluid_pressure,
    m.JOINT_STATE: encode_joint_state}


def encode(msgtype: str, msg: Any) -> bytes:
    """Fast path for the node's periodic outputs, the project codec for everything else."""
    fast = FAST_ENCODERS.get(msgtype)
    return generic_encode(msgtype, msg) if fast is None else fast(msg)


# ------------------------------------------------------------------ decoding
class _Message:
    """A decoded message: slotted attributes named like the ``.msg`` fields (as ``mcap_ros2``'s classes).

    Deliberately not a tuple: code that walks messages treats tuples as arrays.
    """
    __slots__ = ()

    def __eq__(self, other):
        return type(other) is type(self) and all(getattr(self, n) == getattr(other, n) for n in self.__slots__)

    def __repr__(self):
        return f"{type(self).__name__}({', '.join(f'{n}={getattr(self, n)!r}' for n in self.__slots__)})"


class Stamp(_Message):
    """builtin_interfaces/Time."""
    __slots__ = ("sec", "nanosec")

    def __init__(self, sec, nanosec):
        self.sec = sec
        self.nanosec = nanosec


class Header(_Message):
    """std_msgs/Header."""
    __slots__ = ("stamp", "frame_id")

    def __init__(self, stamp, frame_id):
        self.stamp = stamp
        self.frame_id = frame_id


class JointState(_Message):
    """sensor_msgs/JointState (positions [rad or m], velocities [rad/s or m/s], efforts [N·m or N])."""
    __slots__ = ("header", "name", "position", "velocity", "effort")

    def __init__(self, header, name, position, velocity, effort):
        self.header = header
        self.name = name
        self.position = position
        self.velocity = velocity
        self.effort = effort


class FluidPressure(_Message):
    """sensor_msgs/FluidPressure [Pa]."""
    __slots__ = ("header", "fluid_pressure", "variance")

    def __init__(self, header, fluid_pressure, variance):
        self.header = header
        self.fluid_pressure = fluid_pressure
        self.variance = variance


class Temperature(_Message):
    """sensor_msgs/Temperature [°C]."""
    __slots__ = ("header", "temperature", "variance")

    def __init__(self, header, temperature, variance):
        self.header = header
        self.temperature = temperature
        self.variance = variance


class Float64(_Message):
    """std_msgs/Float64."""
    __slots__ = ("data",)

    def __init__(self, data):
        self.data = data


class Vector3(_Message):
    """geometry_msgs/Vector3."""
    __slots__ = ("x", "y", "z")

    def __init__(self, x, y, z):
        self.x = x
        self.y = y
        self.z = z


class Vector3Stamped(_Message):
    """geometry_msgs/Vector3Stamped."""
    __slots__ = ("header", "vector")

    def __init__(self, header, vector):
        self.header = header
        self.vector = vector


def _string(data: bytes, o: int) -> tuple[str, int]:
    """A CDR string at offset ``o`` (4-aligned) -> (text, offset after it)."""
    o += -(o - 4) % 4
    n = _U32.unpack_from(data, o)[0]
    if n == 0 or o + 4 + n > len(data) or data[o + 3 + n] != 0:
        raise ValueError("bad CDR string")
    return data[o + 4:o + 3 + n].decode("utf-8"), o + 4 + n


def _header(data: bytes) -> tuple[Header, int]:
    sec, nsec = _STAMP.unpack_from(data, 4)
    frame, o = _string(data, 12)
    return Header(Stamp(sec, nsec), frame), o


def _doubles(data: bytes, o: int) -> tuple[list, int]:
    o += -(o - 4) % 4
    n = _U32.unpack_from(data, o)[0]
    o += 4
    if n:
        o += -(o - 4) % 8
        if o + 8 * n > len(data):
            raise ValueError("CDR sequence beyond the buffer")
        return list(struct.unpack_from(f"<{n}d", data, o)), o + 8 * n
    return [], o


def _joint_state(data: bytes) -> JointState:
    header, o = _header(data)
    o += -(o - 4) % 4
    count = _U32.unpack_from(data, o)[0]
    o += 4
    if count > len(data):
        raise ValueError("CDR sequence beyond the buffer")
    names = []
    for _ in range(count):
        name, o = _string(data, o)
        names.append(name)
    position, o = _doubles(data, o)
    velocity, o = _doubles(data, o)
    effort, o = _doubles(data, o)
    return JointState(header, names, position, velocity, effort)


def _two_doubles_after_header(data: bytes) -> tuple[Header, float, float]:
    header, o = _header(data)
    o += -(o - 4) % 8
    a, b = _2F64.unpack_from(data, o)
    return header, a, b


def _fluid_pressure(data: bytes) -> FluidPressure:
    return FluidPressure(*_two_doubles_after_header(data))


def _temperature(data: bytes) -> Temperature:
    return Temperature(*_two_doubles_after_header(data))


def _float64(data: bytes) -> Float64:
    return Float64(_F64.unpack_from(data, 4)[0])


def _vector3_stamped(data: bytes) -> Vector3Stamped:
    header, o = _header(data)
    o += -(o - 4) % 8
    return Vector3Stamped(header, Vector3(*_3F64.unpack_from(data, o)))


#: ``pkg/msg/Type`` -> fast decoder (little-endian CDR bytes -> message object).
FAST_DECODERS: dict[str, Callable[[bytes], Any]] = {
    m.JOINT_STATE: _joint_state, m.FLUID_PRESSURE: _fluid_pressure, m.TEMPERATURE: _temperature,
    m.FLOAT64: _float64, m.VECTOR3_STAMPED: _vector3_stamped}


def decode_fast(msgtype: str, data: bytes) -> Any | None:
    """The message as a slotted object, or None (another type, big-endian or malformed: use the generic decoder)."""
    fast = FAST_DECODERS.get(msgtype)
    if fast is None or data[:2] != _LE:
        return None
    try:
        return fast(data)
    except (struct.error, ValueError, IndexError, UnicodeDecodeError):
        return None
