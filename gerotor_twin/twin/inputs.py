"""Bench inputs of the twin: what they are, how a message gives a sample, per-input history.

=====================  ==============================  =====================  ========
kind                   message (DESIGN.md)             value                  required
=====================  ==============================  =====================  ========
``shaft_speed``        sensor_msgs/JointState          ``velocity[0]`` rad/s  yes
``delivery_pressure``  sensor_msgs/FluidPressure       absolute Pa            yes
``suction_pressure``   sensor_msgs/FluidPressure       absolute Pa            no
``delivery_flow``      std_msgs/Float64                m³/s (measured)        no
``oil_temperature``    sensor_msgs/Temperature         °C                     no
=====================  ==============================  =====================  ========

A message is turned into ``(value, stamp_ns)`` by :func:`sample_from_message`
(``stamp_ns`` is the header stamp: ``None`` if the message has no header,
``0`` for a zero stamp, which the core counts and treats as unstamped).
:class:`InputChannel` keeps the accepted samples of one input on the sample
grid (one entry per grid cell, the last one received in it), the stamp checks
(a :class:`~gerotor_twin.twin.stamps.StampGuard`) and the counters.
"""
from __future__ import annotations

import collections
import math
from dataclasses import dataclass
from collections.abc import Mapping
from typing import Any

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.twin.stamps import StampGuard

__all__ = ["InputSpec", "INPUTS", "REQUIRED", "sample_from_message", "InputChannel", "REASONS"]


@dataclass(frozen=True)
class InputSpec:
    """One bench input: default topic, message type, field, unit, whether required."""
    kind: str
    topic: str
    msgtype: str
    field: str
    unit: str
    required: bool


INPUTS: dict[str, InputSpec] = {s.kind: s for s in (
    InputSpec("shaft_speed", "bench/shaft_speed", m.JOINT_STATE, "velocity[0]", "rad/s", True),
    InputSpec("delivery_pressure", "bench/delivery_pressure", m.FLUID_PRESSURE, "fluid_pressure", "Pa", True),
    InputSpec("suction_pressure", "bench/suction_pressure", m.FLUID_PRESSURE, "fluid_pressure", "Pa", False),
    InputSpec("delivery_flow", "bench/delivery_flow", m.FLOAT64, "data", "m³/s", False),
    InputSpec("oil_temperature", "bench/oil_temperature", m.TEMPERATURE, "temperature", "°C", False),
)}

#: The inputs without which the model is held.
REQUIRED = tuple(k for k, s in INPUTS.items() if s.required)

#: Reasons a sample is rejected (keys of the per-input counters).
REASONS = ("malformed", "nonfinite", "negative", "out_of_range", "duplicate_stamp", "out_of_order_stamp",
           "future_stamp")


def _get(msg: Any, name: str) -> Any:
    if isinstance(msg, Mapping):
        return msg[name]
    return getattr(msg, name)


def sample_from_message(kind: str, msg: Any) -> tuple[float, int | None]:
    """Value and header stamp of a decoded input message (dict or message object).

    Parameters
    ----------
    kind : str
        One of :data:`INPUTS`.
    msg : dict or object
        Decoded message of the type in :data:`INPUTS` (rclpy message, ``mcap_ros2``
        namespace, or a :mod:`gerotor_twin.io.messages` dict).

    Returns
    -------
    value : float
        In the unit of the input (may be NaN: validation is the channel's job).
    stamp_ns : int or None
        Header stamp [ns]; ``None`` for Float64 (no header), ``0`` for a zero stamp.

    Raises
    ------
    InputError
        Unknown kind, or the message lacks the field (e.g. empty ``velocity``).
    """
    if kind not in INPUTS:
        raise InputError("input", kind, " | ".join(INPUTS))
    try:
        if kind == "shaft_speed":
            vel = _get(msg, "velocity")
            if len(vel) == 0:
                raise InputError("shaft_speed.velocity", list(vel), "at least one value [rad/s]")
            value = vel[0]
        elif kind == "delivery_flow":
            value = _get(msg, "data")
        elif kind == "oil_temperature":
            value = _get(msg, "temperature")
        else:
            value = _get(msg, "fluid_pressure")
        stamp = None
        if kind != "delivery_flow":
            stamp = m.ns_from_stamp(_get(_get(msg, "header"), "stamp"))
    except (KeyError, AttributeError, TypeError) as exc:
        raise InputError(f"{kind}", type(msg).__name__, f"a {INPUTS[kind].msgtype}",
                         f"{type(exc).__name__}: {exc}") from None
    try:
        value = float(value)
    except (TypeError, ValueError):
        raise InputError(f"{kind}.{INPUTS[kind].field}", value, "a number") from None
    return value, stamp


class InputChannel:
    """Accepted samples of one input on the sample grid, stamp order and counters.

    Not thread-safe by itself; :class:`~gerotor_twin.twin.input_book.InputBook` locks.
    """

    def __init__(self, spec: InputSpec, sample_ns: int, tau_s: float, guard: StampGuard | None = None):
        self.spec = spec
        self.guard = guard or StampGuard(restart_ns=1_000_000_000, ahead_ns=500_000_000)
        self._sample_ns = sample_ns
        self._tau = tau_s
        self.cells: collections.deque[tuple[int, int, float, float]] = collections.deque()
        #: (grid cell index from which it applies, receive ns, filtered value, raw value)
        self.last_receive: int | None = None
        self.accepted = 0
        self.clamped = 0
        self.rejected = dict.fromkeys(REASONS, 0)
        self.zero_stamps = 0
        self.last_error: str = ""

    @property
    def last_stamp(self) -> int | None:
        """Last accepted header stamp [ns]; setting None forgets the stamp order and offset."""
        return self.guard.last_stamp

    @last_stamp.setter
    def last_stamp(self, value: int | None) -> None:
        if value is None:
            self.guard.reset()
        else:
            self.guard.last_stamp = value

    @property
    def stamp_restarts(self) -> int:
        return self.guard.restarts

    @property
    def stamp_rebases(self) -> int:
        return self.guard.rebases

    def clear(self) -> None:
        """Forget samples and stamp order (clock jump back); counters are kept."""
        self.cells.clear()
        self.guard.reset()
        self.last_receive = None

    def check_stamp(self, stamp_ns: int | None, receive_ns: int) -> str | None:
        """Verdict of :meth:`StampGuard.check` (``None`` for an unstamped sample: no check)."""
        if stamp_ns is None:
            return None
        return self.guard.check(stamp_ns, receive_ns)

    def add(self, value: float, stamp_ns: int | None, receive_ns: int, verdict: str | None = None) -> None:
        """Store an accepted sample (filtered) in the cell where it starts to apply."""
        if self.last_receive is not None and receive_ns < self.last_receive:
            self.cells.clear()         # receive clock went back: old samples belong to another timeline
        filt = value
        if self._tau > 0 and self.cells:
            _, r0, y0, _ = self.cells[-1]
            a = 1.0 - math.exp(-max(receive_ns - r0, 0) / (self._tau * 1e9))
            filt = y0 + a * (value - y0)
        cell = -(-receive_ns // self._sample_ns)           # ceil: first grid point at or after reception
        if self.cells and self.cells[-1][0] == cell:
            self.cells.pop()
        self.cells.append((cell, receive_ns, filt, value))
        if len(self.cells) > 1_000_000:                    # bounded memory whatever the backlog
            self.cells.popleft()
        if stamp_ns is not None:
            self.guard.accept(stamp_ns, receive_ns, verdict)
        self.last_receive = receive_ns
        self.accepted += 1

    def at(self, cell: int) -> tuple[float, int] | None:
        """(filtered value, receive ns) applying at grid point ``cell``, or None if nothing yet.

        Drops entries older than the one that applies (cells are visited in order).
        """
        c = self.cells
        while len(c) > 1 and c[1][0] <= cell:
            c.popleft()
        if not c or c[0][0] > cell:
            return None
        return c[0][2], c[0][1]

    def latest(self) -> tuple[float, int] | None:
        """Last accepted (filtered value, receive ns), whatever the grid."""
        if not self.cells:
            return None
        return self.cells[-1][2], self.cells[-1][1]

    def drop_after(self, receive_ns: int) -> None:
        """Forget samples received after ``receive_ns`` (clock jump back detected at a tick)."""
        while self.cells and self.cells[-1][1] > receive_ns:
            self.cells.pop()
        if not self.cells:
            self.last_receive = None
            self.guard.reset()
