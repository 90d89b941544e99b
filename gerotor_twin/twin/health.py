"""Online health of the pump: effective leakage factor, reference efficiency, alarm (no ROS).

Used identically by the node and ``run-bag`` through :class:`~gerotor_twin.twin.core.TwinCore`.

What is estimated
    ``k``, the ratio of the measured flow loss (theoretical − measured delivery flow) to
    the flow loss the twin predicts with its configured (calibrated) leakage, by the
    scalar Kalman filter of :mod:`.leakage_filter` (random-walk drift ``drift_per_sqrt_s``).
    ``k = 1``: the pump is as calibrated; wear opens the clearances and raises ``k``
    (the equivalent common clearance factor is ``k^(1/n)``, n the exponent of the flow loss
    against the clearances at the reference point, :func:`clearance_exponent`; ≈ 3 for
    Poiseuille leakage).
When it is updated (robust to ramps and to the flow meter's lag)
    Once per *settled interval*: the clock is cut into windows of ``window_s``; a
    window is used only when the model's speed and delivery pressure stayed within
    ``speed_tol`` (relative) and ``pressure_tol_pa`` of their value at the window start
    for the whole window *and* for ``settle_s`` before it (≥ 5 flow-meter time
    constants: the meter has caught up), with at least one revolution summary and
    ``min_flow_samples`` measured flow samples.  Ramps and steps are ignored.  With
    ``flow_sensor_tau_s`` > 0 the model's revolution means are read through the meter's
    first-order lag before they are averaged (:class:`~.meter_reading.MeterReading`),
    so a window in which the meter still settles compares like with like.
    Measurement: y = mean theoretical − mean measured flow; regressor: mean predicted
    loss / the factor the model runs with; noise variance
    (``meter_sd_rel`` · q)²/n + max((``model_sd_rel`` · q)², (e_cal · q_th)²), where e_cal is
    the efficiency RMSE the calibration measured (``calibration.residuals.eta_rmse`` of a
    config written by ``gerotor-twin calibrate``; 0 for an uncalibrated config): the twin is
    not trusted more closely than its calibration showed it fits the pump.
What is published (``twin/health``, one message per update, :data:`HEALTH_FIELDS`; the same by name,
stamped, on ``twin/health_update``)
    k and its standard deviation, the clearance factor k^(1/n), the volumetric
    efficiency at the reference point (``reference_rpm``, ``reference_bar``, each capped at the
    pump's ``range``) with k
    and its standard deviation, the same with k = 1 (calibrated), the residual
    (measured − predicted mean flow) of this interval, the mean and RMS of the last
    ``residual_window`` residuals, the normalised innovation, the update count,
    the status level, and the fault the classifier of :mod:`.diagnosis` names from the recent settled
    windows (``fault``: its index in :data:`~.diagnosis.KINDS`, −1 not classified) with its probability
    (``fault_confidence``); for a fault of the flow, the kind the windows separate least from it (``fault_rival``,
    its index, −1 none), how well (``fault_separation``, the expected log-likelihood ratio) and whether that is
    below the classifier's bound (``fault_tentative`` 1: the naming is tentative).  Each window is recorded
    (:attr:`HealthMonitor.windows`: mean speed, pressures, oil temperature, measured and predicted flow, noise,
    shaft-speed samples received and expected) and classified against the twin's steady sensitivities at its
    operating point; not with ``adapt``.
Status (``/diagnostics`` ``gerotor_twin: health``)
    STALE until ``min_updates`` updates (no measured flow, or never steady); ERROR when
    the reference efficiency fell more than ``error_pt`` points below the calibrated
    one; WARN above ``warn_pt`` points, or when the normalised innovation stayed beyond
    ``residual_band`` for ``band_updates`` consecutive updates; OK otherwise.  The fall judged is
    the leakage factor's until the classifier names a fault of the flow, then that fault's loss at the
    reference point (:meth:`HealthMonitor.alarm_drop_pt`).
``adapt``
    False (default): a pure monitor, the model keeps its configured leakage.  True:
    after each update that moved k by more than 1 % from the factor in use, the model's
    tooth-tip and lateral clearances are set to the configured ones × k^(1/n), so the
    predictions follow the pump (the residuals then stay near zero and the drop shows
    in the published k and reference efficiency only).
"""
from __future__ import annotations

import collections
import math
from dataclasses import asdict, dataclass, replace

from gerotor_twin.errors import InputError, check_int, check_ranges
from gerotor_twin.io import messages as m
from gerotor_twin.twin import leakage_filter as lf
from gerotor_twin.twin.diagnosis import FLOW_KINDS, KIND_CODES, KINDS, Diagnosis, DiagnosisSettings, SpeedCounter, SteadySignatures, WindowRecord, classify
from gerotor_twin.twin.meter_reading import MeterReading
from gerotor_twin.twin.outputs import FLOW_SUMMARY, HEALTH as HEALTH_TOPIC, HEALTH_UPDATE, OutputMessage, named_values
from gerotor_twin.twin.residual import FlowSamples

__all__ = ["HealthSettings", "HealthMonitor", "HEALTH_TOPIC", "HEALTH_FIELDS", "HEALTH_STATUS", "calibration_eta_rmse",
           "LEVELS", "alarm_intervals", "alarm_records", "fault_name", "fault_text",
           "tentative_rival"]

#: names of the health levels as logged in ``twin/health`` (``diagnostic_msgs/DiagnosticStatus`` levels)
LEVELS = {0: "OK", 1: "WARN", 2: "ERROR", 3: "STALE"}


def alarm_intervals(t, rows: list[dict]) -> list[tuple[str, float, float]]:
    """Maximal stretches of WARN or ERROR: (level name, start [s], end [s]) (end = last update at that level).

    Parameters
    ----------
    t : sequence of float
        Time of each health update [s].
    rows : list of dict
        The updates' fields (:data:`HEALTH_FIELDS`), ``level`` among them.
    """
    closed, prev = [], None
    for ti, r in zip(t, rows):
        name = LEVELS.get(int(r["level"]), "?")
        if prev is None or name != prev[0]:
            if prev is not None and prev[0] in ("WARN", "ERROR"):
                closed.append(prev)
            prev = (name, float(ti), float(ti))
        else:
            prev = (name, prev[1], float(ti))
    if prev is not None and prev[0] in ("WARN", "ERROR"):
        closed.append(prev)
    return closed


def alarm_records(t, rows: list[dict]) -> list[dict]:
    """The alarm intervals of :func:`alarm_intervals` with the fault named during each.

    The classifier names a kind at every update, and within one alarm the naming may change as evidence
    grows (a second operating point seen, the fault grown).  Per interval: ``start_s``, ``end_s`` [s],
    ``level``; ``fault`` and ``confidence``: the kind named at the interval's *last* update and its
    probability [-] (the most evidence the alarm had), with ``rival`` the kind it was not yet told apart from
    when that naming was tentative (:func:`tentative_rival`; else None); ``first_fault`` and ``first_confidence``: the
    naming at its first update; ``named_at_s`` [s]: the first update from which ``fault`` was named without
    interruption to the interval's end.  Kinds of :data:`~.diagnosis.KINDS`; None when the log carries no
    diagnosis or the update was not classified.

    Parameters
    ----------
    t : sequence of float
        Time of each health update [s].
    rows : list of dict
        The updates' fields (:data:`HEALTH_FIELDS`).
    """
    def named(r):
        fault, conf = fault_name(r), float(r.get("fault_confidence", math.nan))
        return (None, None) if fault == "-" else (fault, conf if math.isfinite(conf) else None)

    t = [float(ti) for ti in t]
    out = []
    for name, a, b in alarm_intervals(t, rows):
        i0 = t.index(a)
        i1 = next(i for i in range(i0, len(t)) if t[i] == b)
        (fault, conf), (first, first_conf) = named(rows[i1]), named(rows[i0])
        i = i1
        while i > i0 and named(rows[i - 1])[0] == fault:
            i -= 1
        out.append({"start_s": a, "end_s": b, "level": name, "fault": fault, "confidence": conf,
                    "rival": tentative_rival(rows[i1]), "first_fault": first,
                    "first_confidence": first_conf, "named_at_s": t[i]})
    return out


def fault_text(name: str | None, p: float | None, rival: str | None = None) -> str:
    """A fault the classifier named, with its probability ``p`` [-]: ``kind (0.93)`` (``-`` when none was); a
    tentative naming, not yet told apart from ``rival``: ``kind (0.71) or rival``."""
    if name in (None, "-"):
        return "-"
    text = name if p is None or not math.isfinite(p) else f"{name} ({p:.2f})"
    return text + (f" or {rival}" if rival else "")


def tentative_rival(row: dict) -> str | None:
    """The kind a tentative naming in one health update was not yet told apart from (``fault_rival`` when
    ``fault_tentative``); None otherwise (a firm naming, or a log without them)."""
    rival = fault_name({"fault": row.get("fault_rival", -1.0)})
    return rival if row.get("fault_tentative", 0.0) == 1.0 and rival != "-" else None


def fault_name(row: dict) -> str:
    """The fault named in one health update (:data:`~.diagnosis.KINDS`; ``-`` when none was)."""
    code = float(row.get("fault", -1.0))
    return KINDS[int(code)] if math.isfinite(code) and 0 <= int(code) < len(KINDS) else "-"


HEALTH_STATUS = "gerotor_twin: health"
HEALTH_FIELDS = ("leakage_factor", "leakage_factor_sd", "clearance_factor", "reference_efficiency",
                 "reference_efficiency_sd", "calibrated_reference_efficiency", "residual_m3s",
                 "residual_mean_m3s", "residual_rms_m3s", "innovation", "updates", "level", "fault",
                 "fault_confidence", "fault_rival", "fault_separation", "fault_tentative")
NS = 1_000_000_000


@dataclass(frozen=True)
class HealthSettings:
    """Settings of the health monitor (SI; efficiency thresholds in percentage points)."""
    enabled: bool = True
    adapt: bool = False
    window_s: float = 1.0
    settle_s: float = 1.0
    speed_tol: float = 0.01
    pressure_tol_pa: float = 50_000.0
    min_flow_samples: int = 3
    meter_sd_rel: float = 0.005
    model_sd_rel: float = 0.003
    drift_per_sqrt_s: float = 0.02
    initial_sd: float = 0.5
    warn_pt: float = 2.0
    error_pt: float = 5.0
    residual_band: float = 4.0
    band_updates: int = 5
    min_updates: int = 3
    residual_window: int = 20
    reference_rpm: float = 1500.0
    reference_bar: float = 20.0
    reference_oil_c: float = 50.0
    flow_sensor_tau_s: float = 0.0

    def __post_init__(self):
        check_ranges(self, "health_", (
            ("window_s", 0.05, 600.0), ("settle_s", 0.0, 600.0), ("speed_tol", 1e-4, 1.0), ("pressure_tol_pa", 1.0, 1e7),
            ("meter_sd_rel", 0.0, 1.0), ("model_sd_rel", 0.0, 1.0), ("drift_per_sqrt_s", 0.0, 10.0),
            ("initial_sd", 1e-6, 100.0), ("warn_pt", 0.0, 100.0), ("error_pt", 0.0, 100.0), ("residual_band", 0.1, 1e3),
            ("reference_rpm", 1.0, 1e5), ("reference_bar", 0.0, 1e3), ("reference_oil_c", -50.0, 300.0),
            ("flow_sensor_tau_s", 0.0, 60.0)))
        for name, lo, hi in (("min_flow_samples", 1, 10**6), ("band_updates", 1, 10**6), ("min_updates", 1, 10**6),
                             ("residual_window", 1, 10**6)):
            check_int(f"health_{name}", getattr(self, name), lo, hi)
        if self.error_pt < self.warn_pt:
            raise InputError("health_error_pt", self.error_pt, f"≥ health_warn_pt = {self.warn_pt:g}")

    def as_dict(self) -> dict:
        return asdict(self)

    def within(self, limits) -> "HealthSettings":
        """These settings with the reference point inside the pump's range ``limits`` (an ``OperatingRange``:
        the speed and delivery pressure each capped at its maximum; a 6-bar lube pump's reference is 6 bar)."""
        return replace(self, reference_rpm=min(self.reference_rpm, limits.max_speed_rpm),
                       reference_bar=min(self.reference_bar, limits.max_delivery_bar))


def clearance_exponent(model, settings: HealthSettings, step: float = 1.1) -> float:
    """Exponent n of the flow loss against a common clearance scale c at the reference point, L ∝ cⁿ [-].

    ≈ 3 for pure Poiseuille leakage; less where filling losses and Couette terms count.  Used to
    turn a leakage factor k into the clearance factor k^(1/n) (published, and applied by ``adapt``).
    """
    from gerotor_twin.model.clearance_scale import scale_clearances
    base = model.config
    loss0, _ = reference_loss(model, settings)
    try:
        scale_clearances(model, base, step)
        loss1, _ = reference_loss(model, settings)
    finally:
        scale_clearances(model, base, 1.0)
    n = math.log(loss1 / loss0) / math.log(step) if loss0 > 0 and loss1 > 0 else 3.0
    return n if math.isfinite(n) and n > 0.5 else 3.0


def calibration_eta_rmse(config) -> float:
    """Volumetric-efficiency RMSE [-] of the fit that produced ``config`` (its ``calibration`` block,
    written by ``gerotor-twin calibrate``): the larger of the fit's and, where the parameter set was chosen
    by cross-validation, the held-out one (``eta_rmse_heldout``); 0 when the config carries none."""
    out = 0.0
    for key in ("eta_rmse", "eta_rmse_heldout"):
        try:
            v = float(((getattr(config, "calibration", None) or {}).get("residuals") or {}).get(key, 0.0))
        except (TypeError, ValueError, AttributeError):
            continue
        out = max(out, v if math.isfinite(v) and 0.0 <= v < 1.0 else 0.0)
    return out


def reference_loss(model, settings: HealthSettings) -> tuple[float, float]:
    """Flow loss and theoretical flow [m³/s] of ``model`` at the reference point (periodic steady state).

    Computed at the reference oil temperature of the settings (``reference_oil_c``).
    """
    from gerotor_twin.units import celsius_to_kelvin
    from gerotor_twin.model.steady import run_steady
    settings = settings.within(model.config.range)
    t_model = getattr(model, "temperature_k", None)
    try:
        res = run_steady(model, settings.reference_rpm, settings.reference_bar,
                         oil_temperature=celsius_to_kelvin(settings.reference_oil_c))
    finally:
        if t_model is not None:
            model.set_temperature(t_model)          # the live model's properties stay where they were
    return res.theoretical_flow_m3s - res.mean_delivery_flow_m3s, res.theoretical_flow_m3s


@dataclass
class _Window:
    start_ns: int
    revs: int = 0
    q_pred: float = 0.0
    q_th: float = 0.0
    loss: float = 0.0
    ticks: int = 0
    op: tuple = (0.0, 0.0, 0.0, 0.0)     #: sums of omega, p_delivery, p_suction, oil temperature (K) over ticks
    oil_ticks: int = 0

    def add_inputs(self, inputs) -> None:
        """Accumulate the tick's operating point (the model's held inputs)."""
        t_oil = getattr(inputs, "oil_temperature", None)
        self.ticks += 1
        self.oil_ticks += t_oil is not None
        self.op = tuple(a + b for a, b in zip(self.op, (inputs.omega, inputs.p_delivery, inputs.p_suction,
                                                          0.0 if t_oil is None else t_oil)))


class HealthMonitor:
    """Settled-interval leakage estimation, reference efficiency and status (see module doc)."""

    def __init__(self, model, settings: HealthSettings | None = None, background: bool = False):
        """``background``: the fault classifier runs in a worker thread beside the caller's tick (the node: a
        classification holds the model thread up to a quarter second, docs/calibration_health.md), its naming
        published from the first update after it finished; False: in the tick, deterministic (replays,
        ``run-bag``)."""
        self.model = model
        self.background = background
        self._pool = None           # the worker (background), created on the first classification
        self._jobs: collections.deque = collections.deque()    # its classifications not yet collected (Futures)
        self.settings = s = (settings or HealthSettings()).within(model.config.range)
        self.base_config = model.config
        self.k_applied = 1.0
        ref = model.replica() if s.enabled else None     # the live model is written by the twin's steps only
        self.loss_ref, self.qth_ref = reference_loss(ref, s) if s.enabled else (math.nan, math.nan)
        self.exponent = clearance_exponent(ref, s) if s.enabled else 3.0
        self.est = lf.LeakageEstimate(var=s.initial_sd ** 2)
        self.eta_rmse_cal = calibration_eta_rmse(model.config)
        self._flow = FlowSamples()
        self._res: collections.deque = collections.deque(maxlen=s.residual_window)
        self._ref = None            # (omega, p_delivery) the steady stretch started with
        self._steady_since: int | None = None
        self._win: _Window | None = None
        self._out_of_band = 0
        self.last_residual = math.nan
        self.history: list[dict] = []
        self.windows: list[WindowRecord] = []
        self.signatures: list[dict] = []
        self.diagnosis: Diagnosis | None = None
        self._signature_of = None
        self._speed = SpeedCounter()
        #: the model's revolution-mean delivery, theoretical flow and loss [m³/s] as the bench's flow meter reads them
        #: (the meter reads q_th − k·loss as lag(q_th) − k·lag(loss)), so that a window compares like with like
        self._meter = MeterReading(s.flow_sensor_tau_s)

    # ------------------------------------------------------------- inputs
    def add_flow(self, value_m3s: float, receive_ns: int) -> None:
        """A measured delivery flow sample [m³/s] (accepted by the input book)."""
        self._flow.add(value_m3s, receive_ns)

    def add_speed(self, receive_ns: int) -> None:
        """A shaft-speed sample was accepted at ``receive_ns`` [ns] (input accounting for the diagnosis)."""
        self._speed.add(receive_ns)

    def clock_jumped_back(self, now_ns: int) -> None:
        """The clock went back to ``now_ns`` [ns] (a bag loop): flow samples received after it are forgotten."""
        self._flow.forget_after(now_ns)
        self._speed.forget_after(now_ns)
        self._meter.reset()

    def observe(self, now_ns: int, inputs, messages) -> list[OutputMessage]:
        """After a tick: track steadiness, collect revolution summaries, update at window ends."""
        if not self.settings.enabled:
            return []
        self._track_steady(now_ns, inputs)
        w = self._win
        if w is None:
            self._win = _Window(now_ns)
            return []
        if inputs is not None:
            w.add_inputs(inputs)
        for msg in messages:
            if msg.topic != FLOW_SUMMARY:
                continue
            q, qth, loss = self._meter.read(msg.stamp_ns, msg.msg["data"][:3])
            if msg.stamp_ns >= w.start_ns:
                w.revs += 1
                w.q_pred += q
                w.q_th += qth
                w.loss += loss
        if now_ns - w.start_ns < self.settings.window_s * NS:
            return []
        self._win = _Window(now_ns)
        return self._close(w, now_ns)

    def _track_steady(self, now_ns: int, inputs) -> None:
        s = self.settings
        if inputs is None:
            self._ref, self._steady_since = None, None
            return
        if self._ref is not None:
            w0, p0 = self._ref
            if abs(inputs.omega - w0) <= s.speed_tol * max(abs(w0), 1.0) and abs(inputs.p_delivery - p0) <= s.pressure_tol_pa:
                return
        self._ref, self._steady_since = (inputs.omega, inputs.p_delivery), now_ns

    # ------------------------------------------------------------- update
    def _close(self, w: _Window, end_ns: int) -> list[OutputMessage]:
        s = self.settings
        if self._steady_since is None or w.start_ns - self._steady_since < s.settle_s * NS or w.revs == 0:
            return []
        samples = self._flow.between(w.start_ns, end_ns)
        self._flow.drop_before(w.start_ns)
        if len(samples) < s.min_flow_samples:
            return []
        q_meas = sum(samples) / len(samples)
        q_pred, q_th, loss = w.q_pred / w.revs, w.q_th / w.revs, w.loss / w.revs
        r = (s.meter_sd_rel * q_meas) ** 2 / len(samples) + max((s.model_sd_rel * q_meas) ** 2,
                                                                   (self.eta_rmse_cal * q_th) ** 2)
        est = lf.predict(self.est, end_ns / NS, s.drift_per_sqrt_s)
        self.est = lf.update(est, q_th - q_meas, loss / self.k_applied, max(r, 1e-18))
        self.last_residual = q_meas - q_pred
        self._diagnose(w, end_ns, q_meas, q_pred, q_th, math.sqrt(max(r, 1e-18)))
        self._res.append(self.last_residual)
        self._out_of_band = self._out_of_band + 1 if abs(self.est.innovation) > s.residual_band else 0
        if s.adapt and self.est.updates >= s.min_updates and abs(self.est.k / self.k_applied - 1) > 0.01:
            self._adapt(self.est.k)
        values = self.values()
        self.history.append({"t_ns": end_ns, **dict(zip(HEALTH_FIELDS, values))})
        return [OutputMessage(HEALTH_TOPIC, m.FLOAT64_MULTIARRAY, end_ns,
                              m.float64_multiarray(values, (",".join(HEALTH_FIELDS),))),
                named_values(HEALTH_UPDATE, end_ns, HEALTH_FIELDS, values)]

    def _diagnose(self, w: _Window, end_ns: int, q_meas: float, q_pred: float, q_th: float, sd: float) -> None:
        """Record the window (:class:`~.diagnosis.WindowRecord`) and classify the recent ones (not with adapt:
        the residuals are then against a moving model)."""
        got, expected = self._speed.count(w.start_ns, end_ns)
        n = max(w.ticks, 1)
        rec = WindowRecord(end_ns / NS, w.op[0] / n, w.op[1] / n, w.op[2] / n,
                           w.op[3] / w.oil_ticks if w.oil_ticks else None, q_meas, q_pred, q_th, sd, got, expected)
        if self.settings.adapt or w.ticks == 0:
            return
        if not self.background:
            self._classify(rec)
            return
        self._raise_failed()
        if self._pool is None:
            from concurrent.futures import ThreadPoolExecutor
            self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="gerotor_twin_diagnosis")
        self._jobs.append(self._pool.submit(self._classify, rec))     # one worker: the windows in their order

    def _raise_failed(self) -> None:
        """Re-raise here what a finished background classification raised (as the tick would have)."""
        while self._jobs and self._jobs[0].done():
            self._jobs.popleft().result()

    def wait(self, timeout: float | None = None) -> None:
        """Wait for the background classifications not yet finished, if any, and re-raise an error of theirs
        (``timeout`` [s] for each)."""
        while self._jobs:
            self._jobs[0].result(timeout)
            self._jobs.popleft()

    def close(self) -> None:
        """Stop the background worker (after the classification running now)."""
        if self._pool is not None:
            self._pool.shutdown(wait=True)
            self._pool = None

    def _classify(self, rec: WindowRecord) -> None:
        """Add ``rec`` to the recent windows with its signatures and name the fault (``self.diagnosis``)."""
        s = self.settings
        try:
            if self._signature_of is None:
                self._signature_of = SteadySignatures(
                    self.base_config, getattr(self.model, "bearing_name", "mobility"),
                    DiagnosisSettings(point_speed_tol=s.speed_tol, point_pressure_pa=s.pressure_tol_pa),
                    reference=(s.reference_rpm, s.reference_bar, s.reference_oil_c))
            signature = self._signature_of(rec)
        except InputError:
            return                  # outside the pump's range (a steady model cannot run there): not classified
        self.windows.append(rec)
        self.signatures.append(signature)
        keep = self._signature_of.settings.horizon
        del self.windows[:-keep], self.signatures[:-keep]
        self.diagnosis = classify(self.windows, self.signatures, self._signature_of.settings,
                                  relinearise=self._signature_of.relinearised)

    def _adapt(self, k: float) -> None:
        from gerotor_twin.model.clearance_scale import scale_clearances
        self.k_applied = max(k, 1e-3)
        scale_clearances(self.model, self.base_config, self.k_applied ** (1.0 / self.exponent))

    # ------------------------------------------------------------- figures
    def reference_efficiency(self, k: float) -> float:
        """Volumetric efficiency at the reference point with leakage factor ``k`` [-]."""
        return 1.0 - k * self.loss_ref / self.qth_ref

    def drop_pt(self) -> float:
        """Fall of the reference efficiency from the calibrated value [percentage points]."""
        return 100.0 * (self.reference_efficiency(1.0) - self.reference_efficiency(self.est.k))

    def alarm_drop_pt(self) -> float:
        """The loss at the reference point the status level judges [percentage points].

        Once the classifier names a fault of the flow (:data:`~.diagnosis.FLOW_KINDS`, seen at two operating
        points or more), that fault's loss there at its fitted size (the latest window's θ,
        :meth:`~.diagnosis.SteadySignatures.reference_loss`); while the windows are at one operating point, where
        every candidate kind fits the residual and carries it to the reference point by its own law, the smallest
        of their losses; otherwise (nothing classified, no kind fits, healthy) the leakage factor's (:meth:`drop_pt`).
        The leakage factor reads every loss as leakage, whose share grows with the delivery pressure, so it
        extrapolates a meter gain, air or a pressure offset seen at a low pressure to a larger loss at the
        reference point and one seen at a high pressure to a smaller one: the level would change with the
        operating point under a constant fault.  A tentative naming (the windows cannot yet tell the named kind
        from its rival, :attr:`~.diagnosis.Diagnosis.tentative`) is judged by the smaller of the two kinds' losses
        at their fitted sizes: the loss the windows support whichever of them is the fault (at one operating point
        every candidate kind is such a rival)."""
        d, sig = self.diagnosis, self._signature_of
        if d is not None and sig is not None and d.kind in FLOW_KINDS and d.kind in d.parameter:
            loss = sig.reference_loss(d.kind, d.parameter[d.kind])
            if d.tentative and d.rival in d.parameter:
                loss = min(loss, sig.reference_loss(d.rival, d.parameter[d.rival]))
            return 100.0 * loss
        if d is not None and sig is not None and d.kind == "unknown" and d.points == 1:
            losses = [sig.reference_loss(k, d.parameter[k]) for k in FLOW_KINDS if k in d.log_likelihood]
            if losses:              # one operating point: every candidate kind is a rival
                return 100.0 * min(losses)
        return self.drop_pt()

    def level(self) -> int:
        s = self.settings
        if self.est.updates < s.min_updates:
            return m.DIAG_STALE
        drop = self.alarm_drop_pt()
        if drop > s.error_pt:
            return m.DIAG_ERROR
        if drop > s.warn_pt or self._out_of_band >= s.band_updates:
            return m.DIAG_WARN
        return m.DIAG_OK

    def values(self) -> list[float]:
        """The :data:`HEALTH_FIELDS` values now."""
        e = self.est
        res = list(self._res)
        mean = sum(res) / len(res) if res else math.nan
        rms = math.sqrt(sum(v * v for v in res) / len(res)) if res else math.nan
        return [e.k, e.sd, max(e.k, 0.0) ** (1 / self.exponent), self.reference_efficiency(e.k), e.sd * self.loss_ref / self.qth_ref,
                self.reference_efficiency(1.0), self.last_residual, mean, rms, e.innovation, float(e.updates),
                float(self.level()), *self.fault_values()]

    def fault_values(self) -> tuple[float, ...]:
        """The diagnosis as published: code of the named kind (index in :data:`~.diagnosis.KINDS`, −1: not
        classified) and its probability [-]; the code of its closest rival (−1: none), their separation [-]
        (:func:`~.diagnosis.separation`; NaN: none) and 1.0 when the naming is tentative (else 0.0)."""
        d = self.diagnosis
        if d is None:
            return -1.0, math.nan, -1.0, math.nan, 0.0
        rival = float(KIND_CODES[d.rival]) if d.rival else -1.0
        return float(d.code), d.confidence, rival, d.separation, float(d.tentative)

    def status(self) -> dict:
        """``diagnostic_msgs/DiagnosticStatus`` dict ``gerotor_twin: health``."""
        s = self.settings
        lvl = self.level()
        v = dict(zip(HEALTH_FIELDS, self.values()))
        if lvl == m.DIAG_STALE:
            text = (f"learning: {self.est.updates} of {s.min_updates} settled intervals with measured flow "
                    "(needs bench/delivery_flow and steady operation)")
        else:
            text = (f"leakage factor {v['leakage_factor']:.3f} ± {v['leakage_factor_sd']:.3f}; efficiency at "
                    f"{s.reference_rpm:g} rpm / {s.reference_bar:g} bar {100 * v['reference_efficiency']:.2f} % "
                    f"({self.drop_pt():+.2f} pt below calibrated; WARN > {s.warn_pt:g}, ERROR > {s.error_pt:g})")
            if self._out_of_band >= s.band_updates:
                text += f"; residual outside ±{s.residual_band:g} σ for {self._out_of_band} intervals"
            if self.diagnosis is not None:
                d = self.diagnosis
                text += f"; fault: {d.kind} (probability {d.confidence:.2f} over {d.windows} intervals)"
                if d.tentative:
                    text += (f", tentative: not yet told apart from {d.rival} at the operating points seen "
                             f"(separation {d.separation:.1f})")
                if d.kind in FLOW_KINDS:
                    text += f", its loss at the reference point {self.alarm_drop_pt():+.2f} pt (the level's)"
        vals = {k: f"{x:.6g}" for k, x in v.items()}
        vals.update({"adapt": str(s.adapt).lower(), "reference_rpm": f"{s.reference_rpm:g}",
                     "reference_bar": f"{s.reference_bar:g}", "reference_oil_c": f"{s.reference_oil_c:g}",
                     "drop_pt": f"{self.drop_pt():.3f}", "alarm_drop_pt": f"{self.alarm_drop_pt():.3f}",
                     "model_eta_sd_from_calibration": f"{self.eta_rmse_cal:.4g}"})
        if self.diagnosis is not None:
            vals.update({"fault": self.diagnosis.kind, "speed_samples_missing": f"{self.diagnosis.dropout:.4f}"})
        return m.diagnostic_status(lvl, HEALTH_STATUS, text, values=vals)
