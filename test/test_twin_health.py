"""Online health (twin/health.py, leakage_filter.py): the filter, the settled-interval gate, status, adapt, settings."""
import math

import numpy as np
import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.model.pump import Inputs
from gerotor_twin.ros.params import PARAMETERS, health_settings
from gerotor_twin.twin import leakage_filter as lf
from gerotor_twin.twin.diagnosis import KINDS
from gerotor_twin.twin.health import HEALTH_FIELDS, HEALTH_STATUS, HealthMonitor, HealthSettings
from gerotor_twin.twin.outputs import HEALTH, summary

NS = 1_000_000_000


def test_kalman_constant_parameter_closed_form():
    """Closed form: without drift, n equal measurements give the precision-weighted mean and
    variance 1/(1/P0 + n H²/R)."""
    est = lf.LeakageEstimate(k=1.0, var=0.25)
    h, r, ys = 2.0, 0.01, [2.6, 2.8, 2.7, 2.5]
    for i, y in enumerate(ys):
        est = lf.update(lf.predict(est, float(i), 0.0), y, h, r)
    prec = 1 / 0.25 + len(ys) * h * h / r
    assert est.var == pytest.approx(1 / prec, rel=1e-12)
    assert est.k == pytest.approx((1.0 / 0.25 + sum(h * y for y in ys) / r) / prec, rel=1e-12)
    assert est.updates == 4


def test_kalman_random_walk_variance_grows_by_drift():
    """Closed form: the prediction adds drift² · Δt to the variance."""
    est = lf.predict(lf.LeakageEstimate(var=0.01, t_s=2.0), 6.0, 0.05)
    assert est.var == pytest.approx(0.01 + 0.05 ** 2 * 4.0)


class Feed:
    """Drives a HealthMonitor the way TwinCore does: ticks of 10 ms, a revolution summary every
    40 ms, a flow-meter sample every 50 ms (a pump whose leakage is ``k`` × the model's)."""

    def __init__(self, monitor, qth=5e-4, loss=1e-4):
        self.mon, self.qth, self.loss, self.t = monitor, qth, loss, 0
        self.messages = []

    def run(self, seconds, k, omega=157.0, p=2.1e6, meter=None):
        end = self.t + int(seconds * NS)
        while self.t < end:
            self.t += 10_000_000
            msgs = []
            if self.t % 40_000_000 == 0:
                msgs.append(summary(self.t, [self.qth - self.loss, self.qth, self.loss, 1 - self.loss / self.qth]))
            if self.t % 50_000_000 == 0:
                self.mon.add_flow(meter(self.t) if meter else self.qth - k * self.loss, self.t)
            w = omega(self.t) if callable(omega) else omega
            self.messages += self.mon.observe(self.t, Inputs(w, 1e5, p), msgs)
        return self


@pytest.fixture()
def monitor(fixed_model):
    return HealthMonitor(fixed_model, HealthSettings())


def test_tracks_leakage_factor_on_steady_operation(monitor):
    """Behaviour: steady operation with 30 % more leakage than the model: k → 1.30 within 2 σ, status follows
    the reference-efficiency drop (STALE while learning, then a level from the thresholds)."""
    f = Feed(monitor).run(0.5, 1.3)
    assert monitor.level() == m.DIAG_STALE
    f.run(12.0, 1.3)
    est = monitor.est
    assert abs(est.k - 1.3) < 2 * est.sd + 1e-3 and est.updates >= 8
    drop = 100 * 0.3 * monitor.loss_ref / monitor.qth_ref
    assert monitor.drop_pt() == pytest.approx(drop, abs=0.2)
    # one operating point: the level judges the smallest loss a candidate kind carries to the reference point,
    # no more than the leakage factor's (a leakage is among the candidates)
    judged = monitor.alarm_drop_pt()
    assert 0.0 < judged <= monitor.drop_pt() + 1e-9
    want = m.DIAG_ERROR if judged > 5 else m.DIAG_WARN if judged > 2 else m.DIAG_OK
    assert monitor.level() == want
    msg, named = f.messages[-2:]
    assert msg.topic == HEALTH and msg.msg["layout"]["dim"][0]["label"] == ",".join(HEALTH_FIELDS)
    v = dict(zip(HEALTH_FIELDS, msg.msg["data"]))
    # the same values by name, stamped with the end of the interval (twin/health_update)
    assert named.topic == "twin/health_update" and named.stamp_ns == msg.stamp_ns
    assert named.msg["header"]["stamp"] == m.stamp_from_ns(msg.stamp_ns)
    np.testing.assert_equal(dict(zip(named.msg["name"], named.msg["position"])), v)     # NaN: no rival at one point
    assert v["clearance_factor"] == pytest.approx(v["leakage_factor"] ** (1 / monitor.exponent))
    st = monitor.status()
    assert st["name"] == HEALTH_STATUS and st["level"] == want
    # every update's window recorded and classified: one operating point, so a fault of unknown kind
    assert len(monitor.windows) == est.updates and monitor.windows[-1].omega == pytest.approx(157.0)
    assert KINDS[int(v["fault"])] == "unknown" and v["fault_confidence"] > 0.9
    assert "fault: unknown (probability" in st["message"]
    assert {kv["key"]: kv["value"] for kv in st["values"]}["fault"] == "unknown"


def test_classifier_in_background_leaves_the_tick_free(fixed_model, monkeypatch):
    """Behaviour: with ``background`` the fault classifier runs in a worker thread: while a classification is
    held (a stand-in that waits for the test's release), the monitor goes on updating the leakage factor and
    publishes no naming yet; once released, every window is classified in its order and the naming is the
    classifier's.  Inside the tick (the default), the first update would wait for the release instead."""
    import threading
    from gerotor_twin.twin import health as health_module
    from gerotor_twin.twin.diagnosis import Diagnosis
    started, release, seen = threading.Event(), threading.Event(), []

    def held_classify(windows, signatures, settings=None, relinearise=None):
        started.set()
        release.wait(20.0)
        seen.append(len(windows))
        return Diagnosis("tip_wear", 0.9, {}, {}, {}, 1.0, len(windows))

    monkeypatch.setattr(health_module, "classify", held_classify)
    mon = HealthMonitor(fixed_model, HealthSettings(), background=True)
    try:
        Feed(mon).run(6.0, 1.2)
        assert started.wait(20.0)
        assert mon.est.updates >= 3 and seen == []                    # updates went on while it was held
        assert mon.diagnosis is None and mon.fault_values()[0] == -1.0
        release.set()
        mon.wait(20.0)
        assert seen == list(range(1, mon.est.updates + 1))            # every window, in order
        assert mon.diagnosis.kind == "tip_wear" and KINDS[int(mon.fault_values()[0])] == "tip_wear"
    finally:
        release.set()
        mon.close()


def test_window_outside_the_range_is_not_classified(monitor):
    """Behaviour: a settled window above the pump's speed range still updates k but is not classified (the
    steady model cannot run there); the monitor keeps running."""
    Feed(monitor).run(4.0, 1.0, omega=400.0)          # 3820 rpm > 3000 rpm
    assert monitor.est.updates >= 1 and monitor.windows == [] and monitor.fault_values()[0] == -1.0


def test_ramps_and_meter_lag_are_not_used(monitor):
    """Behaviour: during a speed ramp no update happens; after the ramp the first settle_s (meter still
    lagging: it reads a wrong flow then) are ignored too, so the estimate is that of the true pump."""
    f = Feed(monitor)
    f.run(6.0, 1.0, omega=lambda t: 100.0 + 10.0 * t / NS)       # 10 rad/s² ramp all along
    assert monitor.est.updates == 0
    t_ramp_end = f.t
    lagging = lambda t: f.qth - (1.0 if t - t_ramp_end > 0.9 * NS else 3.0) * f.loss
    f.run(6.0, 1.0, omega=160.0, meter=lagging)
    assert monitor.est.updates >= 3
    assert abs(monitor.est.k - 1.0) < 0.02


def test_no_flow_meter_stays_stale(monitor):
    """Behaviour: without measured flow the monitor never claims health: STALE, message says why."""
    f = Feed(monitor)
    f.mon.add_flow = lambda *a: None
    f.run(5.0, 1.0)
    st = monitor.status()
    assert st["level"] == m.DIAG_STALE and "delivery_flow" in st["message"]


def test_adapt_feeds_back_into_model(fixed_model):
    """Behaviour: adapt=true gives the model clearances × k^(1/n) (n: loss exponent at the reference point,
    between 1 and 3); adapt=false leaves them alone."""
    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    model = PumpModel(load_config(), "fixed")
    tip0 = model.config.clearances.tooth_tip_m
    mon = HealthMonitor(model, HealthSettings(adapt=True))
    Feed(mon).run(8.0, 1.3)
    assert 1.0 < mon.exponent <= 3.2
    c = mon.k_applied ** (1 / mon.exponent)
    assert mon.k_applied > 1.2
    assert model.config.clearances.tooth_tip_m == pytest.approx(tip0 * c)
    assert model.kernel.pc.tip_clearance == pytest.approx(tip0 * c)
    assert mon.fault_values()[0] == -1.0 and mon.diagnosis is None       # adapt: the residuals are not classified
    mon2 = HealthMonitor(fixed_model, HealthSettings())
    Feed(mon2).run(8.0, 1.3)
    assert fixed_model.config.clearances.tooth_tip_m == tip0


@pytest.mark.parametrize("kw, field", [({"warn_pt": -1.0}, "health_warn_pt"),
                                       ({"warn_pt": 3.0, "error_pt": 2.0}, "health_error_pt"),
                                       ({"window_s": math.nan}, "health_window_s"),
                                       ({"min_updates": 0}, "health_min_updates")])
def test_bad_settings_named(kw, field):
    """Bad input: each bad setting raises one InputError naming the node parameter."""
    with pytest.raises(InputError, match=field):
        HealthSettings(**kw)


def test_node_parameters_map_onto_settings():
    """Behaviour: every health_* node parameter is a HealthSettings field with the same default."""
    prm = {p.name: p.default for p in PARAMETERS}
    hs = health_settings(prm)
    for p in PARAMETERS:
        if p.name.startswith("health_"):
            assert getattr(hs, p.name[len("health_"):]) == p.default


def test_model_error_floored_at_the_calibration_residual(monkeypatch):
    """Closed form: with a calibrated config (calibration.residuals.eta_rmse = e) every update's noise
    variance is (meter_sd·q)²/n + max((model_sd·q)², (e·q_th)²), q the measured mean, n its samples; a
    cross-validated calibration's held-out RMSE floors it when larger than the fit's."""
    from pathlib import Path

    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.twin.health import calibration_eta_rmse
    cfg = load_config(Path(__file__).resolve().parent.parent / "bags" / "pump_fitted_bench_map.yaml")
    res = cfg.calibration["residuals"]
    e = max(res["eta_rmse"], res.get("eta_rmse_heldout", 0.0))      # the shipped fit is cross-validated
    assert calibration_eta_rmse(cfg) == e > 0
    assert calibration_eta_rmse(load_config()) == 0.0              # uncalibrated: no floor
    from dataclasses import replace
    held = replace(cfg, calibration={"residuals": {"eta_rmse": e, "eta_rmse_heldout": 3 * e}})
    assert calibration_eta_rmse(held) == 3 * e                      # cross-validated: the held-out error
    seen = []
    real_update = lf.update
    monkeypatch.setattr(lf, "update", lambda est, y, h, r: seen.append(r) or real_update(est, y, h, r))
    for model_sd in (0.0, 0.05):                                  # floor binding, then the setting
        seen.clear()
        s = HealthSettings(model_sd_rel=model_sd)
        f = Feed(HealthMonitor(PumpModel(cfg, "fixed"), s)).run(4.0, 1.2)
        q, n = f.qth - 1.2 * f.loss, 20                           # 1 s windows, a meter sample every 50 ms
        want = (s.meter_sd_rel * q) ** 2 / n + max((model_sd * q) ** 2, (e * f.qth) ** 2)
        assert seen and all(r == pytest.approx(want, rel=1e-9) for r in seen)


def test_reference_point_capped_at_the_pumps_range(cfg):
    """Behaviour: a pump rated below the default reference point (20 bar, 1500 rpm) gets its health
    reference at the top of its own range instead of an error at start (a 6-bar lube pump of the family)."""
    from dataclasses import replace as _replace
    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.twin.health import HealthMonitor, HealthSettings
    small = _replace(cfg, range=_replace(cfg.range, max_speed_rpm=1200.0, max_delivery_bar=6.0))
    mon = HealthMonitor(PumpModel(small, "fixed"), HealthSettings())
    assert (mon.settings.reference_rpm, mon.settings.reference_bar) == (1200.0, 6.0)
    assert 0.0 < mon.loss_ref < mon.qth_ref


def test_the_reference_point_and_the_startup_check_leave_the_live_model_as_it_is(fixed_model):
    """Behaviour: the health monitor's reference point and clearance exponent (a steady run, the clearances scaled
    and back) and the start-up real-time check (revolutions at the range's extremes) run on a replica sharing the
    tables; the twin's model keeps its kernel, config, temperature and every workspace array bit for bit, so only
    the twin's own steps write it."""
    import numpy as np
    from gerotor_twin.twin import TwinCore, TwinSettings
    m = fixed_model
    kernel, config, temp = m.kernel, m.config, m.temperature_k
    ws = {f: np.array(getattr(m._ws, f), copy=True) for f in m._ws._fields}
    core = TwinCore(m, TwinSettings())
    assert core.health is not None and math.isfinite(core.health.loss_ref)
    core.measure_startup_rtf(0.5, budget_s=0.3)
    assert m.kernel is kernel and m.config is config and m.temperature_k == temp
    for f, before in ws.items():
        assert np.array_equal(getattr(m._ws, f), before, equal_nan=True), f
    assert m.replica().tables is m.tables


def test_the_level_judges_the_named_faults_loss(monitor):
    """Behaviour: the status level judges the leakage factor's drop until the classifier names a fault of the flow,
    then that fault's loss at the reference point (``alarm_drop_pt``: the fitted θ through
    ``SteadySignatures.reference_loss``); ``unknown`` and ``healthy`` leave it to the leakage factor.  Here the
    pump leaks as the model does (drop ≈ 0) and a named meter gain whose θ stands for a 6 pt loss raises ERROR,
    one for 3 pt WARN."""
    from types import SimpleNamespace
    from gerotor_twin.twin.diagnosis import Diagnosis
    Feed(monitor).run(6.0, 1.0)
    assert abs(monitor.drop_pt()) < 1.0 and monitor.level() == m.DIAG_OK
    monitor._signature_of = SimpleNamespace(reference_loss=lambda kind, theta: -theta)   # a meter gain's sign
    for theta, want in ((-0.06, m.DIAG_ERROR), (-0.03, m.DIAG_WARN), (0.01, m.DIAG_OK)):
        monitor.diagnosis = Diagnosis("flowmeter_drift", 0.99, {}, {}, {"flowmeter_drift": theta}, 1.0, 12)
        assert monitor.alarm_drop_pt() == pytest.approx(-100 * theta)
        assert monitor.level() == want
    assert "its loss at the reference point +3.00 pt" not in monitor.status()["message"]
    monitor.diagnosis = Diagnosis("flowmeter_drift", 0.99, {}, {}, {"flowmeter_drift": -0.03}, 1.0, 12)
    assert "its loss at the reference point +3.00 pt" in monitor.status()["message"]
    for kind in ("unknown", "healthy"):
        monitor.diagnosis = Diagnosis(kind, 0.99, {}, {}, {"flowmeter_drift": -0.06}, 1.0, 12)
        assert monitor.alarm_drop_pt() == monitor.drop_pt() and monitor.level() == m.DIAG_OK


def test_a_tentative_naming_is_judged_by_the_smaller_loss(monitor):
    """Closed form: the level's loss is the named fault's at its fitted size; when the naming is tentative (its rival
    not yet excluded) the smaller of the two kinds' losses, the one the windows support whichever is the fault; at one
    operating point the smallest over the candidate kinds; when no kind fits, the leakage factor's."""
    from gerotor_twin.twin.diagnosis import Diagnosis

    class Losses:                       # SteadySignatures.reference_loss with θ read as the loss itself
        @staticmethod
        def reference_loss(kind, theta):
            return theta
    monitor._signature_of = Losses()
    theta = {"air_ingress": 0.07, "pressure_offset": 0.03}
    firm = Diagnosis("air_ingress", 0.9, {}, {}, theta, 1.0, 8, rival="pressure_offset", separation=9.0)
    monitor.diagnosis = firm
    assert monitor.alarm_drop_pt() == pytest.approx(7.0)
    monitor.diagnosis = Diagnosis("air_ingress", 0.8, {}, {}, theta, 1.0, 8, rival="pressure_offset",
                                  separation=1.5, tentative=True)
    assert monitor.alarm_drop_pt() == pytest.approx(3.0)
    # one operating point: every candidate kind (in the log-likelihoods) is a rival; nothing fits: the leakage factor's
    theta = {"tip_wear": 0.09, "lateral_wear": 0.08, "air_ingress": 0.05, "flowmeter_drift": 0.04, "pressure_offset": 0.01}
    ll = {"healthy": -50.0, "unknown": -20.0, **{k: -10.0 for k in theta if k != "pressure_offset"}}
    monitor.diagnosis = Diagnosis("unknown", 1.0, ll, {}, theta, 1.0, 8, points=1)
    assert monitor.alarm_drop_pt() == pytest.approx(4.0)        # the offset is no candidate here (not in ll)
    monitor.diagnosis = Diagnosis("unknown", 1.0, ll, {}, theta, 99.0, 8, points=3)
    assert monitor.alarm_drop_pt() == monitor.drop_pt()
