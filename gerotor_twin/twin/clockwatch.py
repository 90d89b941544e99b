"""Is the node's clock advancing?  (``/clock`` stopped under ``use_sim_time``.)

Under ``use_sim_time`` the node's clock is the last ``/clock`` message: when
the publisher of ``/clock`` stops (a paused or finished replay, a crashed
simulator), nothing is integrated or published and a ROS-time timer would not
fire either.  The node therefore runs ``/diagnostics`` on a wall-clock
(steady) timer and asks :class:`ClockWatch`, at each report, whether the
clock moved: unchanged for longer than ``stall_after_s`` of wall time is
``stalled`` (WARN on ``/diagnostics``, stamped with the last clock time, and
once per stall on the console: :attr:`ClockState.started`),
a clock of 0 is ``waiting`` (no ``/clock`` yet).  Pure Python: the caller
passes both times.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["ClockWatch", "ClockState"]


@dataclass(frozen=True)
class ClockState:
    """What :meth:`ClockWatch.update` found."""
    status: str                 #: ``ok`` | ``waiting`` (clock 0) | ``stalled``
    unchanged_s: float          #: wall time since the clock last moved [s]
    clock_ns: int               #: the clock's value [ns]
    started: bool = False       #: this update found the stall (once per stall: the caller logs it then)

    def describe(self) -> str:
        if self.status == "waiting":
            return f"waiting for /clock (none received for {self.unchanged_s:.1f} s)"
        if self.status == "stalled":
            return (f"clock stalled: /clock has not advanced for {self.unchanged_s:.1f} s of wall time (last "
                    f"{self.clock_ns / 1e9:.3f} s); nothing is integrated or published until it moves")
        return "ok"


class ClockWatch:
    """Tracks when the watched clock last changed, in wall (steady) time.

    Parameters
    ----------
    stall_after_s : float
        Wall time without a change after which the clock is ``stalled`` [s].
    """

    def __init__(self, stall_after_s: float):
        self.stall_after_s = float(stall_after_s)
        self._last_clock: int | None = None
        self._changed_at: float | None = None
        self._in_stall = False
        self.stalls = 0                       #: times the clock went from moving to stalled

    def update(self, clock_ns: int, wall_s: float) -> ClockState:
        """Record the clock's value now (``wall_s`` from a monotonic clock [s]) and classify it."""
        if clock_ns != self._last_clock or self._changed_at is None:
            self._last_clock = clock_ns
            self._changed_at = wall_s
            self._in_stall = False
        unchanged = wall_s - self._changed_at
        if clock_ns == 0:
            return ClockState("waiting", unchanged, 0)
        if unchanged > self.stall_after_s:
            started = not self._in_stall
            self.stalls += started
            self._in_stall = True
            return ClockState("stalled", unchanged, clock_ns, started)
        return ClockState("ok", unchanged, clock_ns)
