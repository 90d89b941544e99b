r"""Which oil temperature the model runs at: the measured one while it is fresh, else the config's reference.

The bench's ``oil_temperature`` input is optional.  Its samples are validated
(finite, within the range of the oil laws, −40…200 °C) and low-pass filtered
by the :class:`~gerotor_twin.twin.input_book.InputBook` like every input.  At
each grid point :class:`OilTemperature` gives the model either that filtered
value (fresh: not older than ``stale_timeout_s``) or ``None`` = the config's
reference temperature (``oil.reference_temperature_c``).  Falling back after
measurements were received (the sensor went stale) is a WARN event and keeps
the model's status WARN on ``/diagnostics`` until fresh samples return; no
sensor at all is normal (reported, not warned).

A bench thermometer in the oil line lags the oil (a first-order lag of a few
seconds is typical).  While the oil warms up, the reading is then low by
``tau × dT/dt``: ≈ 1.3 K at 0.4 K/s and τ = 3 s, which is ≈ 5 % of viscosity
and of the leakage the model predicts, enough to bias a health estimate.  With
``oil_sensor_tau_s`` = τ > 0 the model runs at the inverse of that lag,

.. math:: T = T_m + \tau \, \frac{dT_m}{dt},

with :math:`dT_m/dt` the least-squares slope of the readings over the last
``max(1 s, 2 τ)`` (recomputed when a reading arrives).  A slope over 2 τ is
itself late by ≈ τ, which for a warm-up time constant ≫ τ costs a second-order
error ``τ² d²T/dt²`` (≈ 0.05 K in the example above), and noise σ is amplified
to ≈ σ·τ·√(12 / (n W²)) for n readings in the window W.
"""
from __future__ import annotations

from collections import deque

import numpy as np

from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.settings import NS
from gerotor_twin.units import celsius_to_kelvin, kelvin_to_celsius

__all__ = ["OilTemperature", "MEASURED", "REFERENCE", "STALE", "least_squares_slope"]

MEASURED = "measured"                  #: the filtered bench value is used
REFERENCE = "reference (none received)"   #: no sample yet: the config's reference temperature
STALE = "reference (measurement stale)"   #: samples stopped: back to the reference temperature (WARN)


def least_squares_slope(t: np.ndarray, v: np.ndarray) -> float:
    """Least-squares slope of ``v`` over ``t`` [units of v per unit of t]; 0 with fewer than 3 points."""
    t = np.asarray(t, dtype=float)
    v = np.asarray(v, dtype=float)
    if t.size < 3:
        return 0.0
    tc = t - t.mean()
    den = float(tc @ tc)
    return float(tc @ (v - v.mean()) / den) if den > 0 else 0.0


class OilTemperature:
    """The oil temperature applying at each grid point, with its source.

    Parameters
    ----------
    reference_k : float
        The config's reference temperature [K].
    stale_timeout_s : float
        Age beyond which a sample is no longer used [s].
    events : EventLog
        Where the fall-back WARN goes.
    sensor_tau_s : float
        Time constant of the thermometer's lag [s] (0: no compensation).
    """

    def __init__(self, reference_k: float, stale_timeout_s: float, events: EventLog, sensor_tau_s: float = 0.0):
        self.reference_k = float(reference_k)
        self.sensor_tau_s = float(sensor_tau_s)
        self._window_ns = int(max(1.0, 2.0 * self.sensor_tau_s) * NS)
        self._readings: deque[tuple[int, float]] = deque()    # (receive ns, filtered °C) of the window
        self._lead_c = 0.0                                    # τ·dT/dt of the last window [K]
        self._stale_ns = int(stale_timeout_s * NS)
        self._events = events
        self.source = REFERENCE
        self.value_k = self.reference_k
        self.fallbacks = 0             #: times the model fell back to the reference after measurements

    def at(self, g_ns: int, sample: tuple[float, int] | None) -> float | None:
        """The temperature [K] for grid point ``g_ns`` (None: reference) from the filtered sample (°C, t_ns)."""
        if sample is not None and g_ns - sample[1] <= self._stale_ns:
            self.source, self.value_k = MEASURED, celsius_to_kelvin(sample[0] + self._lead(sample))
            return self.value_k
        if sample is not None and self.source == MEASURED:
            self.fallbacks += 1
            self._events.report("oil_temperature", "stale", 1,
                                f"oil_temperature stale ({(g_ns - sample[1]) / NS:.3g} s old): the model uses the "
                                f"reference temperature {kelvin_to_celsius(self.reference_k):g} °C until samples "
                                "return", g_ns)
        self.source = STALE if sample is not None else REFERENCE
        self.value_k = self.reference_k
        return None

    def _lead(self, sample: tuple[float, int]) -> float:
        """``τ × dT/dt`` [K] from the readings of the last window, updated when ``sample`` is new."""
        if self.sensor_tau_s == 0.0:
            return 0.0
        r = self._readings
        if not r or sample[1] > r[-1][0]:
            r.append((sample[1], sample[0]))
            while sample[1] - r[0][0] > self._window_ns:
                r.popleft()
            t = np.array([x[0] - r[0][0] for x in r], dtype=float) / NS
            self._lead_c = self.sensor_tau_s * least_squares_slope(t, np.array([x[1] for x in r]))
        elif sample[1] < r[-1][0]:          # the source restarted (stamps back): start a new window
            r.clear()
            r.append((sample[1], sample[0]))
            self._lead_c = 0.0
        return self._lead_c

    @property
    def warn(self) -> bool:
        """True while the model runs at the reference temperature because the measurement went stale."""
        return self.source == STALE

    def report(self) -> dict:
        """``oil_temperature_c`` used by the model [°C], its ``source``, the fall-back count and the lag
        compensation applied [K]."""
        return {"oil_temperature_c": kelvin_to_celsius(self.value_k), "oil_temperature_source": self.source,
                "oil_temperature_fallbacks": self.fallbacks, "oil_temperature_lead_k": self._lead_c}
