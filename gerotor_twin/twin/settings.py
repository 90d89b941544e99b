"""Settings of the twin core (:class:`TwinSettings`): time grid, lag, staleness, filtering.

All times are in seconds at this interface (SI) and kept as integer
nanoseconds inside the core.  These defaults are the only ones: the node's parameters that set
them take their defaults from here (:data:`gerotor_twin.ros.params.CORE_SETTINGS`), and
``config/twin.yaml`` repeats them (a test checks that it agrees).  Every field is validated in ``__post_init__``
and a bad value raises :class:`~gerotor_twin.errors.InputError` naming the
field, the value and the allowed range.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from gerotor_twin.errors import InputError, check_range
from gerotor_twin.hydraulics.meter import FLOW_METERS

__all__ = ["TwinSettings", "NS", "oil_sensor_tau_arg"]

NS = 1_000_000_000


@dataclass(frozen=True)
class TwinSettings:
    """How the twin core samples inputs, advances the model and emits outputs.

    Parameters
    ----------
    sample_period_s : float
        Input sampling grid [s]: over every cell ``[k·Ts, (k+1)·Ts)`` of the
        clock the model runs with the (filtered) input values received at or
        before ``k·Ts`` (zero-order hold).  The grid is anchored at clock time 0,
        so results do not depend on when ticks happen.  Also the finest output
        time resolution.  (0.0001, 0.1] s, default 0.005 s.
    publish_period_s : float
        Period of the instantaneous outputs (chamber pressures, delivery flow,
        eccentricity, tooth gaps) [s]; a whole multiple of ``sample_period_s``.
        Default 0.005 s (200 Hz).
    max_span_s : float
        Lag policy: at most this much clock time is integrated per tick [s];
        an older backlog is skipped (see :mod:`gerotor_twin.twin.core`).
        ``math.inf`` disables skipping (offline runs).  Default 0.25 s.
    stale_timeout_s : float
        A required input (shaft speed, delivery pressure) older than this [s]
        freezes the model until a fresh sample arrives; a stale optional input
        falls back to its default.  Default 0.5 s.
    filter_tau_s : float
        Time constant of a first-order low-pass applied to every accepted input
        sample, at its receive time [s]; 0 = no filtering.  Default 0.
    stamp_restart_s : float
        A header stamp older than the last accepted one by more than this [s]
        is taken as a restart of the source (accepted, reported); a smaller step
        back, or an equal stamp, is rejected as out-of-order / duplicate.
        Default 1 s.
    stamp_ahead_s : float
        A header stamp ahead of its receive time by more than this beyond the
        stream's usual offset is implausible: that sample alone is rejected
        (``future_stamp``), the stream goes on [s].  Under ``use_sim_time`` it
        must exceed the ``/clock`` step in bag time.  Default 0.5 s.
    stamp_rebase_samples : int
        After this many consecutive samples rejected for their stamp (out of
        order or ahead) that agree with each other, the stamp order re-anchors
        on them: one bad stamp blocks at most this many minus one good samples.
        Default 3.
    negative_speed_tolerance_rad_s : float
        Shaft speeds in ``[-tol, 0)`` (sensor noise at standstill) are clamped to
        0; below ``-tol`` they are rejected [rad/s].  Default 0.5 rad/s.
    waveform_every : int
        Emit the chamber-pressure waveform every this many complete revolutions
        (0 = never).  Default 1.
    waveform_samples : int
        Number of shaft-angle samples of the waveform over one revolution
        (interpolated from the integration steps; 360 = 1°, the default output step).
    error_report_period_s : float
        Rate limit of input-error events per (input, reason) [s]; counts are
        never rate-limited.  Default 1 s.
    oil_sensor_tau_s : float
        Time constant of the bench's oil thermometer (first-order lag) [s]: the
        model runs at the measured value plus ``tau`` × its rate of change, the
        inverse of the lag (:mod:`gerotor_twin.twin.oil_temperature`).  0 = use the
        reading as it is (default).  [0, 120] s.
    flow_meter : str
        Where the bench's flow meter reads (:mod:`gerotor_twin.hydraulics.meter`): ``delivery`` (at the
        delivery pressure, as the twin's delivery flow; default) or ``atmospheric`` (in the return line: each
        reading is taken to the delivery pressure's volume, ρ(p_atm)/ρ(p_d) at the latest delivery pressure
        read, before the residual and the health monitor compare it; the log keeps the reading as received).
    """

    sample_period_s: float = 0.005
    publish_period_s: float = 0.005
    max_span_s: float = 0.25
    stale_timeout_s: float = 0.5
    filter_tau_s: float = 0.0
    stamp_restart_s: float = 1.0
    stamp_ahead_s: float = 0.5
    stamp_rebase_samples: int = 3
    negative_speed_tolerance_rad_s: float = 0.5
    waveform_every: int = 1
    waveform_samples: int = 360
    error_report_period_s: float = 1.0
    oil_sensor_tau_s: float = 0.0
    flow_meter: str = "delivery"

    def __post_init__(self) -> None:
        check_range("sample_period_s", self.sample_period_s, 1e-4, 0.1, lo_open=True, unit="s")
        check_range("publish_period_s", self.publish_period_s, self.sample_period_s, 10.0, unit="s")
        ratio = self.publish_period_s / self.sample_period_s
        if abs(ratio - round(ratio)) > 1e-6:
            raise InputError("publish_period_s", self.publish_period_s,
                             f"a whole multiple of sample_period_s = {self.sample_period_s:g} s")
        if not (isinstance(self.max_span_s, (int, float)) and self.max_span_s == math.inf):
            check_range("max_span_s", self.max_span_s, self.sample_period_s, 3600.0, unit="s (or inf)")
        check_range("stale_timeout_s", self.stale_timeout_s, 0.0, 3600.0, lo_open=True, unit="s")
        check_range("filter_tau_s", self.filter_tau_s, 0.0, 60.0, unit="s")
        check_range("stamp_restart_s", self.stamp_restart_s, 0.0, 3600.0, unit="s")
        check_range("stamp_ahead_s", self.stamp_ahead_s, 0.0, 3600.0, lo_open=True, unit="s")
        check_range("negative_speed_tolerance_rad_s", self.negative_speed_tolerance_rad_s, 0.0, 100.0,
                    unit="rad/s")
        for name, lo, hi in (("waveform_every", 0, 10_000), ("waveform_samples", 8, 100_000),
                             ("stamp_rebase_samples", 1, 1000)):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int) or not lo <= v <= hi:
                raise InputError(name, v, f"an integer in [{lo}, {hi}]")
        check_range("error_report_period_s", self.error_report_period_s, 0.0, 3600.0, unit="s")
        check_range("oil_sensor_tau_s", self.oil_sensor_tau_s, 0.0, 120.0, unit="s")
        if self.flow_meter not in FLOW_METERS:
            raise InputError("flow_meter", self.flow_meter, " | ".join(FLOW_METERS))

    # integer-nanosecond views used by the core
    @property
    def sample_ns(self) -> int:
        return int(round(self.sample_period_s * NS))

    @property
    def publish_every(self) -> int:
        """Publish period in sample cells."""
        return int(round(self.publish_period_s / self.sample_period_s))

    @property
    def max_span_ns(self) -> float:
        return math.inf if self.max_span_s == math.inf else int(round(self.max_span_s * NS))

    def as_dict(self) -> dict:
        """Plain dict (for MCAP metadata and reports)."""
        return asdict(self)


def oil_sensor_tau_arg(value: float, flag: str = "--oil-sensor-tau") -> float:
    """``value`` [s] checked as :attr:`TwinSettings.oil_sensor_tau_s`; the error names the command-line ``flag``."""
    try:
        TwinSettings(oil_sensor_tau_s=value)
    except InputError as exc:
        raise InputError(flag, value, exc.allowed) from None
    return value
