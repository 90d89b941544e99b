"""The twin core: bench samples in, model advanced to the clock, output messages out (no ROS).

:class:`TwinCore` is the façade of three parts, each in its own module:

* :class:`~gerotor_twin.twin.input_book.InputBook` — input channels,
  validation, stamp guard, sources, sequence gaps;
* :class:`~gerotor_twin.twin.revolution.RevolutionRecorder` — the revolution
  in progress, its flow summary and waveform;
* :class:`~gerotor_twin.twin.clock_driver.ClockDriver` — owns the
  :class:`~gerotor_twin.model.pump.PumpState` and advances the
  :class:`~gerotor_twin.model.pump.PumpModel` to the clock;

and they share one rate-limited :class:`~gerotor_twin.twin.events.EventLog`.
The ROS node and the offline ``gerotor-twin run-bag`` drive it the same way::

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
    At every ``publish_period_s`` multiple of model time: chamber pressures
    (as an array and one ``twin/chambers/<chamber>/pressure`` per chamber),
    delivery flow, eccentricity (values at that instant), the per-gap
    minimum tooth-tip gaps and per-chamber peak pressures since the previous
    publication, and ``twin/sample`` (all of them by name, stamped).  At each completed
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
import time
from typing import Any, Callable

import numpy as np

from gerotor_twin.model.pump import PumpModel, PumpState
from gerotor_twin.twin import outputs as O
from gerotor_twin.twin.clock_driver import ClockDriver, TickResult
from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.health import HealthMonitor, HealthSettings
from gerotor_twin.twin.input_book import InputBook
from gerotor_twin.hydraulics.meter import expansion
from gerotor_twin.twin.residual import FlowResidual
from gerotor_twin.twin.revolution import RevolutionRecorder
from gerotor_twin.twin.settings import NS, TwinSettings
from gerotor_twin.twin.startup_rtf import StartupRtf, measure as measure_rtf

__all__ = ["TwinCore", "TickResult"]


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
    health : HealthSettings, optional
        The health monitor's settings (defaults if omitted).
    diagnosis_in_background : bool
        The health monitor's fault classifier in a worker thread beside ``tick`` (the node), not inside it
        (default: inside, deterministic; :class:`~gerotor_twin.twin.health.HealthMonitor`).

    Attributes
    ----------
    book : InputBook
        The inputs (channels, counters, sources, sequence gaps).
    recorder : RevolutionRecorder
        Per-revolution flow summary and waveform.
    driver : ClockDriver
        The model state and its advance to the clock.

    Notes
    -----
    ``add_sample``/``add_message``/``note_sequence``/``reject`` may be called
    from any thread; ``tick``, ``diagnostics`` and ``pop_events`` from one
    thread at a time.
    """

    def __init__(self, model: PumpModel, settings: TwinSettings | None = None, *,
                 timer: Callable[[], float] = time.perf_counter, health: HealthSettings | None = None,
                 diagnosis_in_background: bool = False):
        self.model = model
        self.settings = s = settings or TwinSettings()
        self.N = model.N
        self._timer = timer
        self._events = EventLog(int(s.error_report_period_s * NS))
        self.book = InputBook(model, s, self._events)
        self.recorder = RevolutionRecorder(model.N, model.displacement, s.waveform_every, s.waveform_samples)
        self.driver = ClockDriver(model, s, self.book, self.recorder, self._events)
        self._win = {"simulated_s": 0.0, "compute_s": 0.0, "counts": {}}
        self._last_tick: TickResult | None = None
        self.health = HealthMonitor(model, health or HealthSettings(), background=diagnosis_in_background)
        #: measured against predicted revolution-mean flow (``twin/flow_residual``)
        self.residual = FlowResidual(model.displacement, s.stale_timeout_s, self.health.settings.flow_sensor_tau_s)
        self.driver.jump_back_listeners += [self.residual.clock_jumped_back, self.health.clock_jumped_back]
        #: result of :meth:`measure_startup_rtf` (None: not measured)
        self.startup_rtf: StartupRtf | None = None

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
        return self._health_sample(kind, self.book.add_message(kind, msg, receive_ns, sequence), receive_ns)

    def _health_sample(self, kind: str, accepted: bool, receive_ns: int) -> bool:
        """Hand an accepted measured flow sample (and the reception of a shaft-speed sample) to the health
        monitor; returns ``accepted``."""
        if accepted and kind == "shaft_speed":
            self.health.add_speed(receive_ns)
        if accepted and kind == "delivery_flow":
            with self.book.lock:
                last = self.book.channels["delivery_flow"].latest()
            if last is not None:
                q = last[0] if self.settings.flow_meter == "delivery" else self._at_delivery(last[0])
                self.health.add_flow(q, receive_ns)
                self.residual.add_flow(q, receive_ns)
        return accepted

    def _at_delivery(self, q_m3s: float) -> float:
        """A return-line meter's reading [m³/s] as the same mass's volume at the delivery pressure
        (``settings.flow_meter``, :mod:`gerotor_twin.hydraulics.meter`): times ρ(p_atm)/ρ(p_d) at the latest
        delivery pressure accepted (none yet: the reading as it is)."""
        with self.book.lock:
            p_d = self.book.channels["delivery_pressure"].latest()
        if p_d is None:
            return q_m3s
        return q_m3s * expansion(self.model.config.fluid.atmospheric_pa, p_d[0], self.model.kernel.eos)

    def note_sequence(self, kind: str, seq: int | None, receive_ns: int) -> int:
        """Book the publisher sequence number of a received ``kind`` message (any thread).

        Call it once per message received, before or after :meth:`add_message`;
        gaps are counted as ``lost`` (see :mod:`gerotor_twin.twin.sequence`).

        Returns
        -------
        int
            Messages this number shows lost before reception (usually 0).
        """
        return self.book.note_sequence(kind, seq, receive_ns)

    def input_accounting(self) -> dict[str, dict[str, int]]:
        """Per input: received, lost, missed_at_start, ... (:class:`~gerotor_twin.twin.sequence.GapCounts`)."""
        return self.book.accounting()

    def reject(self, kind: str, text: str, receive_ns: int, reason: str = "malformed") -> None:
        """Count and report a message of ``kind`` that could not even be decoded."""
        self.book.reject(kind, text, receive_ns, reason)

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
        return self._health_sample(kind, self.book.add_sample(kind, value, stamp_ns, receive_ns), receive_ns)

    def pop_events(self) -> list[tuple[int, str]]:
        """Rate-limited events since the last call: ``(level, text)``, level 1 = WARN, 2 = ERROR."""
        return self._events.pop()

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
        res = TickResult(now_ns, self.driver.t_ns)
        self.driver.tick(now_ns, res)
        res.messages.extend(self.residual.observe(res.messages))
        running = self.driver.status == "running"
        res.messages.extend(self.health.observe(now_ns, self.driver.inputs if running else None, res.messages))
        res.compute_s = self._timer() - t0
        self.driver.count_tick(res)
        self._win["simulated_s"] += res.simulated_s
        self._win["compute_s"] += res.compute_s
        self._last_tick = res
        return res

    def measure_startup_rtf(self, threshold: float, **kwargs) -> StartupRtf | None:
        """Measure the model's real-time factor on this machine (:mod:`gerotor_twin.twin.startup_rtf`).

        Call it once, before the first tick (it runs the model on states of its
        own; the twin's state is not touched).  From then on every
        :meth:`diagnostics` carries the status ``gerotor_twin: real time``
        (WARN while the figure is below ``threshold``), and a WARN event is
        queued for :meth:`pop_events`.

        Parameters
        ----------
        threshold : float
            WARN below this real-time factor [-]; 0 = no measurement, no status.
        **kwargs
            Passed to :func:`gerotor_twin.twin.startup_rtf.measure` (``budget_s`` [s], ...).

        Returns
        -------
        StartupRtf or None
            The figures (None when ``threshold`` is 0).
        """
        if threshold == 0:
            self.startup_rtf = None
            return None
        res = self.startup_rtf = measure_rtf(self.model.replica(), threshold, chunk_s=self.settings.sample_period_s,
                                             **kwargs)       # the same pump and kernel; the live model untouched
        if res.below:
            self._events.report("model", "startup_rtf", 1, res.message(), 0)
        return res

    # ------------------------------------------------------------ reporting
    @property
    def status(self) -> str:
        """``waiting`` (no model state), ``running`` or ``held`` (stale/invalid inputs)."""
        return self.driver.status

    @property
    def state(self) -> PumpState | None:
        """The current model state (None before the first valid inputs or after a reset)."""
        return self.driver.state

    @property
    def model_time_ns(self) -> int | None:
        """Clock time the model has reached [ns]."""
        return self.driver.t_ns

    @property
    def stats(self) -> dict[str, Any]:
        """Counters since start: ticks, simulated/compute/skipped/held time [s], revolutions, resets, ..."""
        return self.driver.stats

    def counts(self) -> dict[str, int]:
        """Solver steps and events since start (summed over resets)."""
        return self.driver.counts()

    def input_report(self, now_ns: int) -> dict[str, dict]:
        """Per input: last value, age [s], accepted, rejected by reason, last error."""
        return self.book.report(now_ns)

    def snapshot(self, now_ns: int) -> dict[str, Any]:
        """Plain figures of the twin (what :meth:`diagnostics` reports)."""
        win = self._win
        rtf = win["simulated_s"] / win["compute_s"] if win["compute_s"] > 0 else None
        st = self.state
        ecc_ratio = (float(np.hypot(*st.eccentricity)) / self.model.config.clearances.housing_radial_m
                     if st is not None else None)
        lt = self._last_tick
        t_ns = self.model_time_ns
        last = self.recorder.last_summary
        snap = {
            "status": self.status, "reason": self._reason(now_ns),
            "real_time_factor": rtf,
            "lag_s": None if t_ns is None else (now_ns - t_ns) / NS,
            "last_tick_compute_s": lt.compute_s if lt else None,
            "model_time_ns": t_ns, "eccentricity_ratio": ecc_ratio,
            "counts": self.counts(), "inputs": self.input_report(now_ns),
            "last_summary": dict(zip(O.SUMMARY_FIELDS, last)) if last else None,
            **self.driver.oil.report(), "oil_temperature_warn": self.driver.oil.warn,
            "flow_residual": self.residual.report(),
        }
        snap.update({k: (dict(v) if isinstance(v, collections.Counter) else v) for k, v in self.stats.items()})
        return snap

    def _reason(self, now_ns: int) -> str:
        if self.status == "running":
            return ""
        stale = self.settings.stale_timeout_s * NS
        last = self.book.latest_required()
        why = [f"{k} not received" for k, v in last.items() if v is None]
        why += [f"{k} stale ({(now_ns - v[1]) / NS:.3g} s old)" for k, v in last.items()
                if v is not None and now_ns - v[1] > stale]
        return ", ".join(why) or self.driver.hold_reason

    def diagnostics(self, now_ns: int, extra: list | None = None) -> dict:
        """``diagnostic_msgs/DiagnosticArray`` dict; resets the real-time-factor window.

        Statuses: ``gerotor_twin: model`` (state, real-time factor, lag, skips,
        resets, solver steps and failures, contact/cavitation events) and
        ``gerotor_twin: inputs`` (per input value, age [s], accepted/rejected
        counts, last error), ``gerotor_twin: real time`` after
        :meth:`measure_startup_rtf` (start-up real-time factor; WARN below its
        threshold), ``gerotor_twin: health`` when enabled.  ``extra`` statuses (dicts of
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
        if self.startup_rtf is not None:
            statuses.append(self.startup_rtf.status())
        if self.health.settings.enabled:
            statuses.append(self.health.status())
        statuses.extend(extra or [])
        return m.diagnostic_array(now_ns, statuses)
