"""Dict form of the project's ROS 2 messages, for :class:`~gerotor_twin.io.mcap_log.McapLog`.

Pure Python (no rclpy): each builder returns the nested ``dict`` that
:func:`gerotor_twin.io.codec.encode` turns into CDR, with field names exactly
as in the ``.msg`` definitions.  SI units throughout (REP 103); time stamps
are integer nanoseconds of the node's clock.

=====================================  ===================================
builder                                message type
=====================================  ===================================
:func:`stamp_from_ns`, :func:`header`  builtin_interfaces/Time, std_msgs/Header
:func:`joint_state`                    sensor_msgs/msg/JointState
:func:`fluid_pressure`                 sensor_msgs/msg/FluidPressure
:func:`temperature`                    sensor_msgs/msg/Temperature
:func:`float64`                        std_msgs/msg/Float64
:func:`float64_multiarray`             std_msgs/msg/Float64MultiArray
:func:`vector3_stamped`                geometry_msgs/msg/Vector3Stamped
:func:`diagnostic_array` (+ status,    diagnostic_msgs/msg/DiagnosticArray
key_value)
:func:`clock`                          rosgraph_msgs/msg/Clock
=====================================  ===================================
"""
from __future__ import annotations

import math
import operator
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from gerotor_twin.errors import InputError

__all__ = [
    "JOINT_STATE", "FLUID_PRESSURE", "TEMPERATURE", "FLOAT64", "FLOAT64_MULTIARRAY",
    "VECTOR3_STAMPED", "DIAGNOSTIC_ARRAY", "CLOCK", "PUMP_FRAME",
    "DIAG_OK", "DIAG_WARN", "DIAG_ERROR", "DIAG_STALE",
    "stamp_from_ns", "ns_from_stamp", "header", "joint_state", "fluid_pressure", "temperature",
    "float64", "multiarray_layout", "float64_multiarray", "vector3_stamped",
    "key_value", "diagnostic_status", "diagnostic_array", "clock",
]

JOINT_STATE = "sensor_msgs/msg/JointState"
FLUID_PRESSURE = "sensor_msgs/msg/FluidPressure"
TEMPERATURE = "sensor_msgs/msg/Temperature"
FLOAT64 = "std_msgs/msg/Float64"
FLOAT64_MULTIARRAY = "std_msgs/msg/Float64MultiArray"
VECTOR3_STAMPED = "geometry_msgs/msg/Vector3Stamped"
DIAGNOSTIC_ARRAY = "diagnostic_msgs/msg/DiagnosticArray"
CLOCK = "rosgraph_msgs/msg/Clock"

#: Frame of the outer-gear eccentricity (pump housing, fixed).
PUMP_FRAME = "pump_housing"

#: diagnostic_msgs/DiagnosticStatus levels.
DIAG_OK, DIAG_WARN, DIAG_ERROR, DIAG_STALE = 0, 1, 2, 3

_NS = 1_000_000_000
_INT32 = 2**31


def stamp_from_ns(ns: int) -> dict[str, int]:
    """builtin_interfaces/Time from a time [ns] (floor: -1.7 s -> sec -2, nanosec 3e8).

    Raises
    ------
    InputError
        If ``ns`` is not an integer or ``sec`` leaves the int32 range.
    """
    try:
        ns = operator.index(ns)
    except TypeError:
        raise InputError("stamp_ns", ns, "an integer number of nanoseconds") from None
    sec, nanosec = divmod(ns, _NS)
    if not -_INT32 <= sec < _INT32:
        raise InputError("stamp_ns", ns, f"[{-_INT32 * _NS}, {_INT32 * _NS}) ns (int32 seconds)")
    return {"sec": sec, "nanosec": nanosec}


def ns_from_stamp(stamp: Any) -> int:
    """Time [ns] of a builtin_interfaces/Time given as dict or object (inverse of :func:`stamp_from_ns`)."""
    if isinstance(stamp, Mapping):
        return int(stamp["sec"]) * _NS + int(stamp["nanosec"])
    return int(stamp.sec) * _NS + int(stamp.nanosec)


def header(stamp_ns: int, frame_id: str = "") -> dict[str, Any]:
    """std_msgs/Header: time stamp [ns] and frame."""
    return {"stamp": stamp_from_ns(stamp_ns), "frame_id": str(frame_id)}


def _floats(field: str, values: Iterable[float] | float) -> list[float]:
    try:
        arr = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputError(field, values, "numbers") from None
    return arr.ravel().tolist()


def _float(field: str, value: float) -> float:
    try:
        return float(value)
    except (TypeError, ValueError):
        raise InputError(field, value, "a number") from None


def joint_state(stamp_ns: int, *, name: Sequence[str] = (), position: Iterable[float] = (),
                velocity: Iterable[float] = (), effort: Iterable[float] = (),
                frame_id: str = "") -> dict[str, Any]:
    """sensor_msgs/JointState (the bench's shaft: ``velocity[0]`` [rad/s], ``position[0]`` [rad]).

    Non-empty arrays must have as many entries as ``name`` (message convention).
    """
    names = [str(n) for n in name]
    arrays = {k: _floats(f"joint_state.{k}", v)
              for k, v in (("position", position), ("velocity", velocity), ("effort", effort))}
    for k, v in arrays.items():
        if v and len(v) != len(names):
            raise InputError(f"joint_state.{k}", v, f"empty or {len(names)} values (one per name)")
    return {"header": header(stamp_ns, frame_id), "name": names, **arrays}


def fluid_pressure(stamp_ns: int, pressure_pa: float, *, variance: float = 0.0,
                   frame_id: str = "") -> dict[str, Any]:
    """sensor_msgs/FluidPressure: absolute pressure [Pa], variance [Pa²] (0 = unknown)."""
    return {"header": header(stamp_ns, frame_id),
            "fluid_pressure": _float("fluid_pressure", pressure_pa),
            "variance": _float("variance", variance)}


def temperature(stamp_ns: int, temperature_c: float, *, variance: float = 0.0,
                frame_id: str = "") -> dict[str, Any]:
    """sensor_msgs/Temperature: temperature [°C], variance [K²] (0 = unknown)."""
    return {"header": header(stamp_ns, frame_id),
            "temperature": _float("temperature", temperature_c),
            "variance": _float("variance", variance)}


def float64(value: float) -> dict[str, float]:
    """std_msgs/Float64 (e.g. delivery flow [m³/s])."""
    return {"data": _float("data", value)}


def multiarray_layout(labels: Sequence[str], sizes: Sequence[int], data_offset: int = 0) -> dict[str, Any]:
    """std_msgs/MultiArrayLayout, row major: ``stride[i] = prod(sizes[i:])``.

    Raises
    ------
    InputError
        If ``labels`` and ``sizes`` differ in length or a size is negative.
    """
    if len(labels) != len(sizes):
        raise InputError("layout.labels", list(labels), f"{len(sizes)} labels (one per dimension)")
    dims = []
    for i, (label, size) in enumerate(zip(labels, sizes)):
        if isinstance(size, bool) or int(size) != size or size < 0:
            raise InputError(f"layout.dim[{i}].size", size, "an integer >= 0")
        dims.append({"label": str(label), "size": int(size),
                     "stride": int(math.prod(int(s) for s in sizes[i:]))})
    return {"dim": dims, "data_offset": int(data_offset)}


def float64_multiarray(data: Any, labels: Sequence[str] = ("chamber",)) -> dict[str, Any]:
    """std_msgs/Float64MultiArray with a labelled row-major layout.

    Parameters
    ----------
    data : array_like
        N-D values (units as documented for the topic); its shape gives the dim sizes.
    labels : sequence of str
        One label per dimension, e.g. ``("chamber",)`` or ``("sample", "angle_p")``.

    Returns
    -------
    dict
        ``data`` is a 1-D float64 array (a copy), not a list: a waveform's 2880
        values as Python floats cost ≈ 0.09 ms per message to make and to encode
        again (docs/performance.md).
    """
    arr = np.asarray(data, dtype=np.float64)
    if arr.ndim == 0:
        arr = arr.reshape(1)
    if arr.ndim != len(labels):
        raise InputError("float64_multiarray.labels", list(labels),
                          f"{arr.ndim} labels for data of shape {arr.shape}")
    return {"layout": multiarray_layout(labels, arr.shape), "data": arr.ravel().copy()}


def vector3_stamped(stamp_ns: int, x: float, y: float, z: float = 0.0, *,
                    frame_id: str = PUMP_FRAME) -> dict[str, Any]:
    """geometry_msgs/Vector3Stamped (outer-gear eccentricity [m] in ``pump_housing``)."""
    return {"header": header(stamp_ns, frame_id),
            "vector": {"x": _float("vector.x", x), "y": _float("vector.y", y),
                       "z": _float("vector.z", z)}}


def key_value(key: str, value: Any) -> dict[str, str]:
    """diagnostic_msgs/KeyValue; floats (also NumPy) are written in shortest round-trip form."""
    if isinstance(value, (float, np.floating)):
        text = repr(float(value))
    else:
        text = str(value)
    return {"key": str(key), "value": text}


def diagnostic_status(level: int, name: str, message: str = "", *, hardware_id: str = "",
                      values: Mapping[str, Any] | Sequence[Mapping[str, str]] = ()) -> dict[str, Any]:
    """diagnostic_msgs/DiagnosticStatus; ``level`` is one of :data:`DIAG_OK` ... :data:`DIAG_STALE`."""
    if level not in (DIAG_OK, DIAG_WARN, DIAG_ERROR, DIAG_STALE):
        raise InputError("diagnostic_status.level", level, "0 (OK) | 1 (WARN) | 2 (ERROR) | 3 (STALE)")
    kvs = ([key_value(k, v) for k, v in values.items()] if isinstance(values, Mapping)
           else [key_value(kv["key"], kv["value"]) for kv in values])
    return {"level": int(level), "name": str(name), "message": str(message),
            "hardware_id": str(hardware_id), "values": kvs}


def diagnostic_array(stamp_ns: int, statuses: Sequence[Mapping[str, Any]]) -> dict[str, Any]:
    """diagnostic_msgs/DiagnosticArray of :func:`diagnostic_status` dicts."""
    return {"header": header(stamp_ns), "status": list(statuses)}


def clock(stamp_ns: int) -> dict[str, Any]:
    """rosgraph_msgs/Clock (``/clock`` under replay)."""
    return {"clock": stamp_from_ns(stamp_ns)}
