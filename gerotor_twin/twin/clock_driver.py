"""The clock driver of the twin: advances the pump model cell by cell to the clock.

:class:`ClockDriver` owns the :class:`~gerotor_twin.model.pump.PumpState` and
ties the :class:`~gerotor_twin.twin.input_book.InputBook` (the inputs applying
at each grid point) and the :class:`~gerotor_twin.twin.revolution.RevolutionRecorder`
(per-revolution outputs) to :meth:`~gerotor_twin.model.pump.PumpModel.advance`.
It applies the sampling, hold, reset and lag policies documented in
:mod:`gerotor_twin.twin.core` and emits the instantaneous outputs at every
publication instant.  Used from one thread (the tick thread).
"""
from __future__ import annotations

import collections
import math
from dataclasses import dataclass, field, replace
from typing import Any

import numpy as np

from gerotor_twin.errors import InputError
from gerotor_twin.model.pump import Inputs, PumpModel, PumpState
from gerotor_twin.model.volumetric import EdgeLosses
from gerotor_twin.twin import outputs as O
from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.input_book import InputBook
from gerotor_twin.twin.inputs import REQUIRED
from gerotor_twin.twin.oil_temperature import OilTemperature
from gerotor_twin.twin.revolution import RevolutionRecorder
from gerotor_twin.twin.settings import NS, TwinSettings

__all__ = ["ClockDriver", "TickResult"]

_TWO_PI = 2.0 * math.pi


@dataclass
class TickResult:
    """What one :meth:`TwinCore.tick` produced."""
    now_ns: int                         #: clock time of the tick [ns]
    model_time_ns: int | None           #: clock time the model has reached (grid point) [ns]
    messages: list = field(default_factory=list)  #: :class:`~gerotor_twin.twin.outputs.OutputMessage` list
    simulated_s: float = 0.0            #: model time integrated in this tick [s]
    skipped_s: float = 0.0              #: clock time skipped by the lag policy [s]
    compute_s: float = 0.0              #: processor time spent in the tick [s] (timer of the core)
    status: str = "waiting"             #: waiting | running | held


class ClockDriver:
    """Advances the model over the sample grid up to the clock; holds, skips and resets.

    Parameters
    ----------
    model : PumpModel
        The pump.
    settings : TwinSettings
        Sample grid, publish period, lag and staleness settings.
    book : InputBook
        Where the inputs applying at each grid point come from.
    recorder : RevolutionRecorder
        Receives every solver output and each completed revolution.
    events : EventLog
        Where holds, skips and resets are queued (key ``model``).
    """

    def __init__(self, model: PumpModel, settings: TwinSettings, book: InputBook,
                 recorder: RevolutionRecorder, events: EventLog):
        self.model = model
        self.settings = settings
        self.book = book
        self.recorder = recorder
        self.events = events
        #: the oil temperature the model runs at (measured or the config's reference)
        self.oil = OilTemperature(model.config.reference_temperature_k, settings.stale_timeout_s, events,
                                  settings.oil_sensor_tau_s)
        self.N = model.N
        self._edge = EdgeLosses.of(model.config, model.displacement)   # model.volumetric
        self._S = settings.sample_ns
        self.state: PumpState | None = None
        self.epoch_ns = 0                   #: clock time of model time 0 [ns]
        self.t_ns: int | None = None        #: clock time the model has reached [ns]
        self._last_now: int | None = None
        #: called with the new clock time [ns] when the clock jumps back (a bag loop), after the reset
        self.jump_back_listeners: list = []
        self.status = "waiting"
        self.hold_reason = "no inputs yet"
        self._inputs: Inputs | None = None
        self._last_row: tuple | None = None
        self._gap_min = np.full(self.N, np.inf)
        self._peak_max = np.full(self.N, -np.inf)
        self._counts_base: dict[str, int] = {}
        self._stats: dict[str, Any] = {
            "ticks": 0, "simulated_s": 0.0, "compute_s": 0.0, "skips": 0, "skipped_s": 0.0,
            "held_s": 0.0, "published": 0, "nonfinite_suppressed": 0,
            "resets": collections.Counter(), "clock_jumps_back": 0, "initialised": 0,
        }

    @property
    def stats(self) -> dict[str, Any]:
        """Tick, skip, hold, reset, revolution and publication counters since start."""
        s, rec = self._stats, self.recorder
        out = {k: s[k] for k in ("ticks", "simulated_s", "compute_s", "skips", "skipped_s", "held_s")}
        out.update(revolutions=rec.revolutions, waveforms=rec.waveforms, published=s["published"],
                   nonfinite_suppressed=s["nonfinite_suppressed"] + rec.nonfinite_suppressed)
        out.update({k: s[k] for k in ("resets", "clock_jumps_back", "initialised")})
        return out

    def counts(self) -> dict[str, int]:
        """Solver steps and events since start (summed over resets)."""
        c = dict(self._counts_base)
        if self.state is not None:
            for k, v in self.state.counts.items():
                c[k] = c.get(k, 0) + v
        return c

    # -------------------------------------------------------------------- tick
    @property
    def inputs(self):
        """The model inputs of the last cell advanced (None before the first)."""
        return self._inputs

    def tick(self, now_ns: int, res: TickResult) -> None:
        """Advance to the last grid point at or before ``now_ns`` [ns]; outputs go to ``res``."""
        S = self._S
        if self._last_now is not None and now_ns < self._last_now:
            self._stats["clock_jumps_back"] += 1
            self._reset("clock_jump_back", 1, f"clock jumped back by {(self._last_now - now_ns) / NS:.6g} s "
                        "(bag loop?): model reset, restarting from the next valid inputs", now_ns)
            self.book.clock_jumped_back(now_ns)
            for listener in self.jump_back_listeners:
                listener(now_ns)
            self.t_ns = None
        self._last_now = now_ns
        target = (now_ns // S) * S
        if self.t_ns is None:
            self.t_ns = target
        span = target - self.t_ns
        keep = span if self.settings.max_span_s == math.inf else (self.settings.max_span_ns // S) * S
        if span > keep:
            if self.state is None:          # nothing to advance: just move on
                self.t_ns += span - keep
            else:
                self._skip(span - keep, now_ns)
                res.skipped_s = (span - keep) / NS
        g = self.t_ns
        while g < target:
            self._cell(g, res)
            g += S
        self.t_ns = max(self.t_ns, target)
        res.model_time_ns = self.t_ns
        res.status = self.status

    def count_tick(self, res: TickResult) -> None:
        """Add a finished tick to the counters."""
        st = self._stats
        st["ticks"] += 1
        st["compute_s"] += res.compute_s
        st["simulated_s"] += res.simulated_s
        st["published"] += len(res.messages)

    # ------------------------------------------------------------- policies
    def _reset(self, reason: str, level: int, text: str, t_ns: int) -> None:
        if self.state is not None:
            for k, v in self.state.counts.items():
                self._counts_base[k] = self._counts_base.get(k, 0) + v
        self.state = None
        self.recorder.drop()
        self._inputs = None
        self.status = "waiting"
        self.hold_reason = reason
        self._stats["resets"][reason] += 1
        self.events.report("model", reason, level, text, t_ns)

    def _skip(self, skip_ns: int, now_ns: int) -> None:
        st = self._stats
        st["skips"] += 1
        st["skipped_s"] += skip_ns / NS
        self.t_ns += skip_ns
        if self.state is not None:
            w = self._inputs.omega if self._inputs is not None else 0.0
            k = round(w * (skip_ns / NS) / _TWO_PI)
            s = self.state
            self.state = replace(s, t=s.t + skip_ns / NS, theta=s.theta + k * _TWO_PI,
                                 swept_angle=s.swept_angle + k * _TWO_PI)
            self.recorder.drop()
        self.events.report("model", "lag_skip", 1,
                           f"behind the clock: skipped {skip_ns / NS:.6g} s of clock time (max_span_s = "
                           f"{self.settings.max_span_s:g} s); state kept, phase kept", now_ns)

    def _hold(self, g: int, reason: str) -> None:
        if self.status == "running":
            self.events.report("model", "hold", 1, f"model held: {reason}", g)
        self.status = "held" if self.state is not None else "waiting"
        self.hold_reason = reason
        self.recorder.drop()
        self._stats["held_s"] += self._S / NS

    # ------------------------------------------------------------ one cell
    def _cell_inputs(self, g: int) -> Inputs | None:
        """The model inputs applying at grid point ``g`` [ns], or None (model held)."""
        stale = int(self.settings.stale_timeout_s * NS)
        vals = self.book.values_at(g // self._S)
        missing = [k for k in REQUIRED if vals[k] is None]
        old = [k for k in REQUIRED if vals[k] is not None and g - vals[k][1] > stale]
        if missing or old:
            why = ", ".join([f"{k} not received" for k in missing] +
                            [f"{k} stale ({(g - vals[k][1]) / NS:.3g} s old)" for k in old])
            self._hold(g, why)
            return None
        ps_v = vals["suction_pressure"]
        ps = ps_v[0] if ps_v is not None and g - ps_v[1] <= stale else self.book.default_ps
        t_oil = self.oil.at(g, vals["oil_temperature"])
        try:
            return self.model.check_inputs(Inputs(vals["shaft_speed"][0], ps, vals["delivery_pressure"][0], t_oil))
        except InputError as exc:
            self._hold(g, f"inputs inconsistent: {exc}")
            return None

    def _cell(self, g: int, res: TickResult) -> None:
        """Advance over the cell [g, g + Ts) with the inputs applying at g."""
        inputs = self._cell_inputs(g)
        if inputs is None:
            return
        S = self._S
        if self.state is None:
            self.state = self.model.initial_state(inputs, theta=0.0, t=0.0)
            self.epoch_ns = g
            self.recorder.drop()
            self._gap_min[:] = np.inf
            self._peak_max[:] = -np.inf
            self._stats["initialised"] += 1
        self._inputs = inputs
        self.status = "running"
        st = self.state
        t_start = (g - self.epoch_ns) / NS
        if st.t != t_start:
            st = replace(st, t=t_start)
        end_s = (g + S - self.epoch_ns) / NS
        try:
            st = self._advance(st, end_s, inputs, res)
        except FloatingPointError as exc:
            self._reset("solver_failure", 2, f"solver failure ({exc}): model reset", g)
            return
        self.state = replace(st, t=end_s)
        res.simulated_s += S / NS
        if ((g + S) // S) % self.settings.publish_every == 0:
            self._publish(g + S, res)

    def _advance(self, st: PumpState, end_s: float, inputs: Inputs, res: TickResult) -> PumpState:
        """Advance ``st`` to model time ``end_s`` [s], split at every whole revolution."""
        w = inputs.omega
        while True:
            rem = end_s - st.t
            if rem <= 1e-12:
                return st
            dt, boundary = rem, None
            if w > 0:      # split at a whole revolution (angle tolerance 1e-9 rad)
                nb = _TWO_PI * (math.floor((st.theta + 1e-9) / _TWO_PI) + 1)
                if st.theta + w * rem >= nb - 1e-9:
                    dt, boundary = min(max((nb - st.theta) / w, 0.0), rem), nb
            st, out = self.model.advance(st, dt, inputs)
            loss = self._edge.flow(w, float(np.mean(out.delivery_pressure)) if len(out) else inputs.p_delivery,
                                   inputs.p_suction)
            self._consume(out, loss)
            self.recorder.add_loss(loss * dt)
            if boundary is not None:
                st = replace(st, theta=boundary)
                res.messages.extend(self.recorder.complete(st, self.epoch_ns + int(round(st.t * NS))))

    def _consume(self, out, loss: float) -> None:
        """Keep the last row (its delivery flow less the edge losses ``loss`` [m³/s]) and record it."""
        if len(out) == 0:
            return
        self._gap_min = np.minimum(self._gap_min, out.gaps.min(axis=0))
        self._peak_max = np.maximum(self._peak_max, out.chamber_peak_pressures.max(axis=0))
        self._last_row = (out.chamber_pressures[-1], float(out.delivery_flow[-1]) - loss, out.eccentricity[-1])
        self.recorder.record(out)

    def _publish(self, t_ns: int, res: TickResult) -> None:
        if self._last_row is None:
            return
        p, q, e = self._last_row
        gaps, peaks = self._gap_min, self._peak_max       # since the previous publication
        if not O.all_finite(p, q, e, gaps, peaks):
            self._stats["nonfinite_suppressed"] += 1
            return
        res.messages.extend(O.instantaneous(t_ns, p, q, e, gaps, peaks))   # (float64_multiarray copies)
        self._gap_min[:] = np.inf
        self._peak_max[:] = -np.inf
