"""The input book of the twin core: every bench sample received, checked, kept or counted.

:class:`InputBook` holds one :class:`~gerotor_twin.twin.inputs.InputChannel`
per input (samples on the grid, stamp guard, counters), the publisher
:class:`~gerotor_twin.twin.sources.SourceTracker` and the
:class:`~gerotor_twin.twin.sequence.SequenceGaps` of each input, and queues
its errors on the shared, rate-limited :class:`~gerotor_twin.twin.events.EventLog`.
It validates a sample (finite, in the pump's range, stamp order) before it is
kept; a rejected sample is counted by reason and the previous value is held.
The bad-input policy is documented in :mod:`gerotor_twin.twin.core`.

Thread safety: every public method takes the book's lock, so samples may be
added from any thread while the clock driver reads :meth:`InputBook.values_at`.
"""
from __future__ import annotations

import math
import threading
from typing import Any

from gerotor_twin.errors import InputError
from gerotor_twin.hydraulics.oil import T_MAX_K, T_MIN_K
from gerotor_twin.units import kelvin_to_celsius
from gerotor_twin.model.pump import Inputs, PumpModel
from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.inputs import INPUTS, REQUIRED, InputChannel, sample_from_message
from gerotor_twin.twin.sequence import SequenceGaps
from gerotor_twin.twin.settings import NS, TwinSettings
from gerotor_twin.twin.sources import SourceTracker
from gerotor_twin.twin.stamps import REBASE, RESTART, StampGuard

__all__ = ["InputBook"]

#: Oil temperature accepted [°C]: the range of the oil laws (hydraulics.oil).
_TEMP_RANGE_C = (kelvin_to_celsius(T_MIN_K), kelvin_to_celsius(T_MAX_K))


def _check_kind(kind: str) -> None:
    """Raise :class:`InputError` unless ``kind`` is one of :data:`INPUTS`."""
    if kind not in INPUTS:
        raise InputError("input", kind, " | ".join(INPUTS))


class _Rejected(Exception):
    """A sample fails validation: the counter ``reason`` and the error ``text``."""

    def __init__(self, reason: str, text: str):
        super().__init__(text)
        self.reason = reason
        self.text = text


class InputBook:
    """Validated bench inputs on the sample grid, with their sources, gaps and counters.

    Parameters
    ----------
    model : PumpModel
        Gives the input ranges (``check_inputs``), the default suction
        pressure [Pa] and the maximum speed (delivery-flow plausibility).
    settings : TwinSettings
        Sample grid, filter, staleness, stamp and negative-speed settings.
    events : EventLog
        Where rejections, stamp notes, source switches and losses are queued.
    """

    def __init__(self, model: PumpModel, settings: TwinSettings, events: EventLog):
        self.model = model
        self.settings = s = settings
        self.events = events
        self.lock = threading.Lock()
        self.channels = {k: InputChannel(spec, s.sample_ns, s.filter_tau_s, self._stamp_guard())
                         for k, spec in INPUTS.items()}
        self._sources = {k: SourceTracker(switch_after_ns=int(s.stale_timeout_s * NS)) for k in INPUTS}
        self._gaps = {k: SequenceGaps() for k in INPUTS}
        #: Suction pressure used while none is received [Pa absolute].
        self.default_ps = float(model.config.boundary.suction_pressure_pa)
        wmax = model.config.range.max_speed_rpm * math.pi / 30
        self._flow_limit = 10.0 * model.theoretical_flow(wmax) + 1e-6

    # ------------------------------------------------------------ receiving
    def add_message(self, kind: str, msg: Any, receive_ns: int, sequence: int | None = None) -> bool:
        """Add a decoded input message; see :meth:`gerotor_twin.twin.core.TwinCore.add_message`."""
        if sequence is not None and not self._from_followed_source(kind, sequence, int(receive_ns)):
            return False
        try:
            value, stamp = sample_from_message(kind, msg)
        except InputError as exc:
            if kind not in INPUTS:
                raise
            with self.lock:
                self._reject(self.channels[kind], "malformed", str(exc), int(receive_ns))
            return False
        return self.add_sample(kind, value, stamp, receive_ns)

    def note_sequence(self, kind: str, seq: int | None, receive_ns: int) -> int:
        """Book a publisher sequence number; see :meth:`gerotor_twin.twin.core.TwinCore.note_sequence`."""
        _check_kind(kind)
        with self.lock:
            gap = self._gaps[kind].add(seq, int(receive_ns))
            if gap:
                self.events.report(kind, "lost", 1, f"{kind}: {gap} message(s) lost before reception (gap in "
                                   "the publisher's sequence numbers; input_queue_depth too small or the node "
                                   "stalled?)", int(receive_ns))
        return gap

    def reject(self, kind: str, text: str, receive_ns: int, reason: str = "malformed") -> None:
        """Count and report a message of ``kind`` that could not even be decoded."""
        _check_kind(kind)
        with self.lock:
            self._reject(self.channels[kind], reason, text, int(receive_ns))

    def add_sample(self, kind: str, value: float, stamp_ns: int | None, receive_ns: int) -> bool:
        """Add one sample; see :meth:`gerotor_twin.twin.core.TwinCore.add_sample` (units, stamps).

        Returns
        -------
        bool
            True if accepted; False if rejected (counted, reported, previous value held).
        """
        _check_kind(kind)
        receive_ns = int(receive_ns)
        with self.lock:
            ch = self.channels[kind]
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
                self.events.report(kind, "stamp_" + verdict, 1, self._stamp_note(kind, verdict), receive_ns)
            ch.add(value, stamp_ns, receive_ns, verdict)
        return True

    def _from_followed_source(self, kind: str, sequence: int, receive_ns: int) -> bool:
        _check_kind(kind)
        with self.lock:
            tr = self._sources[kind]
            switches = tr.switches
            use = tr.observe(sequence, receive_ns)
            if tr.switches != switches:
                self.events.report(kind, "source_switch", 1, f"{kind}: the followed source went silent; now "
                                   f"following source #{tr.followed}", receive_ns)
            if not use:
                self.events.report(kind, "other_source", 1, f"{kind}: more than one publisher on the topic; "
                                   f"following source #{tr.followed}, samples of the others are logged but "
                                   "not used", receive_ns)
        return use

    # ---------------------------------------------------------- stamp checks
    def _stamp_guard(self) -> StampGuard:
        s = self.settings
        return StampGuard(restart_ns=int(round(s.stamp_restart_s * NS)), ahead_ns=int(round(s.stamp_ahead_s * NS)),
                          rebase_after=s.stamp_rebase_samples)

    def _zero_stamp(self, ch: InputChannel, receive_ns: int) -> None:
        """A header stamp of 0: counted, reported, the sample taken as unstamped (no order check)."""
        ch.zero_stamps += 1
        self.events.report(ch.spec.kind, "zero_stamp", 1, f"{ch.spec.kind}: header stamp 0 (the source does not "
                           "stamp its messages): taken as unstamped, its order cannot be checked", receive_ns)

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

    # ------------------------------------------------------------ validation
    def _validate(self, kind: str, value: float, ch: InputChannel) -> float:
        """The sample as a float in range (a slightly negative speed clamped to 0), else :class:`_Rejected`."""
        try:
            v = float(value)
        except (TypeError, ValueError):
            raise _Rejected("malformed", str(InputError(kind, value, "a number"))) from None
        if not math.isfinite(v):
            raise _Rejected("nonfinite", str(InputError(kind, value, f"a finite number [{ch.spec.unit}]")))
        try:
            if kind == "shaft_speed":
                v = self._clamped_speed(v, ch)
            else:
                self._check_range(kind, v)
        except InputError as exc:
            raise _Rejected("out_of_range", str(exc)) from None
        return v

    def _clamped_speed(self, v: float, ch: InputChannel) -> float:
        """Shaft speed [rad/s]: below ``-tolerance`` rejected, slightly negative clamped to 0, range checked."""
        if v < 0:
            tol = self.settings.negative_speed_tolerance_rad_s
            if v < -tol:
                raise _Rejected("negative", str(InputError(
                    "shaft_speed", v, f">= 0 rad/s (values down to -{tol:g} rad/s are clamped to 0)",
                    "the model runs forward only")))
            v = 0.0
            ch.clamped += 1
        self.model.check_inputs(Inputs(v, self.default_ps, self.default_ps))
        return v

    def _check_range(self, kind: str, v: float) -> None:
        """Raise :class:`InputError` if a pressure [Pa], flow [m³/s] or temperature [°C] is out of range."""
        m = self.model
        if kind == "delivery_pressure":
            ps_now = self.channels["suction_pressure"].latest()
            m.check_inputs(Inputs(0.0, ps_now[0] if ps_now is not None else self.default_ps, v))
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

    def _reject(self, ch: InputChannel, reason: str, text: str, receive_ns: int) -> None:
        ch.rejected[reason] = ch.rejected.get(reason, 0) + 1
        ch.last_error = text
        self.events.report(ch.spec.kind, reason, 1, text, receive_ns)

    # ------------------------------------------------------ the clock driver
    def values_at(self, cell: int) -> dict[str, tuple[float, int] | None]:
        """Per input, (filtered value, receive ns) applying at grid point ``cell`` (None if nothing yet)."""
        with self.lock:
            return {k: ch.at(cell) for k, ch in self.channels.items()}

    def latest_required(self) -> dict[str, tuple[float, int] | None]:
        """Per required input, the last accepted (filtered value, receive ns) or None."""
        with self.lock:
            return {k: self.channels[k].latest() for k in REQUIRED}

    def clock_jumped_back(self, now_ns: int) -> None:
        """Forget samples received after ``now_ns`` [ns] and every stamp order (counters are kept)."""
        with self.lock:
            for ch in self.channels.values():
                ch.drop_after(now_ns)
                ch.last_stamp = None

    # -------------------------------------------------------------- reports
    def accounting(self) -> dict[str, dict[str, int]]:
        """Per input: received, lost, missed_at_start, ... (:class:`~gerotor_twin.twin.sequence.GapCounts`)."""
        with self.lock:
            return {k: g.counts().as_dict() for k, g in self._gaps.items()}

    def report(self, now_ns: int) -> dict[str, dict]:
        """Per input: last value, age [s], accepted, rejected by reason, last error, losses, sources."""
        out = {}
        with self.lock:
            for k, ch in self.channels.items():
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
