"""Live model-vs-bench residual of the delivery flow, once per revolution (no ROS).

Used identically by the node and ``run-bag`` through :class:`~gerotor_twin.twin.core.TwinCore`.

What is compared
    At each completed revolution the core emits ``twin/flow_summary`` (the predicted
    revolution-mean delivery flow and volumetric efficiency, stamped with the revolution's
    end).  :class:`FlowResidual` pairs it with the measured flow (``bench/delivery_flow``):
    the mean of the accepted flow-meter samples *received* (node clock) within the
    revolution, ``[end - T, end)`` with ``T`` = displacement / theoretical flow; when none
    was received in it (a meter slower than the revolutions), the last sample received
    before ``end``, if it is younger than ``stale_timeout_s`` (held, as the model's inputs
    are).  Published as ``twin/flow_residual`` (:data:`~gerotor_twin.twin.outputs.RESIDUAL_FIELDS`):
    measured, predicted and measured − predicted mean delivery [m³/s], the measured volumetric
    efficiency (measured / theoretical flow) [-], the predicted one and their difference [-].
    The stamp is that of the revolution's ``twin/flow_summary``.
Without a flow meter
    Nothing is published; the ``gerotor_twin: model`` status says so (``flow_residual``).
The meter's own lag
    With ``flow_sensor_tau_s`` > 0 (the health settings' bench flow meter, node parameter
    ``health_flow_sensor_tau_s``) the predicted delivery and theoretical flow are read through the
    meter's first-order lag (:class:`~.meter_reading.MeterReading`) before they are compared, so the
    residual stays a model error during speed and pressure changes; the published predicted flow and
    efficiencies are then those read through it (η = flow / the lagged theoretical flow).  With 0 the
    measured flow is compared as received, and a meter with a time constant lags the prediction for a
    few time constants after each change.
"""
from __future__ import annotations

import collections
import math

from gerotor_twin.twin import outputs as O
from gerotor_twin.twin.meter_reading import MeterReading
from gerotor_twin.twin.outputs import OutputMessage

__all__ = ["FlowSamples", "FlowResidual"]

NS = 1_000_000_000


class FlowSamples:
    """Accepted flow-meter samples ``(receive_ns, value [m³/s])`` in arrival order, bounded.

    Parameters
    ----------
    maxlen : int
        Samples kept (the oldest go first).
    """

    def __init__(self, maxlen: int = 100_000):
        self._q: collections.deque = collections.deque(maxlen=maxlen)

    def add(self, value_m3s: float, receive_ns: int) -> None:
        """One measured delivery flow [m³/s] received at ``receive_ns`` [ns]; non-finite values are ignored."""
        if math.isfinite(value_m3s):
            self._q.append((int(receive_ns), float(value_m3s)))

    def between(self, start_ns: int, end_ns: int) -> list[float]:
        """Values received in ``[start_ns, end_ns)`` [m³/s]."""
        return [v for t, v in list(self._q) if start_ns <= t < end_ns]

    def last_before(self, end_ns: int) -> tuple[int, float] | None:
        """The last ``(receive_ns, value)`` received before ``end_ns``, or None."""
        for t, v in reversed(list(self._q)):
            if t < end_ns:
                return t, v
        return None

    def forget_after(self, t_ns: int) -> None:
        """Forget the samples received after ``t_ns`` (the clock jumped back to it: a bag loop)."""
        kept = [x for x in list(self._q) if x[0] <= t_ns]
        self._q.clear()
        self._q.extend(kept)

    def drop_before(self, t_ns: int, keep_last: bool = False) -> None:
        """Forget the samples received before ``t_ns`` (with ``keep_last``: all but the last of them)."""
        q = self._q
        while q and q[0][0] < t_ns:
            if keep_last and (len(q) == 1 or q[1][0] >= t_ns):
                return
            q.popleft()


class FlowResidual:
    """Measured against predicted revolution-mean delivery flow (see the module docstring).

    Parameters
    ----------
    displacement : float
        Volume per revolution [m³].
    stale_s : float
        A held flow sample older than this is not used [s] (the twin's ``stale_timeout_s``).
    flow_sensor_tau_s : float, optional
        The flow meter's time constant [s]: the predictions are read through its lag (module doc; 0: off).
    """

    def __init__(self, displacement: float, stale_s: float, flow_sensor_tau_s: float = 0.0):
        self.displacement = float(displacement)
        self.stale_ns = int(stale_s * NS)
        self.samples = FlowSamples()
        self.meter = MeterReading(flow_sensor_tau_s)
        self.published = 0          #: residuals published [-]
        self.held = 0               #: of which with a held sample (none received in the revolution) [-]
        self.without_flow = 0       #: revolutions without a usable measured flow [-]
        self.last: tuple | None = None   #: last published values (:data:`~.outputs.RESIDUAL_FIELDS` order)
        #: where the measured flow comes from, for the status text (the node sets its ``delivery_flow_topic``;
        #: '' = no flow-meter input)
        self.meter_topic = "bench/delivery_flow"

    def add_flow(self, value_m3s: float, receive_ns: int) -> None:
        """A measured delivery flow sample [m³/s] accepted by the input book, received at ``receive_ns`` [ns]."""
        self.samples.add(value_m3s, receive_ns)

    def clock_jumped_back(self, now_ns: int) -> None:
        """The clock went back to ``now_ns`` [ns]: samples received after it belong to another pass."""
        self.samples.forget_after(now_ns)
        self.meter.reset()

    def observe(self, messages) -> list[OutputMessage]:
        """The ``twin/flow_residual`` messages for the revolution summaries among ``messages``."""
        out: list[OutputMessage] = []
        for msg in messages:
            if msg.topic == O.FLOW_SUMMARY:
                out.extend(self._revolution(msg.stamp_ns, msg.msg["data"]))
        return out

    def measured(self, start_ns: int, end_ns: int) -> tuple[float, bool] | None:
        """Measured mean flow over ``[start_ns, end_ns)`` [m³/s] and whether it is a held sample; None if none."""
        values = self.samples.between(start_ns, end_ns)
        if values:
            return sum(values) / len(values), False
        last = self.samples.last_before(end_ns)
        if last is not None and end_ns - last[0] <= self.stale_ns:
            return last[1], True
        return None

    def _revolution(self, end_ns: int, summary) -> list[OutputMessage]:
        q_pred, q_th, _loss, eta_pred = (float(v) for v in summary[:4])
        if not q_th > 0:
            return []
        start_ns = end_ns - int(round(self.displacement / q_th * NS))
        if self.meter.tau_s > 0:                       # the predictions as the meter reads them
            q_pred, q_th = self.meter.read(end_ns, (q_pred, q_th))
            eta_pred = q_pred / q_th
        got = self.measured(start_ns, end_ns)
        self.samples.drop_before(start_ns, keep_last=True)
        if got is None:
            self.without_flow += 1
            return []
        q_meas, held = got
        eta_meas = q_meas / q_th
        values = (q_meas, q_pred, q_meas - q_pred, eta_meas, eta_pred, eta_meas - eta_pred)
        if not O.all_finite(values):
            return []
        self.published += 1
        self.held += held
        self.last = values
        return O.residual_messages(end_ns, values)

    def report(self) -> dict:
        """Values for the ``gerotor_twin: model`` status: state text and counters."""
        if self.published:
            text = f"published ({self.published} revolutions)"
        elif not self.meter_topic:
            text = "not published: no measured delivery flow: no flow-meter input (delivery_flow_topic is '')"
        else:
            text = (f"not published: no measured delivery flow received on {self.meter_topic}; "
                    "it is published once a flow meter's samples arrive")
        vals = {"flow_residual": text, "flow_residual_published": self.published,
                "flow_residual_held_sample": self.held, "flow_residual_without_flow": self.without_flow}
        if self.last is not None:
            vals.update({f"last_residual_{k}": v for k, v in zip(O.RESIDUAL_FIELDS, self.last)})
        return vals
