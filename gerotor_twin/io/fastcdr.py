"""Fast CDR encoding of std_msgs/Float64MultiArray (NumPy ``tobytes`` for the data).

The generic encoder (:func:`gerotor_twin.io.codec.encode`) packs a
720 × 8 waveform in ~5 ms; this one in ~0.05 ms and yields the same bytes
(tested against the codec): little-endian CDR with the 4-byte encapsulation
header, alignment relative to the end of that header.
"""
from __future__ import annotations

import struct
from typing import Any

import numpy as np

from gerotor_twin.io import messages as m
from gerotor_twin.io.codec import encode as generic_encode

__all__ = ["encode_float64_multiarray", "encode"]


def _pad(buf: bytearray, align: int) -> None:
    n = (len(buf) - 4) % align
    if n:
        buf.extend(b"\x00" * (align - n))


def encode_float64_multiarray(msg: dict) -> bytes:
    """CDR bytes of a :func:`gerotor_twin.io.messages.float64_multiarray` dict."""
    buf = bytearray(b"\x00\x01\x00\x00")
    dims = msg["layout"]["dim"]
    buf += struct.pack("<I", len(dims))
    for d in dims:
        label = str(d["label"]).encode("utf-8") + b"\x00"
        _pad(buf, 4)
        buf += struct.pack("<I", len(label)) + label
        _pad(buf, 4)
        buf += struct.pack("<II", int(d["size"]), int(d["stride"]))
    _pad(buf, 4)
    data = np.asarray(msg["data"], dtype="<f8")
    buf += struct.pack("<II", int(msg["layout"]["data_offset"]), data.size)
    if data.size:
        _pad(buf, 8)
        buf += data.tobytes()
    return bytes(buf)


def encode(msgtype: str, msg: Any) -> bytes:
    """Fast path for Float64MultiArray, the project codec for everything else."""
    if msgtype == m.FLOAT64_MULTIARRAY:
        return encode_float64_multiarray(msg)
    return generic_encode(msgtype, msg)
