"""Choosing the parameter set by cross-validation, and the empirical baseline (`calibrate --map`, `--cv`).

Tiers: closed form (folds, candidate sets, the two-term law on data that follow it exactly, the choice
rule and the prediction band on hand-made errors); behaviour on a synthetic map (the twin at known
clearances and a known displacement deficit: the chosen set holds the displacement and predicts the
held-out speed; a map that follows the empirical law and not the twin: the command says the law wins).
"""
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.stats import t as student_t

from gerotor_twin.cli import main
from gerotor_twin.config import load_config
from gerotor_twin.errors import InputError
from gerotor_twin.calibration import selection as S
from gerotor_twin.calibration.command import calibrate_records
from gerotor_twin.calibration.map_synth import synthetic_map
from gerotor_twin.calibration.plateaus import PlateauRecord

P_ATM = 101325.0


def _rec(rpm, bar, flow=1e-4, index=1):
    return PlateauRecord(bag="m.csv", index=index, t0_s=math.nan, t1_s=math.nan, omega=rpm * math.pi / 30,
                         p_delivery_pa=P_ATM + bar * 1e5, p_suction_pa=P_ATM, oil_temperature_c=50.0, flow_m3s=flow,
                         flow_sem_m3s=math.nan, bins=1)


def test_folds_and_candidate_sets_closed_form():
    """Closed form: speeds within 2 % are one fold; one fold per point; the prior and every subset up to three
    parameters, the prefixes beyond; auto → speed with two speeds, point with one, none with a single point."""
    recs = [_rec(1000, 5), _rec(2000, 5), _rec(1010, 10), _rec(3000, 5), _rec(2020, 20)]
    assert [f.tolist() for f in S.folds(recs, "speed")] == [[0, 2], [1, 4], [3]]
    assert len(S.folds(recs, "point")) == 5
    assert S.candidate_sets(("a", "b")) == [(), ("a",), ("b",), ("a", "b")]
    assert S.candidate_sets(("a", "b", "c", "d")) == [(), ("a",), ("a", "b"), ("a", "b", "c"), ("a", "b", "c", "d")]
    assert S.resolve_scheme("auto", recs) == "speed" and S.resolve_scheme("auto", [recs[0], recs[2]]) == "point"
    assert S.resolve_scheme("auto", recs[:1]) == "none"


def test_baseline_recovers_an_exact_two_term_law():
    """Closed form: η_v = 1 − (0.04 + 3e-7·Δp/n) at every point (Δp [Pa], n [rev/s]) → a = 0.04,
    b = 3e-7 1/(Pa·s), and zero error held out (leave one speed out)."""
    d = 20e-6
    recs = []
    for rpm in (1000, 2000, 3000):
        for bar in (5, 15):
            n = rpm / 60
            eta = 1 - (0.04 + 3e-7 * bar * 1e5 / n)
            recs.append(_rec(rpm, bar, eta * d * n))
    b = S.baseline(recs, S.folds(recs, "speed"), d, P_ATM)
    assert b["a"] == pytest.approx(0.04, abs=1e-12) and b["b_per_pa_s"] == pytest.approx(3e-7, rel=1e-9)
    assert b["cv_rmse"] < 1e-12


def _cand(names, errors, directions):
    e = np.asarray(errors, float)
    return S.Candidate(tuple(names), e, e, directions)


def test_choice_rule_and_band_closed_form():
    """Closed form: the best held-out RMSE is 0.010; a one-direction set at 0.011 is within the noise 0.002 and
    simpler, so it is chosen; without the noise the standard error alone decides.  Band: t(0.975, m−1)·RMSE."""
    best = _cand(("a", "b"), [0.01, -0.01, 0.01, -0.01], 2)
    simple = _cand(("a",), [0.011, -0.011, 0.011, -0.011], 1)
    prior = _cand((), [0.05, 0.05, 0.05, 0.05], 0)
    pick, why = S.choose([prior, simple, best], noise=0.002)
    assert pick is simple and "within the noise" in why
    assert S.choose([prior, simple, best], noise=0.0)[0] is best        # SE 0: the constant |e| has no scatter
    assert S.prediction_band(best) == pytest.approx(student_t.ppf(0.975, 3) * 0.01)


@pytest.fixture(scope="module")
def deficit_map():
    raw = load_config().to_dict()
    raw["clearances"]["tooth_tip_m"] *= 1.15
    raw["clearances"]["lateral_m"] *= 1.15
    raw["volumetric"]["displacement_factor"] = 0.96
    pts = [(rpm * math.pi / 30, P_ATM + bar * 1e5, 50.0) for rpm in (1200, 2000, 2800) for bar in (4, 16)]
    return synthetic_map(raw, pts, source="deficit.csv")


def test_cross_validation_chooses_the_displacement(deficit_map):
    """Behaviour (synthetic truth, the twin's own model): among the prior, the gaps' common factor and the
    gaps with the displacement, leave-one-speed-out chooses both; held out it predicts η_v within 0.05 pt where
    the clearance-only fit is off by more than 1 pt; the prior is among the candidates and worse; no model-form
    error is seen held out, so the prediction interval is the parameters' part (closed form)."""
    res = calibrate_records(deficit_map, ["deficit.csv"], params=("tip", "lateral", "displacement"), cv="speed",
                            candidates=[("tip", "lateral"), ("tip", "lateral", "displacement")],
                            jobs=1)
    sel = res["selection"]
    assert sel["chosen"] == ["tip", "lateral", "displacement"] and res["params"] == sel["chosen"]
    by = {"+".join(c["params"]): c for c in sel["candidates"]}
    assert set(by) == {"", "tip+lateral", "tip+lateral+displacement"}
    assert by["tip+lateral+displacement"]["cv_max_abs"] < 5e-4
    assert by["tip+lateral"]["cv_max_abs"] > 0.01 and by[""]["cv_rmse"] > by["tip+lateral"]["cv_rmse"]
    assert not sel["baseline_better"]
    # the held-out errors show no model-form error, so the interval is the parameters' part alone (under the
    # fit's assumed 0.3 % flow error, --flow-floor): t(0.975, m − 1) × their sd at every point
    pi = sel["prediction_interval"]
    assert pi["model_form_sd_eta"] < 1e-4 and pi["held_out"] == 6
    t = student_t.ppf(0.975, 5)
    assert pi["half_width_eta"] == pytest.approx([t * math.hypot(a, pi["model_form_sd_eta"])
                                                  for a in pi["sd_param_eta"]], rel=1e-9)
    assert res["config"]["volumetric"]["displacement_factor"] == pytest.approx(0.96, abs=2e-3)


def test_command_says_when_the_empirical_law_wins(tmp_path, capsys):
    """Behaviour: a map that follows 1 − η = a + b·Δp/n exactly, with a speed dependence the twin's gaps do not
    have (b·Δp/n with b 20× the twin's at the low speed), is predicted better by the law; the command prints the
    candidate table with fit and held-out errors side by side and says the law wins."""
    rows = ["speed [rpm],p_delivery [bar],T_oil [degC],eta_v [-]"]
    for rpm in (1000, 2000, 3000):
        for bar in (2, 8):
            rows.append(f"{rpm},{bar},40,{1 - (0.03 + 2e-7 * bar * 1e5 / (rpm / 60)):.6f}")
    p = tmp_path / "law.csv"
    p.write_text("\n".join(rows) + "\n")
    out = tmp_path / "fit.yaml"
    page = tmp_path / "fit.html"
    assert main(["calibrate", "--map", str(p), "-o", str(out), "--candidates", "displacement", "--jobs", "1",
                 "--report", str(page), "--quiet"]) == 0
    text = capsys.readouterr().out
    assert "held-out RMSE" in text and "fit RMSE" in text and "empirical 1 − η = a + b·Δp/n" in text
    assert "the empirical law predicts the held-out points better than the twin" in text
    assert "its held-out |η error| by speed (mean [pt]): 1000 rpm " in text       # each fold's speed, in order
    assert text.index("1000 rpm ", text.index("by speed")) < text.index("2000 rpm ", text.index("by speed")) \
        < text.index("3000 rpm ", text.index("by speed"))
    assert load_config(out).calibration["selection"]["baseline_better"] is True
    html = page.read_text()
    assert "held-out RMSE [pt]" in html and "The empirical law predicts the held-out points better" in html
    assert "Its held-out |η_v error| by speed (mean): 1000 rpm " in html


def test_bench_map_subtracts_its_loss_closed_form():
    """Closed form: a constructed map of `bench maps` is the twin's steady flow less the added loss; the
    filling loss is 5 % × (n/n_max)² of the theoretical flow (at 1500 rpm of 3000: 1.25 %); with ``--noise`` each
    flow is that times (1 + noise·z), z from numpy's generator seeded with 1 and the map's name."""
    from gerotor_twin.calibration.map_bench import MAPS, _raw, build
    case = next(c for c in MAPS if c.name == "filling")
    got = build(case, speeds_rpm=(1500,), bars=(5,))[0]
    plain = synthetic_map(_raw(case), [(got.omega, got.p_delivery_pa, got.oil_temperature_c)])[0]
    qth = load_config().gears.displacement_closed_form() * 25.0
    assert plain.flow_m3s - got.flow_m3s == pytest.approx(0.0125 * qth, rel=1e-12)
    noisy = build(case, speeds_rpm=(1500,), bars=(5,), noise=0.002)[0]     # numpy's generator, seeded as documented
    z = np.random.default_rng([1, *b"filling"]).standard_normal(1)[0]
    assert noisy.flow_m3s == pytest.approx(got.flow_m3s * (1 + 0.002 * z), rel=1e-12) and z != 0.0


def test_bench_maps_grid_checked_in_one_line(capsys):
    """Behaviour: ``bench maps --rpm/--bar`` give the maps' grid; one speed (leave one speed out needs two), a
    speed above the pump's range or a pressure ≤ 0 is an InputError naming the option; so is a negative
    ``--noise`` (one line, exit 2, nothing run)."""
    from gerotor_twin.calibration.map_bench import BARS, SPEEDS_RPM, grid
    assert grid(None, None) == {"speeds_rpm": SPEEDS_RPM, "bars": BARS}
    assert grid("1000,2000", "5") == {"speeds_rpm": (1000.0, 2000.0), "bars": (5.0,)}
    for rpm, bar, option in (("1000", None, "--rpm"), ("1000,1000", None, "--rpm"), ("1000,9000", None, "--rpm"),
                             ("1000,x", None, "--rpm"), (None, "0,5", "--bar"), (None, "5,99", "--bar")):
        with pytest.raises(InputError) as err:
            grid(rpm, bar)
        assert str(err.value).startswith(f"{option} = "), (rpm, bar, str(err.value))
    assert main(["bench", "maps", "--noise", "-0.01"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: --noise = -0.01 is invalid") and "\n" not in err, err


def test_solve_holds_a_bounded_coordinate_unless_the_data_pull_it_in():
    """Closed form: linear residuals r = A b − y (unit weights), b₀ free, b₁ ≥ 0 (its prior on the bound, as a
    bypass area or a gap's opening), y = 0.3 + t·c with c the part of A's second column orthogonal to the first.
    Held at b₁ = 0 the fit gives b₀ = 0.3 and r = −t·c, so the gradient along b₁ is g = −t‖c‖², its curvature
    H = ‖a₁‖², and the χ² releasing it would gain g²/H exceeds 1 for t > ‖a₁‖/‖c‖².  t < 0: b₁ stays 0 (the
    Karush–Kuhn–Tucker point); t at half that threshold: b₁ stays 0; at five times it: the unconstrained
    least-squares solution (0.3 − 1.5 t, t) (y = 0.3 − 1.5 t + t·a₁, the mean of a₁ being 1.5)."""
    from gerotor_twin.calibration.fit import _solve
    a = np.array([[1.0, 0.0], [1.0, 1.0], [1.0, 2.0], [1.0, 3.0]])
    c = a[:, 1] - a[:, 1].mean()
    t_min = np.linalg.norm(a[:, 1]) / np.linalg.norm(c) ** 2
    lo, hi = np.array([-10.0, 0.0]), np.array([10.0, 100.0])

    def run(t):
        y = 0.3 + t * c
        return _solve(lambda b: a @ b - y, lambda b, cols=None: a.copy(), lo, hi)[0]

    for t in (-0.2, 0.5 * t_min):
        assert run(t)[1] == 0.0 and run(t)[0] == pytest.approx(0.3, abs=1e-6)
    assert run(5 * t_min) == pytest.approx([0.3 - 1.5 * 5 * t_min, 5 * t_min], abs=1e-5)


def test_rcond_option_checked_in_one_line(tmp_path, capsys):
    """Bad input: ``calibrate --rcond`` outside [0.01, 0.5] is refused before any simulation, in one line naming
    the option, the value and the range (exit 2, nothing written)."""
    out = tmp_path / "fitted.yaml"
    example = Path(__file__).resolve().parents[1] / "config" / "maps" / "example_map.csv"
    assert main(["calibrate", "--map", str(example), "-o", str(out), "--rcond", "2"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--rcond = 2.0 is invalid; allowed: [0.01, 0.5]" in err[0]
    assert not out.exists()


def test_selection_table_says_which_parameters_a_set_kept_at_the_prior():
    """Behaviour: a candidate set whose fit kept a parameter at the prior (the identifiability analysis) is
    named under the table with that parameter and the ratio used, so that a set equal to a smaller one is not
    read as a fit of its extra parameter; a set that fitted all of its parameters gets no line."""
    import io
    from gerotor_twin.calibration.command import print_selection
    row = {"fit_rmse": 0.0124, "cv_rmse": 0.0121, "cv_rmse_se": 0.0023, "cv_max_abs": 0.023}
    sel = {"cv": "speed", "folds": [[0], [1], [2]], "reason": "tip+lateral: lowest held-out RMSE (1.21 pt)",
           "baseline": {"law": "1 − η = a + b·Δp/n", "fit_rmse": 0.0099, "cv_rmse": 0.0136, "cv_max_abs": 0.03},
           "baseline_better": False,
           "candidates": [{"params": ["tip", "lateral"], **row, "held_at_prior": [], "rcond": 0.1},
                          {"params": ["tip", "lateral", "lateral_opening"], **row,
                           "held_at_prior": ["lateral_opening"], "rcond": 0.1}]}
    buf = io.StringIO()
    print_selection(sel, buf)
    notes = [ln.strip() for ln in buf.getvalue().splitlines() if "kept at the prior" in ln]
    assert notes == ["(tip+lateral+lateral_opening: lateral_opening kept at the prior by the identifiability "
                     "analysis, --rcond 0.1)"]
