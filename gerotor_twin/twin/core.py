"""The twin core: bench samples in, model advanced to the clock, output messages out (no ROS).

:class:`TwinCore` owns a :class:`~gerotor_twin.model.pump.PumpModel` and its
:class:`~gerotor_twin.model.pump.PumpState`.  The ROS node and the offline
``gerotor-twin run-bag`` drive it the same way::

    core = TwinCore(PumpModel(load_config(), "mobility"), TwinSettings())
    core.add_message("shaft_speed", joint_state_msg, receive_ns)   # any thread
    core.add_sample("delivery_pressure", 2.85e6, stamp_ns, receive_ns)
    result = core.tick(now_ns)                                     # one thread
    for out in result.messages:          # OutputMessage(topic, msgtype, stamp_ns, msg dict)
        publish(out.topic, out.msg)
    diag = core.diagnostics(now_ns)      # diagnostic_msgs/DiagnosticArray dict
    for level, text in core.pop_events():
        log(level, text)                 # rate-limited input errors, resets, skips

Time base
    ``receive_ns`` and ``now_ns`` are times of one clock (the node's clock:
    wall time, or ``/clock`` under ``use_sim_time``; in an MCAP log written by
    the node, the ``log_time`` of an input).  Header stamps only serve the
    order / duplicate checks and are reported.
Input sampling (deterministic)
    The clock is cut into cells ``[k·Ts, (k+1)·Ts)`` (``Ts`` =
    ``settings.sample_period_s``, anchored at clock time 0).  Over a cell the
    model runs with the (low-pass filtered, ``filter_tau_s``) values of the last
    samples received at or before ``k·Ts``: a zero-order hold.  ``tick(now)``
    integrates every whole cell up to ``floor(now/Ts)·Ts``, so the predictions
    depend on the samples and their receive times only, not on when ticks
    happen (coarse ``/clock`` or a fast offline loop give the same result);
    they lag the clock by less than one cell.  The shaft angle is integrated
    from the speed; the advance is also split at every whole revolution.
Outputs
    At every ``publish_period_s`` multiple of model time: chamber pressures,
    delivery flow, eccentricity (values at that instant) and the per-gap
    minimum tooth-tip gaps since the previous publication.  At each completed
    revolution: ``twin/flow_summary`` (mean delivery over the revolution from
    the exact delivered volume, theoretical = displacement / revolution time,
    leakage = their difference, volumetric efficiency) and every
    ``waveform_every`` revolutions the chamber-pressure waveform over the
    revolution.  Stamps are the model (clock) time of the prediction.  A
    message with a non-finite value is never emitted (counted instead).
Bad input policy (each counted per input and reason, reported on diagnostics,
rate-limited in :meth:`TwinCore.pop_events`)
    * NaN/inf, malformed message, speed below ``-negative_speed_tolerance``,
      value outside the pump's range (``PumpModel.check_inputs``), duplicate
      or out-of-order header stamp: the sample is **rejected**, the previous
      accepted value is held.  Slightly negative speeds are clamped to 0.
    * A stamp far older than the last one (``> stamp_restart_s``) is a restart
      of the source: accepted.
    * A stamp implausibly ahead of its receive time (more than
      ``stamp_ahead_s`` beyond the stream's usual offset) is rejected by itself
      (``future_stamp``); the good stream that follows is accepted.  After
      ``stamp_rebase_samples`` consecutive consistent samples rejected for
      their stamp, the order re-anchors on them, so one bad stamp never blocks
      the stream (:mod:`gerotor_twin.twin.stamps`).
    * More than one publisher on an input topic: the first source is
      followed, the others' samples counted (and logged by the node) but not
      used; WARN on diagnostics (:mod:`gerotor_twin.twin.sources`).
    * A header stamp of 0 (source does not stamp) is counted per input
      (``zero_stamps``), reported (WARN on diagnostics in a period where it
      happened) and the sample taken as unstamped.
    * A required input (speed, delivery pressure) not received, or older than
      ``stale_timeout_s``: the model is **held** (state frozen, nothing
      published, diagnostics STALE) until a fresh sample arrives; then it
      continues from the frozen state.  A stale optional suction pressure
      falls back to the config default.
    * Clock jump backwards (bag loop, ``now`` < previous ``now``): the model
      is **reset**; samples received after the new ``now`` are dropped, stamp
      order is forgotten; the model restarts from the next valid inputs.
    * Solver failure (non-finite state): reset, restart at the next cell.
Lag policy
    A tick never integrates more than ``max_span_s`` of clock time.  When the
    backlog is longer (the CPU cannot keep up, or the process stalled), the
    excess is **skipped**: model time jumps forward to ``now - max_span_s``, the
    state is kept and the shaft angle jumps by a whole number of revolutions
    (the nearest to ∫ω dt), so the state stays consistent with its phase; the
    revolution in progress is dropped from the summaries.  Work per tick is
    bounded, so outputs stay current; skips and the skipped time are reported.
    ``max_span_s = inf`` (offline) never skips.
"""
from __future__ import annotations

import collections
import math
import threading
import time
from dataclasses import dataclass, field, replace
from typing import Any, Callable

import numpy as np

from gerotor_twin.errors import InputError
from gerotor_twin.model.pump import Inputs, PumpModel, PumpState
from gerotor_twin.twin import outputs as O
from gerotor_twin.twin.inputs import INPUTS, REQUIRED, InputChannel, sample_from_message
from gerotor_twin.twin.sequence import SequenceGaps
from gerotor_twin.twin.settings import NS, TwinSettings
from gerotor_twin.twin.sources import SourceTracker
from gerotor_twin.twin.stamps import REBASE, RESTART, StampGuard

__all__ = ["TwinCore", "TickResult"]

_TWO_PI = 2.0 * math.pi
_TEMP_RANGE_C = (-50.0, 250.0)


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


class TwinCore:
    """Digital-twin core: validated inputs, clock-driven model, output messages.

    Parameters
    ----------
    model : PumpModel
        The pump (its config gives ranges and the default suction pressure).
    settings : TwinSettings, optional
        Sampling, lag and bad-input settings (defaults if omitted).
    timer : callable, optional
        Returns seconds; measures compute time for the real-time factor
        (default :func:`time.perf_counter`).

    Notes
    -----
    ``add_sample``/``add_message`` may be called from any thread; ``tick``,
    ``diagnostics`` and ``pop_events`` from one thread at a time.
    """

    def __init__(self, model: PumpModel, settings: TwinSettings | None = None, *,
                 timer: Callable[[], float] = time.perf_counter):
        self.model = model
        self.settings = settings or TwinSettings()
        self.N = model.N
        self._timer = timer
        self._lock = threading.Lock()
        s = self.settings
        self._S = s.sample_ns
        self._channels = {k: InputChannel(spec, self._S, s.filter_tau_s, self._stamp_guard())
                          for k, spec in INPUTS.items()}
        self._sources = {k: SourceTracker(switch_after_ns=int(s.stale_timeout_s * NS)) for k in INPUTS}
        self._gaps = {k: SequenceGaps() for k in INPUTS}
        self._default_ps = float(model.config.boundary.suction_pressure_pa)
        wmax = model.config.range.max_speed_rpm * math.pi / 30
        self._flow_limit = 10.0 * model.theoretical_flow(wmax) + 1e-6
        self._state: PumpState | None = None
        self._epoch_ns = 0
        self._t_ns: int | None = None
        self._last_now: int | None = None
        self._status = "waiting"
        self._hold_reason = "no inputs yet"
        self._inputs: Inputs | None = None
        self._rev: dict | None = None
        self._last_row: tuple | None = None
        self._gap_min = np.full(self.N, np.inf)
        self._last_summary: tuple | None = None
        self._counts_base: dict[str, int] = {}
        self._events: collections.deque = collections.deque(maxlen=1000)
        self._reported: dict[tuple[str, str], list] = {}
        self.stats: dict[str, Any] = {
            "ticks": 0, "simulated_s": 0.0, "compute_s": 0.0, "skips": 0, "skipped_s": 0.0,
            "held_s": 0.0, "revolutions": 0, "waveforms": 0, "published": 0, "nonfinite_suppressed": 0,
            "resets": collections.Counter(), "clock_jumps_back": 0, "initialised": 0,
        }
        self._win = {"simulated_s": 0.0, "compute_s": 0.0, "counts": {}}
        self._last_tick: TickResult | None = None

    # ------------------------------------------------------------------ inputs
    def add_message(self, kind: str, msg: Any, receive_ns: int, sequence: int | None = None) -> bool:
        """Add a decoded input message (see :func:`~gerotor_twin.twin.inputs.sample_from_message`).

        ``sequence`` is the publisher's publication sequence number (message
        info of the subscription, or the MCAP message sequence; None / 0 =
        unknown): with more than one publisher on the topic, only the followed
        source is used (:mod:`gerotor_twin.twin.sources`).

        Returns
        -------
        bool
            True if accepted; False if rejected (counted and reported) or from another source.
        """
        if sequence is not None and not self._from_followed_source(kind, sequence, int(receive_ns)):
            return False
        try:
            value, stamp = sample_from_message(kind, msg)
        except InputError as exc:
            if kind not in INPUTS:
                raise
            with self._lock:
                self._reject(self._channels[kind], "malformed", str(exc), int(receive_ns))
            return False
        return self.add_sample(kind, value, stamp, receive_ns)

    def note_sequence(self, kind: str, seq: int | None, receive_ns: int) -> int:
        """Book the publisher sequence number of a received ``kind`` message (any thread).

        Call it once per message received, before or after :meth:`add_message`;
        gaps are counted as ``lost`` (see :mod:`gerotor_twin.twin.sequence`).

        Returns
        -------
        int
            Messages this number shows lost before reception (usually 0).
        """
        if kind not in INPUTS:
            raise InputError("input", kind, " | ".join(INPUTS))
        with self._lock:
            gap = self._gaps[kind].add(seq, int(receive_ns))
            if gap:
                self._report(kind, "lost", 1, f"{kind}: {gap} message(s) lost before reception (gap in the "
                             "publisher's sequence numbers; input_queue_depth too small or the node stalled?)",
                             int(receive_ns))
        return gap

    def input_accounting(self) -> dict[str, dict[str, int]]:
        """Per input: received, lost, missed_at_start, ... (:class:`~gerotor_twin.twin.sequence.GapCounts`)."""
        with self._lock:
            return {k: g.counts().as_dict() for k, g in self._gaps.items()}

    def reject(self, kind: str, text: str, receive_ns: int, reason: str = "malformed") -> None:
        """Count and report a message of ``kind`` that could not even be decoded."""
        if kind not in INPUTS:
            raise InputError("input", kind, " | ".join(INPUTS))
        with self._lock:
            self._reject(self._channels[kind], reason, text, int(receive_ns))

    def add_sample(self, kind: str, value: float, stamp_ns: int | None, receive_ns: int) -> bool:
        """Add one input sample.

        Parameters
        ----------
        kind : str
            ``shaft_speed`` [rad/s], ``delivery_pressure`` / ``suction_pressure``
            [Pa absolute], ``delivery_flow`` [m³/s], ``oil_temperature`` [°C].
        value : float
            The value in that unit.
        stamp_ns : int or None
            Header stamp [ns] (``None``: unstamped, no order check; ``0``: a zero
            header stamp, counted and reported, then as unstamped).
        receive_ns : int
            Clock time of reception [ns] (same clock as :meth:`tick`).

        Returns
        -------
        bool
            True if accepted; False if rejected (counted, reported, previous value held).
        """
        if kind not in INPUTS:
            raise InputError("input", kind, " | ".join(INPUTS))
        receive_ns = int(receive_ns)
        with self._lock:
            ch = self._channels[kind]
            if stamp_ns == 0:
                self._zero_stamp(ch, receive_ns)
                stamp_ns = None
            verdict = ch.check_stamp(stamp_ns, receive_ns)
            if verdict not in (None, RESTART, REBASE):
                self._reject(ch, verdict, self._stamp_error(ch, verdict, stamp_ns, receive_ns), receive_ns)
                return False
            try:
                value = self._validate(kind, value, ch)
            except _Rejected as rej:
                self._reject(ch, rej.reason, rej.text, receive_ns)
                return False
            if verdict is not None:
                self._report(kind, "stamp_" + verdict, 1, self._stamp_note(kind, verdict), receive_ns)
            ch.add(value, stamp_ns, receive_ns, verdict)
        return True

    def _from_followed_source(self, kind: str, sequence: int, receive_ns: int) -> bool:
        if kind not in INPUTS:
            raise InputError("input", kind, " | ".join(INPUTS))
        with self._lock:
            tr = self._sources[kind]
            switches = tr.switches
            use = tr.observe(sequence, receive_ns)
            if tr.switches != switches:
                self._report(kind, "source_switch", 1, f"{kind}: the followed source went silent; now following "
                             f"source #{tr.followed}", receive_ns)
            if not use:
                self._report(kind, "other_source", 1, f"{kind}: more than one publisher on the topic; following "
                             f"source #{tr.followed}, samples of the others are logged but not used", receive_ns)
        return use

    # ---------------------------------------------------------- stamp checks
    def _stamp_guard(self) -> StampGuard:
        s = self.settings
        return StampGuard(restart_ns=int(round(s.stamp_restart_s * NS)), ahead_ns=int(round(s.stamp_ahead_s * NS)),
                          rebase_after=s.stamp_rebase_samples)

    def _zero_stamp(self, ch: InputChannel, receive_ns: int) -> None:
        """A header stamp of 0: counted, reported, the sample taken as unstamped (no order check)."""
        ch.zero_stamps += 1
        self._report(ch.spec.kind, "zero_stamp", 1, f"{ch.spec.kind}: header stamp 0 (the source does not stamp "
                     "its messages): taken as unstamped, its order cannot be checked", receive_ns)

    def _stamp_error(self, ch: InputChannel, reason: str, stamp_ns: int, receive_ns: int) -> str:
        kind = ch.spec.kind
        if reason == "future_stamp":
            usual = ch.guard.usual_offset(receive_ns) or 0.0
            return str(InputError(f"{kind}.header.stamp", stamp_ns,
                                  f"at most {self.settings.stamp_ahead_s:g} s ahead of its receive time "
                                  f"{receive_ns} ns (+ the usual offset {usual / NS:.6g} s)",
                                  f"{(stamp_ns - receive_ns - usual) / NS:.6g} s ahead: implausible, this "
                                  "sample alone dropped"))
        what = "equal to" if reason == "duplicate_stamp" else "older than"
        return str(InputError(f"{kind}.header.stamp", stamp_ns,
                              f"newer than the last accepted stamp {ch.last_stamp} ns", f"{what} it: sample dropped"))

    def _stamp_note(self, kind: str, verdict: str) -> str:
        if verdict == RESTART:
            return (f"{kind}: header stamp went back by more than {self.settings.stamp_restart_s:g} s; "
                    "taken as a restart of the source")
        return (f"{kind}: {self.settings.stamp_rebase_samples} consecutive consistent samples after stamp "
                "rejections: stamp order re-anchored on them (the earlier stamp was the outlier, or the "
                "source clock jumped)")

    def _validate(self, kind: str, value: float, ch: InputChannel) -> float:
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise _Rejected("malformed", str(InputError(kind, value, "a number"))) from None
        if not math.isfinite(v):
            raise _Rejected("nonfinite", str(InputError(kind, value, f"a finite number [{ch.spec.unit}]")))
        m = self.model
        ps_now = self._channels["suction_pressure"].latest()
        ps = ps_now[0] if ps_now is not None else self._default_ps
        try:
            if kind == "shaft_speed":
                if v < 0:
                    tol = self.settings.negative_speed_tolerance_rad_s
                    if v < -tol:
                        raise _Rejected("negative", str(InputError(
                            kind, v, f">= 0 rad/s (values down to -{tol:g} rad/s are clamped to 0)",
                            "the model runs forward only")))
                    v = 0.0
                    ch.clamped += 1
                m.check_inputs(Inputs(v, self._default_ps, self._default_ps))
            elif kind == "delivery_pressure":
                m.check_inputs(Inputs(0.0, ps, v))
            elif kind == "suction_pressure":
                m.check_inputs(Inputs(0.0, v, v))
            elif kind == "oil_temperature":
                lo, hi = _TEMP_RANGE_C
                if not lo <= v <= hi:
                    raise InputError(kind, v, f"[{lo:g}, {hi:g}] °C")
            elif kind == "delivery_flow":
                if abs(v) > self._flow_limit:
                    raise InputError(kind, v, f"[-{self._flow_limit:.4g}, {self._flow_limit:.4g}] m³/s "
                                              "(10 × the theoretical flow at maximum speed)")
        except InputError as exc:
            raise _Rejected("out_of_range", str(exc)) from None
        return v

    def _reject(self, ch: InputChannel, reason: str, text: str, receive_ns: int) -> None:
        ch.rejected[reason] = ch.rejected.get(reason, 0) + 1
        ch.last_error = text
        self._report(ch.spec.kind, reason, 1, text, receive_ns)

    def _report(self, kind: str, reason: str, level: int, text: str, t_ns: int) -> None:
        """Queue an event, at most one per (kind, reason) per ``error_report_period_s``."""
        key = (kind, reason)
        period = int(self.settings.error_report_period_s * NS)
        rec = self._reported.get(key)
        if rec is None or t_ns - rec[0] >= period or t_ns < rec[0]:
            extra = f" (+{rec[1]} similar since the last report)" if rec and rec[1] else ""
            self._events.append((level, text + extra))
            self._reported[key] = [t_ns, 0]
        else:
            rec[1] += 1

    def pop_events(self) -> list[tuple[int, str]]:
        """Rate-limited events since the last call: ``(level, text)``, level 1 = WARN, 2 = ERROR."""
        out = list(self._events)
        self._events.clear()
        return out

    # -------------------------------------------------------------------- tick
    def tick(self, now_ns: int) -> TickResult:
        """Advance the model to the last sample-grid point at or before ``now_ns``.

        Parameters
        ----------
        now_ns : int
            Clock time [ns] (wall or ``/clock``); may be coarse or irregular.

        Returns
        -------
        TickResult
            Output messages with their prediction stamps, and tick figures.
        """
        t0 = self._timer()
        now_ns = int(now_ns)
        S = self._S
        res = TickResult(now_ns, self._t_ns)
        if self._last_now is not None and now_ns < self._last_now:
            self.stats["clock_jumps_back"] += 1
            self._reset("clock_jump_back", 1, f"clock jumped back by {(self._last_now - now_ns) / NS:.6g} s "
                        "(bag loop?): model reset, restarting from the next valid inputs", now_ns)
            with self._lock:
                for ch in self._channels.values():
                    ch.drop_after(now_ns)
                    ch.last_stamp = None
            self._t_ns = None
        self._last_now = now_ns
        target = (now_ns // S) * S
        if self._t_ns is None:
            self._t_ns = target
        span = target - self._t_ns
        keep = span if self.settings.max_span_s == math.inf else (self.settings.max_span_ns // S) * S
        if span > keep:
            if self._state is None:          # nothing to advance: just move on
                self._t_ns += span - keep
            else:
                self._skip(span - keep, now_ns)
                res.skipped_s = (span - keep) / NS
        g = self._t_ns
        while g < target:
            self._cell(g, res)
            g += S
        self._t_ns = max(self._t_ns, target)
        res.model_time_ns = self._t_ns
        res.status = self._status
        res.compute_s = self._timer() - t0
        st = self.stats
        st["ticks"] += 1
        st["compute_s"] += res.compute_s
        st["simulated_s"] += res.simulated_s
        st["published"] += len(res.messages)
        self._win["simulated_s"] += res.simulated_s
        self._win["compute_s"] += res.compute_s
        self._last_tick = res
        return res

    # ------------------------------------------------------------- internals
    def _reset(self, reason: str, level: int, text: str, t_ns: int) -> None:
        if self._state is not None:
            for k, v in self._state.counts.items():
                self._counts_base[k] = self._counts_base.get(k, 0) + v
        self._state = None
        self._rev = None
        self._inputs = None
        self._status = "waiting"
        self._hold_reason = reason
        self.stats["resets"][reason] += 1
        self._report("model", reason, level, text, t_ns)

    def _skip(self, skip_ns: int, now_ns: int) -> None:
        st = self.stats
        st["skips"] += 1
        st["skipped_s"] += skip_ns / NS
        self._t_ns += skip_ns
        if self._state is not None:
            w = self._inputs.omega if self._inputs is not None else 0.0
            k = round(w * (skip_ns / NS) / _TWO_PI)
            s = self._state
            self._state = replace(s, t=s.t + skip_ns / NS, theta=s.theta + k * _TWO_PI,
                                  swept_angle=s.swept_angle + k * _TWO_PI)
            self._rev = None
        self._report("model", "lag_skip", 1,
                     f"behind the clock: skipped {skip_ns / NS:.6g} s of clock time (max_span_s = "
                     f"{self.settings.max_span_s:g} s); state kept, phase kept", now_ns)

    def _hold(self, g: int, reason: str) -> None:
        if self._status == "running":
            self._report("model", "hold", 1, f"model held: {reason}", g)
        self._status = "held" if self._state is not None else "waiting"
        self._hold_reason = reason
        self._rev = None
        self.stats["held_s"] += self._S / NS

    def _cell(self, g: int, res: TickResult) -> None:
        """Advance over the cell [g, g + Ts) with the inputs applying at g."""
        S = self._S
        cell = g // S
        stale = int(self.settings.stale_timeout_s * NS)
        with self._lock:
            vals = {k: ch.at(cell) for k, ch in self._channels.items()}
        missing = [k for k in REQUIRED if vals[k] is None]
        old = [k for k in REQUIRED if vals[k] is not None and g - vals[k][1] > stale]
        if missing or old:
            why = ", ".join([f"{k} not received" for k in missing] +
                            [f"{k} stale ({(g - vals[k][1]) / NS:.3g} s old)" for k in old])
            self._hold(g, why)
            return
        ps_v = vals["suction_pressure"]
        ps = ps_v[0] if ps_v is not None and g - ps_v[1] <= stale else self._default_ps
        try:
            inputs = self.model.check_inputs(Inputs(vals["shaft_speed"][0], ps, vals["delivery_pressure"][0]))
        except InputError as exc:
            self._hold(g, f"inputs inconsistent: {exc}")
            return
        if self._state is None:
            self._state = self.model.initial_state(inputs, theta=0.0, t=0.0)
            self._epoch_ns = g
            self._rev = None
            self._gap_min[:] = np.inf
            self.stats["initialised"] += 1
        self._inputs = inputs
        self._status = "running"
        st = self._state
        t_start = (g - self._epoch_ns) / NS
        if st.t != t_start:
            st = replace(st, t=t_start)
        end_s = (g + S - self._epoch_ns) / NS
        w = inputs.omega
        try:
            while True:
                rem = end_s - st.t
                if rem <= 1e-12:
                    break
                dt, boundary = rem, None
                if w > 0:      # split at a whole revolution (angle tolerance 1e-9 rad)
                    nb = _TWO_PI * (math.floor((st.theta + 1e-9) / _TWO_PI) + 1)
                    if st.theta + w * rem >= nb - 1e-9:
                        dt, boundary = min(max((nb - st.theta) / w, 0.0), rem), nb
                st, out = self.model.advance(st, dt, inputs)
                self._consume(st, out)
                if boundary is not None:
                    st = replace(st, theta=boundary)
                    self._revolution(st, res)
        except FloatingPointError as exc:
            self._reset("solver_failure", 2, f"solver failure ({exc}): model reset", g)
            return
        self._state = replace(st, t=end_s)
        res.simulated_s += S / NS
        if ((g + S) // S) % self.settings.publish_every == 0:
            self._publish(g + S, res)

    def _consume(self, st: PumpState, out) -> None:
        if len(out) == 0:
            return
        self._gap_min = np.minimum(self._gap_min, out.gaps.min(axis=0))
        self._last_row = (out.chamber_pressures[-1], float(out.delivery_flow[-1]), out.eccentricity[-1])
        r = self._rev
        if r is not None:
            r["theta"].append(out.theta - r["theta0"])
            r["p"].append(out.chamber_pressures)
            r["rows"] += len(out)
            if r["rows"] > 200_000:             # very slow revolution: keep memory bounded
                r["theta"] = [np.concatenate(r["theta"])[::2]]
                r["p"] = [np.concatenate(r["p"])[::2]]
                r["rows"] = len(r["theta"][0])

    def _revolution(self, st: PumpState, res: TickResult) -> None:
        """A whole revolution ended at ``st``: summary, waveform, start the next one."""
        r = self._rev
        stamp = self._epoch_ns + int(round(st.t * NS))
        if r is not None:
            T = st.t - r["t0"]
            dv = float(st.volumes[0] - r["vol0"])
            disp = self.model.displacement
            if T > 0:
                q, qth = dv / T, disp / T
                vals = (q, qth, qth - q, dv / disp)
                if O.all_finite(vals):
                    res.messages.extend(O.summary_messages(stamp, vals))
                    self._last_summary = vals
                else:
                    self.stats["nonfinite_suppressed"] += 1
            self.stats["revolutions"] += 1
            every = self.settings.waveform_every
            if every and self.stats["revolutions"] % every == 0:
                table = self._waveform_table(r)
                if table is not None and O.all_finite(table):
                    res.messages.append(O.waveform(stamp, table))
                    self.stats["waveforms"] += 1
                elif table is not None:
                    self.stats["nonfinite_suppressed"] += 1
        self._rev = {"t0": st.t, "vol0": float(st.volumes[0]), "theta0": st.theta,
                     "theta": [np.zeros(1)], "p": [st.pressures[None, :self.N].copy()], "rows": 1}

    def _waveform_table(self, r: dict):
        ang = np.concatenate(r["theta"])
        p = np.concatenate(r["p"])
        if ang.size < 2:
            return None
        M = self.settings.waveform_samples
        grid = np.arange(M) * (_TWO_PI / M)
        table = np.empty((M, 1 + self.N))
        table[:, 0] = grid
        for j in range(self.N):
            table[:, 1 + j] = np.interp(grid, ang, p[:, j])
        return table

    def _publish(self, t_ns: int, res: TickResult) -> None:
        if self._last_row is None:
            return
        p, q, e = self._last_row
        gaps = self._gap_min if np.all(np.isfinite(self._gap_min)) else None
        if gaps is None or not O.all_finite(p, q, e, gaps):
            self.stats["nonfinite_suppressed"] += 1
            return
        res.messages.extend(O.instantaneous(t_ns, p, q, e, gaps.copy()))
        self._gap_min[:] = np.inf

    # ------------------------------------------------------------ reporting
    @property
    def status(self) -> str:
        """``waiting`` (no model state), ``running`` or ``held`` (stale/invalid inputs)."""
        return self._status

    @property
    def state(self) -> PumpState | None:
        """The current model state (None before the first valid inputs or after a reset)."""
        return self._state

    @property
    def model_time_ns(self) -> int | None:
        """Clock time the model has reached [ns]."""
        return self._t_ns

    def counts(self) -> dict[str, int]:
        """Solver steps and events since start (summed over resets)."""
        c = dict(self._counts_base)
        if self._state is not None:
            for k, v in self._state.counts.items():
                c[k] = c.get(k, 0) + v
        return c

    def input_report(self, now_ns: int) -> dict[str, dict]:
        """Per input: last value, age [s], accepted, rejected by reason, last error."""
        out = {}
        with self._lock:
            for k, ch in self._channels.items():
                last = ch.latest()
                out[k] = {"value": None if last is None else last[0],
                          "age_s": None if last is None else (now_ns - last[1]) / NS,
                          "accepted": ch.accepted, "clamped": ch.clamped, "rejected": dict(ch.rejected),
                          "stamp_restarts": ch.stamp_restarts, "stamp_rebases": ch.stamp_rebases,
                          "zero_stamps": ch.zero_stamps, "last_error": ch.last_error,
                          "lost": self._gaps[k].lost, "missed_at_start": self._gaps[k].missed_at_start,
                          **self._source_report(k, now_ns)}
        return out

    def _source_report(self, kind: str, now_ns: int) -> dict[str, Any]:
        tr = self._sources[kind]
        return {"sources_active": tr.active(now_ns), "sources_seen": tr.sources_seen,
                "followed_source": tr.followed, "other_source_samples": tr.other_samples,
                "source_switches": tr.switches}

    def snapshot(self, now_ns: int) -> dict[str, Any]:
        """Plain figures of the twin (what :meth:`diagnostics` reports)."""
        win = self._win
        rtf = win["simulated_s"] / win["compute_s"] if win["compute_s"] > 0 else None
        st = self._state
        ecc_ratio = (float(np.hypot(*st.eccentricity)) / self.model.config.clearances.housing_radial_m
                     if st is not None else None)
        lt = self._last_tick
        snap = {
            "status": self._status, "reason": self._reason(now_ns),
            "real_time_factor": rtf,
            "lag_s": None if self._t_ns is None else (now_ns - self._t_ns) / NS,
            "last_tick_compute_s": lt.compute_s if lt else None,
            "model_time_ns": self._t_ns, "eccentricity_ratio": ecc_ratio,
            "counts": self.counts(), "inputs": self.input_report(now_ns),
            "last_summary": dict(zip(O.SUMMARY_FIELDS, self._last_summary)) if self._last_summary else None,
        }
        snap.update({k: (dict(v) if isinstance(v, collections.Counter) else v) for k, v in self.stats.items()})
        return snap

    def _reason(self, now_ns: int) -> str:
        if self._status == "running":
            return ""
        stale = self.settings.stale_timeout_s * NS
        with self._lock:
            last = {k: self._channels[k].latest() for k in REQUIRED}
        why = [f"{k} not received" for k, v in last.items() if v is None]
        why += [f"{k} stale ({(now_ns - v[1]) / NS:.3g} s old)" for k, v in last.items()
                if v is not None and now_ns - v[1] > stale]
        return ", ".join(why) or self._hold_reason

    def diagnostics(self, now_ns: int, extra: list | None = None) -> dict:
        """``diagnostic_msgs/DiagnosticArray`` dict; resets the real-time-factor window.

        Statuses: ``gerotor_twin: model`` (state, real-time factor, lag, skips,
        resets, solver steps and failures, contact/cavitation events) and
        ``gerotor_twin: inputs`` (per input value, age [s], accepted/rejected
        counts, last error).  ``extra`` statuses (dicts of
        :func:`gerotor_twin.io.messages.diagnostic_status`) are appended.
        """
        from gerotor_twin.io import messages as m
        from gerotor_twin.twin.diagnostics import input_status, model_status
        snap = self.snapshot(now_ns)
        counts = dict(snap["counts"])
        counts["skips"] = snap["skips"]
        for k, info in snap["inputs"].items():
            counts[f"rejected.{k}"] = sum(info["rejected"].values())
            counts[f"zero_stamps.{k}"] = info["zero_stamps"]
            counts[f"lost.{k}"] = info["lost"]
        prev = self._win["counts"]
        delta = {k: v - prev.get(k, 0) for k, v in counts.items()}
        self._win = {"simulated_s": 0.0, "compute_s": 0.0, "counts": counts}
        statuses = [model_status(snap, delta), input_status(snap, self.settings.stale_timeout_s, delta)]
        statuses.extend(extra or [])
        return m.diagnostic_array(now_ns, statuses)


class _Rejected(Exception):
    def __init__(self, reason: str, text: str):
        super().__init__(text)
        self.reason = reason
        self.text = text
