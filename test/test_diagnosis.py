"""Fault classifier (gerotor_twin.twin.diagnosis): the likelihood in closed form, the named kind on window records.

The behaviour tests build the settled windows of a faulty pump from the twin's own steady model (the fault
applied in full, not linearised: tip clearance × 2 or lateral × 1.15, 3 % free air, a 1 bar transducer offset, a 5 %
meter gain) at four operating points (1000 / 2500 rpm × 5 / 25 bar, 50 °C), with the monitor's noise, and
check that the classifier names the fault.
"""
import math

import numpy as np
import pytest

from gerotor_twin.config import load_config
from gerotor_twin.errors import InputError
from gerotor_twin.twin.diagnosis import (DiagnosisSettings, FLOW_KINDS, KINDS, KIND_CODES, SpeedCounter, SteadySignatures,
                                         WindowRecord, _fit_kind, classify, fitted_residuals, kind_log_likelihood,
                                         missing_fraction, operating_points, point_key, separation)
from gerotor_twin.twin.health import alarm_records, fault_text, tentative_rival
from gerotor_twin.offline.diagnosis_bench import (MODEL_CASES as CASES, POINTS, alarm_summary, crossing_time,
                                                 main as bench_main, model_records, reference_loss, severity_for)

REL_SD = 0.003          #: the monitor's model-error floor (HealthSettings.model_sd_rel)


def test_likelihood_closed_form():
    """Closed form: with zero drift the Kalman likelihood of a pure flow-meter gain is the marginal likelihood
    log N(e; 0, diag σ² + P0·q qᵀ) and the fitted gain the Gaussian posterior mean Σqe/σ² / (1/P0 + Σq²/σ²)."""
    rng = np.random.default_rng(1)
    q = rng.uniform(1e-4, 1e-3, 12)
    sd = 0.004 * q
    e = 0.05 * q + rng.normal(0.0, sd)
    p0 = 0.2
    ll, g, g_sd, _ = kind_log_likelihood(e, q, sd, np.arange(12.0), p0, 0.0)
    cov = np.diag(sd ** 2) + p0 ** 2 * np.outer(q, q)
    sign, logdet = np.linalg.slogdet(cov)
    expected = -0.5 * (e @ np.linalg.solve(cov, e) + logdet + len(e) * math.log(2 * math.pi))
    assert sign > 0 and ll == pytest.approx(expected, rel=1e-9)
    info = 1 / p0 ** 2 + np.sum(q * q / sd ** 2)
    assert g == pytest.approx(np.sum(q * e / sd ** 2) / info, rel=1e-9)
    assert g_sd == pytest.approx(info ** -0.5, rel=1e-9)
    assert g == pytest.approx(0.05, abs=3 * g_sd)


def test_trend_likelihood_closed_form():
    """Closed form: with zero drift and a growth rate r ~ N(0, R0²) the Kalman likelihood is the marginal
    likelihood log N(e; 0, diag σ² + P0·d dᵀ + R0²·(d∘τ)(d∘τ)ᵀ), τ the time since the first window, and the
    final θ the posterior mean of θ0 + r·τ_n; a ramp of the fault fits far better than with r fixed at 0."""
    rng = np.random.default_rng(2)
    n = 16
    d = rng.uniform(1e-4, 1e-3, n)
    t = 0.5 * np.arange(n) + 3.0
    sd = 0.003 * d
    e = d * 0.01 * (t - t[0]) + rng.normal(0.0, sd)           # θ grows by 0.01 per second
    p0, r0 = 0.2, 0.2 / (t[-1] - t[0])
    ll, th, th_sd, _ = kind_log_likelihood(e, d, sd, t, p0, 0.0, r0)
    x = np.column_stack([d, d * (t - t[0])])
    cov = np.diag(sd ** 2) + x @ np.diag([p0 ** 2, r0 ** 2]) @ x.T
    expected = -0.5 * (e @ np.linalg.solve(cov, e) + np.linalg.slogdet(cov)[1] + n * math.log(2 * math.pi))
    assert ll == pytest.approx(expected, rel=1e-9)
    info = np.diag([p0 ** -2, r0 ** -2]) + x.T @ np.diag(sd ** -2) @ x
    post = np.linalg.solve(info, x.T @ (e / sd ** 2))
    last = np.array([1.0, t[-1] - t[0]])
    assert th == pytest.approx(last @ post, rel=1e-7)
    assert th_sd == pytest.approx(math.sqrt(last @ np.linalg.solve(info, last)), rel=1e-7)
    assert th == pytest.approx(0.01 * (t[-1] - t[0]), abs=3 * th_sd)
    assert ll > kind_log_likelihood(e, d, sd, t, p0, 0.0)[0] + 20.0


def test_drift_forgets():
    """Closed form: a random walk widens the prior between updates by drift²·Δt (one update after a gap)."""
    ll0, th0, sd0, _ = kind_log_likelihood([0.0, 1.0], [1.0, 1.0], [1.0, 1.0], [0.0, 4.0], 1.0, 0.0)
    ll1, th1, sd1, _ = kind_log_likelihood([0.0, 1.0], [1.0, 1.0], [1.0, 1.0], [0.0, 4.0], 1.0, 0.5)
    # after the first update P = 1/2; before the second P = 1/2 (+ 0.25·4 with drift)
    assert th0 == pytest.approx(0.5 / 1.5) and th1 == pytest.approx(1.5 / 2.5)
    assert sd1 ** 2 == pytest.approx(1.5 / 2.5)


def test_missing_speed_samples():
    """Closed form: every fifth sample of a 100 Hz sensor missing → 20 %; none missing → 0; samples received in
    bursts → no expected count."""
    c = SpeedCounter()
    for i in range(100):
        if i % 5:
            c.add(i * 10_000_000)
    got, expected = c.count(0, 1_000_000_000)
    assert (got, expected) == (80, 100)
    rec = WindowRecord(1.0, 100.0, 2e6, 1e5, None, 1e-4, 1e-4, 1e-4, 1e-6, got, expected)
    assert missing_fraction([rec]) == pytest.approx(0.2)
    assert missing_fraction([WindowRecord(1.0, 100.0, 2e6, 1e5, None, 1e-4, 1e-4, 1e-4, 1e-6)]) == 0.0
    burst = SpeedCounter()                      # 10 samples every 10 ms, 0.1 ms apart: no period to count against
    for i in range(100):
        burst.add((i // 10) * 10_000_000 + (i % 10) * 100_000)
    assert burst.count(0, 100_000_000) == (100, 0)


def test_bad_settings():
    """Bad input: a setting outside its range names the field, the value and the range."""
    with pytest.raises(InputError, match="diagnosis_prior_sd"):
        DiagnosisSettings(prior_sd=-1.0)
    with pytest.raises(InputError, match="diagnosis_horizon"):
        DiagnosisSettings(horizon=0)
    with pytest.raises(InputError, match="diagnosis_relinearise = -1 is invalid"):
        DiagnosisSettings(relinearise=-1)
    with pytest.raises(InputError, match="diagnosis_point_pressure_pa = 0"):
        DiagnosisSettings(point_pressure_pa=0.0)
    with pytest.raises(InputError, match="diagnosis_trend = 'yes'"):
        DiagnosisSettings(trend="yes")
    with pytest.raises(InputError, match="signatures"):
        classify([WindowRecord(1.0, 100.0, 2e6, 1e5, None, 1e-4, 1e-4, 1e-4, 1e-6)], [])


@pytest.fixture(scope="module")
def plant():
    """The configured pump, a model to make faulty flows with, and the classifier's signatures."""
    cfg = load_config()
    return cfg, SteadySignatures(cfg)


def _records(cfg, fault: dict, gain: float = 0.0, **kw):
    return model_records(cfg, fault, gain, rel_sd=REL_SD, **kw)


@pytest.mark.parametrize("kind", list(CASES))
def test_names_the_fault(plant, kind):
    """Behaviour: on the windows of a pump with one fault the classifier names that fault with probability
    > 0.9 (healthy: no fault)."""
    cfg, sig = plant
    fault, gain = CASES[kind]
    recs = _records(cfg, fault, gain)
    d = classify(recs, [sig(r) for r in recs], relinearise=sig.relinearised)
    assert d.kind == kind, (d.kind, d.probability)
    assert d.confidence > 0.9


@pytest.mark.parametrize("restriction_pa", [0.0, 4e4])
def test_suction_restriction(plant, restriction_pa):
    """Behaviour: with a suction sensor, a suction pressure that falls with the flow (40 kPa at 68 L/min) names
    suction_restriction; one that falls with the speed only (the suction line) names no fault."""
    cfg, sig = plant
    recs = _records(cfg, {}, restriction_pa=restriction_pa)
    d = classify(recs, [sig(r) for r in recs])
    assert d.kind == ("suction_restriction" if restriction_pa else "healthy"), d.probability
    assert d.confidence > 0.9


def test_growing_suction_restriction_seen_twice(plant):
    """Behaviour: a restriction that grows between two visits of the four operating points (10 kPa at 68 L/min on
    the first, 50 kPa on the second, 6 s later) is named with the restriction's growth in time (its drop ∝ flow²
    with a coefficient b₀ + b₁·τ); without the trend a constant b fits neither visit and the flow's healthy
    explanation wins."""
    import dataclasses
    cfg, sig = plant
    first = _records(cfg, {}, restriction_pa=1e4, seed=1)
    second = [dataclasses.replace(r, t_s=r.t_s + 6.0) for r in _records(cfg, {}, restriction_pa=5e4, seed=2)]
    recs = first + second
    d = classify(recs, [sig(r) for r in recs])
    assert d.kind == "suction_restriction" and d.confidence > 0.9, d.probability
    assert classify(recs, [sig(r) for r in recs], DiagnosisSettings(trend=False)).kind == "healthy"


def test_one_operating_point_names_no_kind(plant):
    """Behaviour: at one operating point every kind fits the one residual: a fault, kind "unknown", with the
    probability of a fault; a healthy pump is still "healthy"."""
    cfg, sig = plant
    for fault, expected in (({"tip": 2.0}, "unknown"), ({}, "healthy")):
        recs = _records(cfg, fault, points=((1000, 25),))
        d = classify(recs, [sig(r) for r in recs])
        assert d.kind == expected and d.confidence > 0.9, d.probability


def test_separation_closed_form():
    """Closed form: for a step (no trend, no drift) a kind's marginal log-likelihood of residuals θ̂·d is
    −½θ̂²s/(1 + P₀s) − ½ln(1 + P₀s) + const, s = Σ d²/σ², θ̂ = θ·s/(s + 1/P₀) the posterior mode of residuals θ·d;
    a kind whose column is c·d has s → c²s, and the same column separates by nothing."""
    d, sd, t = np.array([1.0, 2.0, 1.5, 0.5]), np.full(4, 0.1), np.arange(4.0)
    theta, p0, c = 0.3, 0.2 ** 2, 2.0
    s = float(np.sum((d / sd) ** 2))
    th = theta * s / (s + 1.0 / p0)
    assert fitted_residuals(theta * d, d, sd, t, 0.2) == pytest.approx(th * d, rel=1e-12)

    def ll(scale):
        return -0.5 * th ** 2 * s / (1.0 + p0 * scale ** 2 * s) - 0.5 * math.log(1.0 + p0 * scale ** 2 * s)
    assert separation(theta * d, d, c * d, sd, t, 0.2, 0.0) == pytest.approx(ll(1.0) - ll(c), rel=1e-9)
    assert separation(theta * d, d, d, sd, t, 0.2, 0.0) == 0.0


def test_separation_is_the_mean_and_half_the_variance_of_the_observed_ratio():
    """Behaviour (Monte Carlo, the law the naming threshold rests on): with kind a true, the log-likelihood ratio
    of a over b observed on noisy residuals has mean ≈ Δ (:func:`separation`) and variance ≈ 2Δ, so its sign
    is wrong with probability ≈ Φ(−√(Δ/2))."""
    rng = np.random.default_rng(7)
    n = 12
    t = np.arange(n) * 0.5
    d_a = np.linspace(1.0, 2.0, n)
    d_b = np.linspace(1.0, 2.0, n) ** 1.3                  # nearly collinear: Δ of a few nats
    sd = np.full(n, 0.02)
    truth = 0.15 * d_a
    delta = separation(truth, d_a, d_b, sd, t, 0.2, 0.0)
    assert 2.0 < delta < 20.0
    obs = []
    for _ in range(3000):
        e = truth + rng.normal(0.0, sd)
        obs.append(kind_log_likelihood(e, d_a, sd, t, 0.2, 0.0)[0] - kind_log_likelihood(e, d_b, sd, t, 0.2, 0.0)[0])
    obs = np.array(obs)
    assert obs.mean() == pytest.approx(delta, abs=0.15 * delta)
    assert obs.var() == pytest.approx(2.0 * delta, rel=0.25)
    wrong = 0.5 * math.erfc(math.sqrt(delta / 2.0) / math.sqrt(2.0))
    assert np.mean(obs < 0.0) == pytest.approx(wrong, abs=0.03)


def test_kinds_one_speed_cannot_tell_apart_are_named_tentatively(plant):
    """Behaviour: free air and a delivery-pressure offset each change the flow by the same amount at every
    pressure of one speed: on windows at 1000 rpm and 5 / 25 bar, with either fault, the naming is one of the two,
    tentative, with the other as its closest rival; with 2500 rpm seen too, air is named firmly."""
    cfg, sig = plant
    one_speed = ((1000, 5), (1000, 25))
    bound = 2.0 * DiagnosisSettings().separable_z ** 2
    for fault in ({"air_fraction": 0.04}, {"offset_pa": -3e5}):
        recs = _records(cfg, fault, points=one_speed)
        d = classify(recs, [sig(r) for r in recs], relinearise=sig.relinearised)
        assert {d.kind, d.rival} == {"air_ingress", "pressure_offset"}, (d.kind, d.rival, d.probability)
        assert d.tentative and d.separation < bound
    recs = _records(cfg, {"air_fraction": 0.04}, points=one_speed + ((2500, 25),))
    d = classify(recs, [sig(r) for r in recs], relinearise=sig.relinearised)
    assert d.kind == "air_ingress" and not d.tentative and d.separation >= bound, (d.rival, d.separation)


def test_separability_of_the_operating_points(plant, capsys):
    """Behaviour (``--separability``, before any bag): at one operating point no pair of flow kinds is separable;
    at one speed air and a pressure offset separate by a thirtieth of what the four points give, where they are
    separable; Δ grows with the fault's size squared (θ 0.04 → 0.08: ≈ 4×, the priors aside)."""
    from gerotor_twin.offline.separability import separability
    cfg, _ = plant
    bound = 2.0 * DiagnosisSettings().separable_z ** 2
    one = separability(cfg, [(1000, 25)])
    assert max(v for row in one.values() for v in row.values()) < bound
    speed = separability(cfg, [(1000, 5), (1000, 25)])
    four, double = separability(cfg, POINTS), separability(cfg, POINTS, loss=0.08)
    for a, b in (("air_ingress", "pressure_offset"), ("pressure_offset", "air_ingress")):
        assert speed[a][b] < four[a][b] / 30.0 and four[a][b] > bound, (speed[a][b], four[a][b])
    ratio = double["air_ingress"]["pressure_offset"] / four["air_ingress"]["pressure_offset"]
    assert ratio == pytest.approx(4.0, rel=0.1)
    assert bench_main(["--separability", "0.04"]) == 0
    assert "| true \\ rival | tip_wear |" in capsys.readouterr().out


def test_unknown_when_nothing_fits(plant):
    """Behaviour: a residual no candidate makes (flow gained at high pressure only, lost at low) is "unknown"."""
    cfg, sig = plant
    recs = _records(cfg, {})
    odd = [WindowRecord(r.t_s, r.omega, r.p_delivery, r.p_suction, r.oil_k,
                        r.q_meas + (0.05 if r.p_delivery > 1e6 else -0.05) * r.q_th * (1 if r.omega > 200 else -1),
                        r.q_pred, r.q_th, r.sd) for r in recs]
    d = classify(odd, [sig(r) for r in odd])
    assert d.kind == "unknown", d.probability


def test_speed_dropout(plant):
    """Behaviour: flow residuals that fit "healthy" with a fifth of the speed samples missing name speed_dropout."""
    cfg, sig = plant
    recs = [WindowRecord(*[getattr(r, f) for f in ("t_s", "omega", "p_delivery", "p_suction", "oil_k", "q_meas",
                                                   "q_pred", "q_th", "sd")], 40, 50) for r in _records(cfg, {})]
    d = classify(recs, [sig(r) for r in recs])
    assert d.kind == "speed_dropout" and d.dropout == pytest.approx(0.2)
    assert KINDS[d.code] == "speed_dropout"


def test_bench_loss_crossing_interpolates():
    """Closed form: the 2-pt crossing of the bench is the linear interpolation between the truth's samples, by
    magnitude (an apparent gain crosses too), the first sample when already there, None when never."""
    t = [0.0, 0.1, 0.2, 0.3]
    assert crossing_time(t, [0.0, 0.01, 0.03, 0.05]) == pytest.approx(0.15)
    assert crossing_time(t, [0.0, -0.01, -0.03, -0.05]) == pytest.approx(0.15)
    assert crossing_time(t, [0.02, 0.03, 0.04, 0.05]) == 0.0
    assert crossing_time(t, [0.0, 0.005, 0.01, 0.019]) is None


def test_bench_counts_alarms_not_bags():
    """Closed form: the bench's fraction is over alarms (two right of three in two tip-wear bags), the other
    alarms by the kind they named, a fault bag whose loss crossed 2 pt without an alarm naming it counted as
    missed, and the healthy bags' alarms kept apart from the fault bags' total."""
    def bag(kind, named, crossing, first, rivals=None):
        return {"kind": kind, "alarms": [{"fault": n, "rival": r} for n, r in zip(named, rivals or [None] * len(named))],
                "crossing_s": crossing, "first_right_s": first,
                "delay_s": None if crossing is None or first is None else first - crossing}
    s = alarm_summary([bag("tip_wear", ["tip_wear", "unknown"], 3.0, 4.0),
                       bag("tip_wear", ["tip_wear"], 2.0, 5.0, ["lateral_wear"]),
                       bag("air_ingress", [], 2.5, None), bag("healthy", ["lateral_wear"], None, None),
                       bag("pressure_offset", ["air_ingress"], 1.0, None, ["pressure_offset"])])
    assert (s["tip_wear"]["alarms"], s["tip_wear"]["right"]) == (3, 2)
    assert s["tip_wear"]["fraction"] == pytest.approx(2 / 3) and s["tip_wear"]["wrong_named"] == {"unknown": 1}
    assert s["tip_wear"]["delay_s"] == [1.0, 3.0] and s["air_ingress"]["missed"] == 1
    assert s["air_ingress"]["fraction"] is None and s["healthy"]["alarms"] == 1
    assert s["tip_wear"]["tentative"] == [1, 0] and s["pressure_offset"]["tentative"] == [0, 1]
    assert (s["all"]["bags"], s["all"]["alarms"], s["all"]["right"], s["all"]["tentative"]) == (4, 4, 2, [1, 1])


def test_bench_severity_reaches_its_loss(plant):
    """Behaviour: the bench's severity of a flow kind is the value whose apparent loss at the monitor's reference
    point is the target (within the rounding to three significant digits of the fault's step), inside the kind's
    allowed range; a target the range cannot reach gives the range's end with its smaller loss (a −5 bar offset
    loses 6.8 pt on the default pump, not 8); the meter gain g is −target / η_v (closed form)."""
    cfg, _ = plant
    v, loss = severity_for(cfg, "lateral_wear", 0.04)
    assert 1.0 < v < 3.0 and loss == pytest.approx(0.04, abs=0.002)
    assert loss == pytest.approx(reference_loss(cfg, "lateral_wear", [v])[0], rel=1e-12)
    v, loss = severity_for(cfg, "pressure_offset", 0.08)
    assert v == -5e5 and 0.02 < loss < 0.08
    g, loss = severity_for(cfg, "flowmeter_drift", 0.04)
    eta = reference_loss(cfg, "flowmeter_drift", [-1.0])[0]
    assert g == pytest.approx(-0.04 / eta, rel=1e-3) and loss == pytest.approx(-g * eta, rel=1e-12)


@pytest.mark.parametrize("argv, message", [
    (["--severity", "mid"], "--severity = 'mid' is invalid; allowed: high | low | both"),
    (["--seeds", "1,x"], "--seeds = '1,x' is invalid; allowed: comma-separated"),
    (["--ramp", "-1"], "--ramp = -1.0 is invalid; allowed: [0, 10000] s"),
    (["--config", "/nonexistent/pump.yaml"], "--config = '/nonexistent/pump.yaml' is invalid"),
    (["--profile-file", "/nonexistent/profile.yaml"], "--profile-file = '/nonexistent/profile.yaml' is invalid"),
    (["--settle", "-1"], "--settle = -1.0 is invalid; allowed: [0, 600] s"),
    (["--separability", "2"], "--separability = 2.0 is invalid; allowed: [0.0001, 0.5]")])
def test_bench_bad_input(tmp_path, capsys, argv, message):
    """Bad input: the bench refuses a bad option in one line naming it, the value and the allowed range (exit 2)
    before any bag is made."""
    with pytest.raises(SystemExit) as exc:
        bench_main(["-o", str(tmp_path / "b"), *argv])
    assert exc.value.code == 2 and message in capsys.readouterr().err
    assert not (tmp_path / "b").exists()


def test_relinearisation_converges_closed_form():
    """Closed form: a fault whose flow change is quadratic in its size, e_i = θ·(a_i + b_i·θ), fitted with the
    secant column a + b·θ̂ re-linearised at each fit: the linear fit (step 1) misses θ = 3 and leaves χ² far above
    n; the fixed point is the true size, reached within the bounded iterations, and the column is asked for at
    most ``relinearise`` times."""
    a = np.linspace(1.0, 2.0, 8)
    b = np.linspace(0.5, -0.2, 8)
    e, sd, t = 3.0 * (a + 3.0 * b), [1e-4] * 8, np.arange(8.0)
    calls = []

    def secant(recs, kind, theta, steps):
        calls.append(theta)
        return list(a + b * theta), theta
    s = DiagnosisSettings(prior_sd=10.0, drift_per_sqrt_s=0.0, relinearise=8)
    sigs = [{"tip_wear": ai + bi} for ai, bi in zip(a, b)]
    lin = _fit_kind("tip_wear", None, sigs, e, sd, t, s, 0.0)[0]
    fit, column = _fit_kind("tip_wear", None, sigs, e, sd, t, s, 0.0, secant)
    assert abs(lin[1] - 3.0) > 0.1 and lin[3] > 1e3
    assert fit[1] == pytest.approx(3.0, rel=1e-4) and fit[3] < len(e) and len(calls) <= 8
    assert column == pytest.approx(a + b * 3.0, rel=1e-4)
    calls.clear()
    _fit_kind("tip_wear", None, sigs, e, sd, t, DiagnosisSettings(prior_sd=10.0, relinearise=2), 0.0, secant)
    assert len(calls) == 2


def test_large_air_named_after_relinearisation(plant):
    """Behaviour: 8 % of free air in full at the four points is far from linear in the air fraction: with the
    signature of +1 % the best fit fails the χ² check (``unknown``); re-linearised at the fitted size it is named
    air ingress with probability > 0.9.  Re-linearisation is refused for the linear meter gain, within one step
    and in the direction a wear cannot take."""
    cfg, sig = plant
    recs = _records(cfg, {"air_fraction": 0.08})
    sigs = [sig(r) for r in recs]
    assert classify(recs, sigs).kind == "unknown"
    d = classify(recs, sigs, relinearise=sig.relinearised)
    assert d.kind == "air_ingress" and d.confidence > 0.9, d.probability
    assert sig.relinearised(recs, "flowmeter_drift", 0.5) is None
    assert sig.relinearised(recs, "air_ingress", 0.5 / sig.scale["air_ingress"]) is None
    column, steps = sig.relinearised(recs, "air_ingress", d.parameter["air_ingress"])
    assert steps > 1.0 and all(c < 0 for c in column)
    assert sig.relinearised(recs, "tip_wear", -0.05) is None


def test_alarm_record_names_closed_form():
    """Closed form: an alarm's ``fault`` / ``confidence`` are the naming at its last update, ``first_fault`` /
    ``first_confidence`` at its first, ``named_at_s`` the start of the last unbroken stretch naming ``fault``."""
    def row(level, kind, p):
        return {"level": level, "fault": KIND_CODES[kind], "fault_confidence": p}
    t = [1.0, 2.0, 3.0, 4.0, 5.0, 6.0]
    rows = [row(0, "healthy", 0.9), row(1, "unknown", 1.0), row(1, "tip_wear", 0.5), row(1, "lateral_wear", 0.6),
            row(1, "lateral_wear", 0.7), row(2, "lateral_wear", 0.8)]
    warn, error = alarm_records(t, rows)
    assert warn == {"start_s": 2.0, "end_s": 5.0, "level": "WARN", "fault": "lateral_wear", "confidence": 0.7,
                    "rival": None, "first_fault": "unknown", "first_confidence": 1.0, "named_at_s": 4.0}
    assert (error["fault"], error["first_fault"], error["named_at_s"]) == ("lateral_wear", "lateral_wear", 6.0)
    # a tentative naming carries the kind it was not yet told apart from; a firm one does not
    rival = {"fault_rival": KIND_CODES["pressure_offset"], "fault_separation": 1.5}
    rows[-1] = {**row(2, "air_ingress", 0.83), **rival, "fault_tentative": 1.0}
    assert alarm_records(t, rows)[-1]["rival"] == "pressure_offset"
    assert fault_text("air_ingress", 0.83, "pressure_offset") == "air_ingress (0.83) or pressure_offset"
    rows[-1] = {**row(2, "air_ingress", 0.99), **rival, "fault_tentative": 0.0}
    assert alarm_records(t, rows)[-1]["rival"] is None and tentative_rival(rows[-1]) is None


def test_operating_points_by_tolerance_closed_form():
    """Closed form: windows on one plateau (603.3, 604.3, 602.3 kPa at 1000 rpm, across a 5 kPa rounding step of
    the signature cache) are one operating point; 5 against 25 bar, or 1000 against 2500 rpm, are two."""
    def rec(rpm, p):
        return WindowRecord(1.0, rpm * math.pi / 30, p, 1e5, None, 1e-4, 1e-4, 1e-4, 1e-6)
    plateau = [rec(1000.01, 603339.0), rec(1000.01, 604264.0), rec(999.98, 602289.0)]
    assert len({point_key(r)[:2] for r in plateau}) == 2
    assert operating_points(plateau, 0.01, 5e4) == 1
    assert operating_points(plateau + [rec(1000.0, 2.6e6)], 0.01, 5e4) == 2
    assert operating_points(plateau + [rec(2500.0, 6.0e5)], 0.01, 5e4) == 2


@pytest.mark.parametrize("kind,fault,gain", [(k, *CASES[k]) for k in CASES if k != "healthy"]
                         + [("pressure_offset", {"offset_pa": -2e5}, 0.0)])
def test_reference_loss_is_the_fault_loss_at_the_reference_point(plant, kind, fault, gain):
    """Behaviour (known truth): the loss at the health monitor's reference point (1500 rpm, 20 bar, 50 °C) that the
    fitted θ of the named kind stands for (``SteadySignatures.reference_loss``, what the status level judges once
    the classifier names a flow fault) is the fault's apparent loss there, computed apart from the classifier with
    the fault applied in full in the twin's steady model: q_twin − q_meter over the theoretical flow (a meter gain g:
    −g·η_v; an offset: the pump at the pressure read less the offset), within 10 % and 0.2 pt.  With the signatures'
    reference at the config's reference oil temperature instead, the wears' θ read 0.65–0.66 of it and the offset's
    0.57 (measured); a transducer reading 2 bar low, +2.7 pt."""
    from gerotor_twin.offline.model_windows import _flow
    cfg, _ = plant
    sig = SteadySignatures(cfg)                     # the monitor's default reference point, 50 °C oil
    recs = _records(cfg, fault, gain)
    d = classify(recs, [sig(r) for r in recs], relinearise=sig.relinearised)
    assert d.kind == kind, d.probability
    ref = _flow(cfg, 1500.0, 20.0)
    true = _flow(cfg, 1500.0, 20.0, **dict(fault)).mean_delivery_flow_m3s * (1.0 + gain)
    loss = (ref.mean_delivery_flow_m3s - true) / ref.theoretical_flow_m3s
    got = sig.reference_loss(kind, d.parameter[kind])
    assert abs(got - loss) <= 0.1 * abs(loss) + 0.002, (got, loss)


def test_relinearised_offset_read_low_keeps_the_direction(plant):
    """Behaviour: a pressure offset may lie on either side of no fault; re-linearised at a size read low (θ < 0,
    two steps: a pump at 27 bar read as 25) the secant is taken on that side (n' < 0) and θ keeps the unit step's direction: each record's
    column has the sign of the linear signature's and its size within 25 % of it.  (Scaled by the reference
    point's |change|, the column flipped sign and θ with it: a 3 bar offset read low at 1000 / 2500 rpm was
    published as a loss of −4.1 pt where the truth is +4.1.)"""
    cfg, sig = plant
    recs = _records(cfg, {})
    lin = np.array([sig(r)["pressure_offset"] for r in recs])
    col, n = sig.relinearised(recs, "pressure_offset", -2.0 / sig.scale["pressure_offset"])
    assert n < -1.0
    assert np.all(np.sign(col) == np.sign(lin)) and np.allclose(col, lin, rtol=0.25), (col, lin)


def test_a_window_near_atmospheric_delivery_pressure_has_every_signature(plant):
    """Behaviour: at a delivery pressure below the pressure offset's step (an open-circuit lube pump at 0.3 bar, or a
    transducer reading a 5 bar plateau 5 bar low) the offset's signature is the step taken the other way, sign
    reversed, so the window is classified; it has the sign of the signature at 5 bar and, the flow being near-linear
    in the pressure there, its size within 30 %.  (With the step one way only the steady model refused the pump
    below 0 bar gauge and the window was left out of the classification.)"""
    cfg, sig = plant
    low = WindowRecord(1.0, 1000 * math.pi / 30, 101325.0 + 0.3e5, 101325.0, 323.15, 3e-4, 3e-4, 3.4e-4, 1e-6)
    ref = WindowRecord(1.0, 1000 * math.pi / 30, 101325.0 + 5e5, 101325.0, 323.15, 3e-4, 3e-4, 3.4e-4, 1e-6)
    a, b = sig(low)["pressure_offset"], sig(ref)["pressure_offset"]
    assert math.isfinite(a) and a * b > 0 and abs(a / b - 1) < 0.3, (a, b)
