"""Which oil temperature the model runs at: the measured one while it is fresh, else the config's reference.

The bench's ``oil_temperature`` input is optional.  Its samples are validated
(finite, within the range of the oil laws, −40…200 °C) and low-pass filtered
by the :class:`~gerotor_twin.twin.input_book.InputBook` like every input.  At
each grid point :class:`OilTemperature` gives the model either that filtered
value (fresh: not older than ``stale_timeout_s``) or ``None`` = the config's
reference temperature (``oil.reference_temperature_c``).  Falling back after
measurements were received (the sensor went stale) is a WARN event and keeps
the model's status WARN on ``/diagnostics`` until fresh samples return; no
sensor at all is normal (reported, not warned).
"""
from __future__ import annotations

from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.settings import NS
from gerotor_twin.units import celsius_to_kelvin, kelvin_to_celsius

__all__ = ["OilTemperature", "MEASURED", "REFERENCE", "STALE"]

MEASURED = "measured"                  #: the filtered bench value is used
REFERENCE = "reference (none received)"   #: no sample yet: the config's reference temperature
STALE = "reference (measurement stale)"   #: samples stopped: back to the reference temperature (WARN)


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
    """

    def __init__(self, reference_k: float, stale_timeout_s: float, events: EventLog):
        self.reference_k = float(reference_k)
        self._stale_ns = int(stale_timeout_s * NS)
        self._events = events
        self.source = REFERENCE
        self.value_k = self.reference_k
        self.fallbacks = 0             #: times the model fell back to the reference after measurements

    def at(self, g_ns: int, sample: tuple[float, int] | None) -> float | None:
        """The temperature [K] for grid point ``g_ns`` (None: reference) from the filtered sample (°C, t_ns)."""
        if sample is not None and g_ns - sample[1] <= self._stale_ns:
            self.source, self.value_k = MEASURED, celsius_to_kelvin(sample[0])
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

    @property
    def warn(self) -> bool:
        """True while the model runs at the reference temperature because the measurement went stale."""
        return self.source == STALE

    def report(self) -> dict:
        """``oil_temperature_c`` used by the model [°C], its ``source`` and the fall-back count."""
        return {"oil_temperature_c": kelvin_to_celsius(self.value_k), "oil_temperature_source": self.source,
                "oil_temperature_fallbacks": self.fallbacks}
