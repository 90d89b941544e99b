"""The model's flows as the bench's flow meter reads them: a first-order lag per value (no ROS).

The health monitor's windows (:mod:`.health`) and ``twin/flow_residual`` (:mod:`.residual`) compare the meter's
readings with the model's flows; a meter with a time constant τ reads late, so during the few τ after a change of
speed or pressure the model's flows are read through the same lag before they are compared (``flow_sensor_tau_s``
of the health settings, node parameter ``health_flow_sensor_tau_s``).
"""
from __future__ import annotations

__all__ = ["MeterReading"]

NS = 1_000_000_000


class MeterReading:
    """Values read through a first-order lag of ``tau_s`` [s], each value held from the previous stamp to its own
    (:func:`~gerotor_twin.hydraulics.meter.lag_step`, exact for a held input); ``tau_s`` ≤ 0: the values as given.

    Parameters
    ----------
    tau_s : float
        The meter's time constant [s].
    """

    def __init__(self, tau_s: float = 0.0):
        self.tau_s = float(tau_s)
        self._last: tuple | None = None      # (stamp [ns], the values as read)

    def read(self, stamp_ns: int, values) -> tuple:
        """The values given at ``stamp_ns`` [ns] (each held since the previous call's stamp) as the meter reads
        them now, in the values' units; the first call, or one stamped before the last: the values as given."""
        values = tuple(float(v) for v in values)
        if not self.tau_s > 0:
            return values
        from gerotor_twin.hydraulics.meter import lag_step     # not at import: hydraulics' package imports numba
        prev = self._last
        if prev is not None and stamp_ns >= prev[0]:
            values = tuple(lag_step(y, v, (stamp_ns - prev[0]) / NS, self.tau_s) for y, v in zip(prev[1], values))
        self._last = (stamp_ns, values)
        return values

    def reset(self) -> None:
        """Forget the reading (the clock jumped back: a bag loop)."""
        self._last = None
