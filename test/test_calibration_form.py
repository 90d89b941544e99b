"""Calibration on pumps that differ from the twin in form (issue 28): never worse than the nominal twin, and
prediction intervals that hold the model-form error.

Tiers: closed form (the model-form error from held-out errors, the interval's parts, the hold-out verdict,
the steady bench's readings); behaviour (the shipped bench pumps on a steady bench,
:mod:`gerotor_twin.calibration.bench_steady`: the calibration refuses where fitting makes the held-out
predictions worse, and the 95 % prediction interval holds ≥ 90 % of held-out plateaus).  Steady plateaus, not
recordings, so each test stays within ≈ 20 s (a recording of the same plateaus takes ≈ 45 s to synthesize);
the full figures: ``python -m gerotor_twin.offline.calibration_coverage``.
"""
import json
import math

import numpy as np
import pytest
import yaml
from scipy.stats import t as student_t

from gerotor_twin.bench_emulator import BenchSpec, load_bench_pump
from gerotor_twin.bench_emulator.bench_pump import BenchPump
from gerotor_twin.calibration import prediction as P
from gerotor_twin.calibration.bench_steady import SteadyBench, steady_plateaus
from gerotor_twin.calibration.command import holdout_verdict
from gerotor_twin.calibration.map_synth import write_map
from gerotor_twin.cli import main
from gerotor_twin.config import load_config
from gerotor_twin.offline import calibration_coverage as cov

PUMPS = {p.stem: p for p in cov.shipped_pumps()}
#: one seed per bench pump: fixed seeds over the four pumps
SEEDS = {"aerated_oil_sensor_lag": 1, "deflecting_plates": 1, "port_timing_lateral_bias": 2,
         "worn_tips_flow_number": 3}
#: the candidate set the cross-validation should choose on each: the loss's form
CHOSEN = {"aerated_oil_sensor_lag": ["displacement"], "deflecting_plates": ["tip", "lateral", "lateral_opening"],
          "port_timing_lateral_bias": ["tip", "lateral"], "worn_tips_flow_number": ["tip", "lateral"]}


def test_model_form_error_and_interval_closed_form():
    """Closed form: held-out errors ±1, ±2 pt with a parameter variance of (0.316 pt)² each and no measurement
    variance → σ_d² = mean(e²) − 1e-5 = 2.5e-4 − 1e-5; the half-width at a point of parameter variance 4e-6 and
    measurement variance 1e-6 is t(0.975, 3)·√(4e-6 + 1e-6 + σ_d²); errors smaller than the parameters'
    share give σ_d = 0 (not negative); a fold whose covariance is undefined (NaN) counts none."""
    e = np.array([0.01, -0.01, 0.02, -0.02])
    form = P.model_form_error(e, np.full(4, 1e-5), np.zeros(4))
    assert form.sd ** 2 == pytest.approx(2.5e-4 - 1e-5, rel=1e-12) and form.held_out == 4 and form.dof == 3
    assert form.half_width(4e-6, 1e-6) == pytest.approx(student_t.ppf(0.975, 3) * math.sqrt(5e-6 + form.sd ** 2))
    assert P.model_form_error(np.array([1e-4, -1e-4]), np.full(2, 1e-6), np.zeros(2)).sd == 0.0
    # a fold without residual degrees of freedom (NaN covariance): its whole error is model form
    assert P.model_form_error(e, np.array([np.nan, np.nan, 1e-5, 1e-5]), np.zeros(4)).sd ** 2 == \
        pytest.approx(2.5e-4 - 0.5e-5, rel=1e-12)
    g = np.array([[1.0, 0.0], [0.5, 2.0]])
    cov_x = np.array([[4.0, 1.0], [1.0, 9.0]])
    assert P.param_variance(g, cov_x).tolist() == pytest.approx([4.0, 0.25 * 4 + 2 * 0.5 * 2 * 1 + 4 * 9])


def test_holdout_verdict_closed_form():
    """Closed form (``--cv none``): the fit is kept only when its held-out η RMSE is below the nominal twin's;
    the message is one line saying which and why, with both figures."""
    def ho(fit, nominal):
        rows = lambda e: [{"eta_error": v} for v in e]          # noqa: E731
        stats = lambda e: {"rmse": float(np.sqrt(np.mean(np.square(e)))), "max_abs": float(np.max(np.abs(e)))}  # noqa: E731
        return {"held_out": ["b#2", "b#4"], "plateaus": rows(fit), "plateaus_prior": rows(nominal),
                "eta_error": stats(fit), "eta_error_prior": stats(nominal)}
    worse = holdout_verdict(ho([0.008, -0.009], [0.004, 0.005]), ("tip", "lateral"))
    assert not worse["calibrated"] and worse["chosen"] == [] and "\n" not in worse["message"]
    assert worse["message"].startswith("calibration refused") and "nominal values are kept" in worse["message"]
    assert "fitted 0.85 / 0.85 pt, nominal 0.45 / 0.45 pt" in worse["message"]
    better = holdout_verdict(ho([0.001, -0.001], [0.004, 0.005]), ("tip", "lateral"))
    assert better["calibrated"] and better["message"].startswith("calibration accepted: tip+lateral")
    unchecked = holdout_verdict(None, ("tip",))
    assert unchecked["calibrated"] and not unchecked["checked"]


def test_steady_bench_readings_closed_form():
    """Closed form: a steady plateau reads the emulated pump's flow through the sensor biases (speed, delivery
    pressure, oil, flow added exactly) with a flow noise draw of the standard error √(σ_abs² + (σ_rel Q)²)/√40,
    and the suction pressure of the emulator's suction line, p_atm − Δp_s (ω/ω_max)²."""
    bp = BenchPump(name="biased", sensors={"speed_bias_rad_s": 0.2, "pressure_bias_pa": 1.5e4,
                                           "flow_bias_m3s": -8e-7, "temperature_bias_c": 1.0})
    bench = SteadyBench.of(bp, base=BenchSpec(clearance_factor=1.3))
    assert bench.spec.clearance_factor == 1.0           # a bench pump sets its clearances itself
    omega, p_d, t_c = 1500 * math.pi / 30, 101325.0 + 10e5, 45.0
    (r,) = steady_plateaus(bench, [(omega, p_d, t_c)], seed=4)
    q = bench.true_flow(omega, p_d, t_c)
    sem = math.hypot(1e-6, 0.003 * q) / math.sqrt(40)
    assert (r.omega, r.p_delivery_pa, r.oil_temperature_c) == pytest.approx((omega + 0.2, p_d + 1.5e4, 46.0))
    assert r.flow_sem_m3s == pytest.approx(sem) and abs(r.flow_m3s - (q - 8e-7)) < 4 * sem
    assert r.p_suction_pa == pytest.approx(101325.0 - 5000.0 * (1500 / 3000) ** 2)


def test_coverage_points_scale_to_the_pump_range_closed_form():
    """Closed form: the coverage run's training map and held-out draws are the default pump's operating points
    (1000 / 1900 / 2800 rpm × 5 / 14 / 24 bar) on its own range, and on a pump of the family the same points scaled
    by its top speed / 3000 rpm and top pressure / 27.5 bar (04: 7000 rpm, 6 bar), the same draws per seed."""
    nominal = load_config()
    small = load_config("config/pumps/04_motorcycle_engine_oil.yaml")
    p_atm = nominal.fluid.atmospheric_pa
    pts = cov.train_points(nominal)
    assert [round(w * 30 / math.pi, 9) for w, _, _ in pts[:4]] == [1000, 1000, 1000, 1900]
    assert [round((p - p_atm) / 1e5, 9) for _, p, _ in pts[:4]] == [5, 14, 24, 24]
    scaled = cov.train_points(small)
    for (w, p, t), (w2, p2, t2) in zip(pts, scaled):
        assert w2 == pytest.approx(w * 7000 / 3000) and t2 == t
        assert p2 - small.fluid.atmospheric_pa == pytest.approx((p - p_atm) * 6 / 27.5)
    held, held2 = cov.held_out_points(4, 5, nominal), cov.held_out_points(4, 5, small)
    assert all(800 <= w * 30 / math.pi <= 2950 for w, _, _ in held)
    assert [w2 for w2, _, _ in held2] == pytest.approx([w * 7000 / 3000 for w, _, _ in held])


def test_calibrate_refuses_when_fitting_makes_held_out_worse(tmp_path, capsys):
    """Behaviour (known truth): a steady map at 50 °C of the bench pump with 0.8 % free air and a lower port Cd
    (``aerated_oil_sensor_lag``; its clearances are nominal) read as ``calibrate --map``.  The clearances fitted
    on two speeds bend to absorb the air's filling loss and predict the third worse than the nominal twin
    (measured 2026-12-05 at 08611a9: held-out η RMSE 0.61 pt nominal, 0.67 pt fitted, max 0.69 → 1.25 pt); the command
    says so in one line, keeps the nominal values, exits 0 with the verdict in its JSON and shows the nominal
    and the fitted held-out errors side by side."""
    bench = SteadyBench.of(load_bench_pump(PUMPS["aerated_oil_sensor_lag"]))
    pts = [(rpm * math.pi / 30, bench.p_atm_pa + bar * 1e5, 50.0) for rpm in (1000, 1900, 2800) for bar in (5, 22)]
    csv = write_map(tmp_path / "aerated.csv", steady_plateaus(bench, pts, seed=1), bench.p_atm_pa)
    out, js, page = tmp_path / "fitted.yaml", tmp_path / "fit.json", tmp_path / "fit.html"
    assert main(["calibrate", "--map", str(csv), "--params", "tip,lateral", "--candidates", "tip,lateral",
                 "-o", str(out), "--json", str(js), "--report", str(page), "--jobs", "2", "--quiet"]) == 0
    text = capsys.readouterr().out
    res = json.loads(js.read_text())
    by = {"+".join(c["params"]): c for c in res["selection"]["candidates"]}
    assert by["tip+lateral"]["cv_rmse"] > by[""]["cv_rmse"]                 # the premise: fitting is worse held out
    assert by["tip+lateral"]["cv_max_abs"] > by[""]["cv_max_abs"]
    refusal = [ln for ln in text.splitlines() if ln.startswith("calibration refused")]
    assert len(refusal) == 1 and "nominal values are kept" in refusal[0]
    assert f"nominal {100 * by['']['cv_mean_abs']:.2f} / {100 * by['']['cv_rmse']:.2f} pt" in refusal[0]
    assert res["verdict"]["calibrated"] is False and res["params"] == [] and res["selection"]["chosen"] == []
    nominal, fitted = load_config(), load_config(out)
    assert fitted.clearances.tooth_tip_m == nominal.clearances.tooth_tip_m
    assert fitted.clearances.lateral_m == nominal.clearances.lateral_m
    assert yaml.safe_load(out.read_text())["calibration"]["verdict"]["calibrated"] is False
    assert "prior (nothing fitted)" in text and "tip+lateral" in text and "held-out RMSE" in text
    html = page.read_text()
    assert "calibration refused" in html and "nominal and calibrated side by side" in html


_RESULTS: dict[tuple, dict] = {}


def _evaluated(name: str, params=None) -> dict:
    """``calibrate --bench``'s default candidate sets, or ``params`` as the one set (``--params``)."""
    key = (name, params)
    if key not in _RESULTS:
        case = cov.Case(PUMPS[name], SEEDS[name], held_out=6) if params is None else \
            cov.Case(PUMPS[name], SEEDS[name], 6, params, None)
        _RESULTS[key] = cov.evaluate(case, jobs=2)
    return _RESULTS[key]


@pytest.mark.parametrize("name", sorted(SEEDS))
def test_bench_pump_never_worse_than_nominal(name):
    """Behaviour (known truth, each shipped bench pump on a steady bench, one fixed seed): calibrated on a
    map's nine plateaus (3 speeds × 3 pressures, oil warming 35 → 60 °C) with ``calibrate --bench``'s candidate
    sets, the twin predicts six other plateaus (800–2950 rpm, 3–27 bar, 40–60 °C) better than the nominal twin
    and meets the issue's goal, held-out mean |η error| ≤ 0.5 pt and max ≤ 1 pt.  Where the bench pump's
    leakage paths differ from the nominal ones (``port_timing_lateral_bias``, ``worn_tips_flow_number``) the gaps
    are chosen; the aerated pump (nominal clearances, 0.8 % free air, another port Cd) takes a share of the
    flow at every speed, which the effective displacement makes and no clearance does, so it is chosen there;
    the pump whose lateral gaps open under pressure (``deflecting_plates``) leaks faster than Δp, which the gaps
    with their opening make (every fold fitting the directions the fit on all points fits: with each fold analysing its own six plateaus, one fold kept the opening at its prior and the
    displacement was chosen, 0.56 pt mean, 1.48 at worst) (measured 2026-12-05: 0.61 → 0.06, 1.52 → 0.04, 9.97 → 0.03 and 2.83 → 0.04 pt
    mean; k_D 0.994 on the aerated pump)."""
    r = _evaluated(name)
    assert r["calibrated"] and r["chosen"], r["verdict"]
    assert r["chosen"] == CHOSEN[name]
    assert r["fitted_mean_abs"] < r["nominal_mean_abs"], r["verdict"]
    assert r["fitted_mean_abs"] <= 0.005 and r["fitted_max_abs"] <= 0.01, r


def test_bench_pump_gaps_alone_refused_where_they_cannot_make_the_loss():
    """Behaviour (known truth): with the gaps as the only candidate (``--params tip,lateral``) the aerated pump's
    fitted clearances predict the held-out speeds no better than its nominal ones beyond the noise, so the
    calibration is refused and the nominal values kept (measured 2026-12-05: held out 0.61 pt nominal, the
    gaps within the noise of it): never worse than doing nothing, when the set offered cannot make the loss."""
    r = _evaluated("aerated_oil_sensor_lag", ("tip", "lateral"))
    assert not r["calibrated"] and r["chosen"] == [], r["verdict"]
    assert r["verdict"].startswith("calibration refused")
    assert r["fitted_mean_abs"] == pytest.approx(r["nominal_mean_abs"], rel=1e-12)


def test_prediction_interval_coverage_over_bench_pumps():
    """Behaviour (known truth): over the four shipped bench pumps (one seed each; six held-out plateaus each),
    the calibrated twin's 95 % prediction interval holds the held-out η error on ≥ 90 % of the 24 held-out
    plateaus (measured 2026-12-05: 24 of 24).  The model-form term is what holds the error of a twin whose form
    is wrong: on the aerated pump calibrated with the gaps alone (refused, the nominal twin's 0.5–0.7 pt errors),
    the interval holds ≥ 5 of its 6 plateaus (measured: 6), and with the parameter and measurement variance alone
    (no model-form term, ≈ ± 0.2 pt) fewer than that (measured: none) — checked here on the same plateaus."""
    rows = [_evaluated(n) for n in sorted(SEEDS)]
    covered = sum(r["covered"] for r in rows)
    total = sum(r["held_out"] for r in rows)
    assert total == 24 and covered >= math.ceil(0.9 * total), [(r["pump"], r["covered"]) for r in rows]
    gaps = _evaluated("aerated_oil_sensor_lag", ("tip", "lateral"))
    assert gaps["covered"] >= math.ceil(0.9 * gaps["held_out"]), gaps["covered"]
    no_form = sum(abs(p["eta_error"]) <= P.ModelFormError(0.0, 9).half_width(p["sd_param_eta"] ** 2,
                                                                              p["sd_meas_eta"] ** 2)
                  for p in gaps["plateaus"])
    assert no_form < math.ceil(0.9 * gaps["held_out"]), no_form


def test_coverage_command_options_refused_in_one_line(capsys):
    """Bad input: the coverage run's ``--candidates`` names an unknown parameter, or comes with ``--params``:
    exit 2 with one line naming the option and what is allowed."""
    for argv, needle in ((["--candidates", "tip,lateral;gap"], "--candidates = 'gap'"),
                         (["--params", "tip", "--candidates", "tip"], "--candidates = 'tip'")):
        with pytest.raises(SystemExit) as e:
            cov.main(argv)
        assert e.value.code == 2
        err = capsys.readouterr().err.strip().splitlines()[-1]
        assert needle in err and "allowed" in err, err
