"""Section 4 of the paper: tables 3–5 and the qualitative findings (test tier 2).

Reference values are the paper's tables 3–5 (``gerotor_twin.paper.reference``), typed
from ``../shared/paper/gerotor-micromotion-paper.md``; nothing here comes from the code
under test.  Findings of sec. 4 that this model does not reproduce are ``xfail(strict)``
with the reason, so the discrepancy stays visible and a fix is noticed.
"""
import json
import math
from dataclasses import replace

import numpy as np
import pytest

from gerotor_twin.cli import main
from gerotor_twin.config import MicroMotion
from gerotor_twin.paper.calibration import DEFAULT_RESULT_PATH, acceptance
from gerotor_twin.paper.efficiency import row_slopes
from gerotor_twin.paper.reference import PAPER_EFFICIENCY, PRESSURES_BAR, SPEEDS_RPM, slope_per_bar


@pytest.fixture(scope="module")
def tables(tmp_path_factory):
    """`gerotor-twin paper efficiency --json` for fixed and mobility (one run, 36 points)."""
    path = tmp_path_factory.mktemp("paper") / "eff.json"
    assert main(["paper", "efficiency", "--json", str(path)]) == 0
    return json.loads(path.read_text())


@pytest.fixture(scope="module")
def section4(cfg):
    from gerotor_twin.paper.section4 import run_section4
    return run_section4(cfg)


def test_reference_tables_are_linear_in_pressure_with_slope_inverse_to_speed():
    """Sanity of the typed values: the fixed rows fall ∝ Δp/n (within 3 %), as leakage does."""
    s = {n: slope_per_bar(PRESSURES_BAR, PAPER_EFFICIENCY[("fixed", n)]) * n for n in SPEEDS_RPM}
    assert max(s.values()) / min(s.values()) == pytest.approx(1.0, abs=0.035)


def test_efficiency_json_schema(tables):
    pts = tables["points"]
    assert len(pts) == 36
    for p in pts:
        assert set(("rpm", "bar", "model", "volumetric_efficiency", "paper")) <= set(p)
        assert p["model"] in ("fixed", "mobility")
        assert 0.0 < p["volumetric_efficiency"] < 1.0 and 0.0 < p["paper"] < 1.0


def test_calibrated_fixed_centre_matches_tables_3_to_5(tables):
    """Issue 4 acceptance, recomputed from the model: every point within ±2 pt, slope within 10 % at each speed.

    In-sample: the two clearances were fitted to these 18 points (docs/calibration.json), so this
    checks the fit, not a prediction; the out-of-sample checks are the structure below (slopes
    ∝ 1/n) and the mobility rows, which were not fitted.
    """
    fixed = [p for p in tables["points"] if p["model"] == "fixed"]
    for p in fixed:
        assert p["volumetric_efficiency"] == pytest.approx(p["paper"], abs=0.02), p
    for s in row_slopes(fixed):
        assert s["slope_per_bar"] == pytest.approx(s["paper_slope_per_bar"], rel=0.10), s
    assert acceptance(fixed, row_slopes(fixed))["passed"]


def test_model_slopes_scale_inverse_to_speed(tables):
    """Structure, not fitted per speed: two global clearances give fixed-centre slopes ∝ 1/n.

    The paper's rows do so within 3.5 % (test above); the model's slope × n must agree across
    1000/2000/3000 rpm within 10 %, as leakage ∝ Δp at a swept volume ∝ n predicts.
    """
    fixed = [p for p in tables["points"] if p["model"] == "fixed"]
    s = {r["rpm"]: r["slope_per_bar"] * r["rpm"] for r in row_slopes(fixed)}
    assert max(s.values()) / min(s.values()) == pytest.approx(1.0, abs=0.10), s


def test_config_uses_the_recorded_calibration(cfg):
    """config/pump.yaml carries the clearances of docs/calibration.json (to 0.01 µm)."""
    res = json.loads(DEFAULT_RESULT_PATH.read_text())
    assert cfg.clearances.tooth_tip_m == pytest.approx(res["tooth_tip_m"], abs=1e-8)
    assert cfg.clearances.lateral_m == pytest.approx(res["lateral_m"], abs=1e-8)


@pytest.mark.parametrize("volumes", ["nominal", "displaced"])
def test_micro_motion_models_give_close_trajectories(section4, cfg, volumes):
    """Mobility, Method 1 and FDM: trajectories within 2 % of δ at every point of the cycle and within 0.5 % of δ
    RMS (δ = 31.4 µm; measured 2026-12-06, Method 1 / FDM against the mobility method, largest and RMS: chamber
    volumes of the centred gear, as in the paper, 0.076 / 0.21 µm and 0.011 / 0.021 µm; of the displaced gear,
    the default, with the tooth contact as a constraint (``gear_coupling: constrained``), 0.089 / 0.38 µm and
    0.024 / 0.10 µm).  In contact the gear slides along the teeth with the velocity its own film gives under the
    load and the teeth's reactions together, M(e, F + λn) (docs/numerics.md, "The tooth contact as a
    constraint"), so the film model sets the sliding direction there as well as the speed: FDM's mobility, whose
    cross-coupling differs most from the short-bearing closed form, slides furthest from the mobility method's
    (with the reactions linearised at the free load it was 0.069 µm RMS, against a bound of 0.3 % of δ then;
    ``stages``, where the check pulled the gear back onto the teeth along e after each step: 0.11 / 0.06 µm and
    0.020 / 0.015 µm).

    Why so close (the film models differ by 1.5–13 % in force for the same eccentricity,
    docs/bearing.md): under the pressure load the outer gear rests on the inner gear at
    almost every step (the tooth contact binds), so the position is set by the gear geometry
    and the film model decides how fast it gets there and how it slides along the teeth.
    With the volumes of the displaced gear (the default since issue 13) the gear's speed also
    squeezes the closed chambers; every bearing model moves inside the ROS2 stages
    (``gear_coupling``).  Without ``volumes.PLACEMENT_TOLERANCE`` the difference reached 0.70 / 0.52 µm, 1–3 steps after a
    contact switch: Method 1 and FDM, stepped one output step per call, lost the gear's squeeze velocity
    at every step where the overlap check re-projected the gear by round-off
    (``volumes.PLACEMENT_TOLERANCE``).
    The cycles start at the same shaft angle (``chamber_cycle``).
    """
    if volumes == "nominal":
        from gerotor_twin.paper.section4 import run_section4
        section4 = run_section4(replace(cfg, micro_motion=MicroMotion(chamber_volumes="nominal")))
    delta = cfg.clearances.tooth_tip_m
    ref = section4["cycles"]["mobility"].eccentricity
    for m in ("short", "fdm"):
        e = section4["cycles"][m].eccentricity
        assert e.shape == ref.shape
        d = np.hypot(*(e - ref).T)
        assert d.max() < 0.02 * delta, (m, d.max())
        assert np.sqrt(np.mean(d ** 2)) < 0.005 * delta, (m, np.sqrt(np.mean(d ** 2)))
        assert np.all(np.hypot(e[:, 0], e[:, 1]) < cfg.clearances.housing_radial_m)
    assert np.ptp(ref[:, 0]) > 0.1 * delta      # and the trajectory is not a point


def test_trajectory_moves_opposite_ways_with_pressure_and_speed(cfg):
    """Sec. 4: raising pressure at constant speed and raising speed at constant pressure
    move the centre in opposite directions along x (the paper's "left"/"right"; its fig. 13
    frame is not given in the text, so only the opposition is asserted, plus our sign)."""
    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.model.steady import run_steady

    m = PumpModel(cfg, "mobility")
    x = {(n, p): run_steady(m, n, p).outputs.eccentricity[:, 0].mean() for n, p in
         ((1000, 5.0), (1000, 27.5), (3000, 27.5))}
    by_pressure = x[(1000, 27.5)] - x[(1000, 5.0)]
    by_speed = x[(3000, 27.5)] - x[(1000, 27.5)]
    assert abs(by_pressure) > 0.5e-6 and abs(by_speed) > 0.5e-6, x
    assert by_pressure * by_speed < 0, x


@pytest.mark.xfail(strict=True, reason="not reproduced: the outer gear rests on the inner gear's teeth at 27.5 bar at "
                   "both speeds, so the pressure moves the tooth-1 gap by the same ≈ 6 µm rms; the independent coupled "
                   "reference agrees (docs/paper.md, 'Section 4')")
def test_pressure_changes_the_tooth_gap_more_at_high_speed(cfg):
    """Fig. 12 of the paper: "in the case of high speed, the effect of pressure increase is
    more pronounced than in the low-speed case" — rms change of the tooth-1 gap over a
    chamber cycle from 5 to 27.5 bar, 3000 vs 1000 rpm; we ask for a ratio > 1.2.  Measured
    2026-12-05 with the default ``gear_coupling: constrained``: 6.25 µm at 3000 rpm against 6.44 µm
    at 1000 rpm.  Over one revolution at the same shaft angles the coupled reference
    (``model/coupled_reference.py``: Radau on pressures and gear together, independent of the
    twin's time discretisation and contact scheme) gives 5.82 against 5.96 µm, the constrained twin
    5.95 against 6.02 µm (2026-12-06); ``stages``, whose gear the overlap check pulled back after every step,
    gave 3.75 against 1.85 µm, the paper's ratio, from that artefact (its mean position 1–2 µm from
    the coupled reference's, the constrained twin's within 0.2 µm)."""
    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.model.steady import run_steady
    from gerotor_twin.paper.section4 import chamber_cycle

    m = PumpModel(cfg, "mobility")
    rms = {}
    for rpm in (1000, 3000):
        g = [chamber_cycle(m, run_steady(m, rpm, bar)).gaps[:, 0] for bar in (5.0, 27.5)]
        assert g[0].shape == g[1].shape      # same angle grid: cycles start at θ ≡ 0
        rms[rpm] = float(np.sqrt(np.mean((g[1] - g[0]) ** 2)))
    assert rms[3000] > 1.2 * rms[1000] > 0, rms


@pytest.mark.xfail(strict=True, reason="not reproduced: with the calibrated clearances the tooth-tip gaps carry "
                   "a few % of the leakage and the outer gear rests on the inner gear, so micro-motion changes "
                   "η by < 0.2 pt (docs/paper.md, 'Section 4')")
def test_micro_motion_raises_volumetric_efficiency(tables):
    """Tables 3–5: MM above fixed by 1.35–2.6 pt at every point; we ask for ≥ 0.5 pt."""
    by = {(p["model"], p["rpm"], p["bar"]): p["volumetric_efficiency"] for p in tables["points"]}
    for n in SPEEDS_RPM:
        for p in PRESSURES_BAR:
            assert by[("mobility", n, p)] - by[("fixed", n, p)] > 0.005


@pytest.mark.xfail(strict=True, reason="not reproduced: see docs/paper.md, 'Section 4'")
def test_fixed_centre_has_the_deeper_depression(section4):
    """Fig. 14: near the delivery-to-suction transition the fixed-centre chamber pressure
    dips lower than with micro-motion."""
    low = {m: section4["cycles"][m].chamber_pressures[:, 0].min() for m in ("fixed", "mobility")}
    assert low["fixed"] < low["mobility"] - 1e3, low


def test_section4_restriction_gives_the_design_pressure(section4):
    """The restriction sized for 27.5 bar with the fixed centre gives 27.5 bar (±2 %) on its
    own run, from a fresh start in restriction mode (a consistency check of the two modes)."""
    pd = section4["fixed"].outputs.delivery_pressure.mean() - 101325.0
    assert pd == pytest.approx(27.5e5, rel=0.02)


def test_figures_written(tmp_path):
    assert main(["paper", "figures", "--out", str(tmp_path), "--models", "fixed,mobility"]) == 0
    names = sorted(p.name for p in tmp_path.glob("fig1*.png"))
    assert names == ["fig12_gap_vs_pressure_speed.png", "fig13_trajectories.png", "fig14_chamber1_pressure.png",
                     "fig15_delivery_pressure.png", "fig16_gap_height_length.png"]
    assert all((tmp_path / n).stat().st_size > 10_000 for n in names)


def test_equivalent_length_closed_form(fixed_model):
    """l_e = 2√(2 h d_h/κ) is where two circles of relative curvature κ part by h·d_h
    (parabolic film h + x²κ/2 = h(1 + d_h) at x = l_e/2)."""
    from gerotor_twin.paper.figures import equivalent_length
    h = 30e-6
    theta = np.array([0.1, 1.0])
    le = equivalent_length(fixed_model, theta, np.full(2, h))
    kappa = fixed_model.tables.column("KREL", theta, 0)
    x = le / 2
    assert np.allclose(h + x ** 2 * kappa / 2, h * (1 + fixed_model.config.tip_dh))


def test_bench_models_prints_a_row_per_model_and_speed(capsys):
    assert main(["bench", "models", "--models", "fixed,mobility", "--repeats", "1"]) == 0
    rows = [ln.split() for ln in capsys.readouterr().out.splitlines() if ln.startswith("  ")]
    assert sorted((r[0], r[1]) for r in rows if r[0] in ("fixed", "mobility")) == [
        ("fixed", "1000"), ("fixed", "3000"), ("mobility", "1000"), ("mobility", "3000")]


def test_housing_contact_is_reported_not_clamped_silently(cfg):
    """A bearing that cannot carry the load (20 µm housing clearance, 0.5 mPa·s oil): the
    outer gear reaches the film limit ε = 0.95 — the steps are counted
    (``housing_contact``, printed by ``simulate``) and everything stays finite."""
    from dataclasses import replace

    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.model.steady import run_steady

    c = 20e-6
    weak = replace(cfg, clearances=replace(cfg.clearances, housing_radial_m=c),
                   fluid=replace(cfg.fluid, viscosity_pa_s=5e-4))
    r = run_steady(PumpModel(weak, "mobility"), 1000, 27.5, max_revolutions=5)
    s = r.summary()
    assert s["counts"]["housing_contact"] > 0
    assert np.all(np.isfinite(r.outputs.chamber_pressures)) and math.isfinite(s["volumetric_efficiency"])
    assert max(np.hypot(*r.outputs.eccentricity.T)) <= 0.95 * c * (1 + 1e-9)


def test_paper_commands_keep_the_calibrated_ray_kidney(cfg):
    """Behaviour: the paper's commands run the kidneys and the orifice law the clearances were calibrated
    with (ray edges, flow-number law), whatever the config says; ``suction_edge="chamber"`` gives the
    twin's default kidney, which fills better at low pressure, and ``orifice_law="merritt"`` its default
    law, whose larger laminar conductance fills the ray kidney better (fixed centre, 1000 rpm / 5 bar,
    eq. (23); docs/paper.md, "Orifice law": +0.34 pt)."""
    from dataclasses import replace
    from gerotor_twin.paper.efficiency import efficiency_points
    ray_cfg = replace(cfg, suction_port=replace(cfg.suction_port, closing_edge="ray"),
                      orifice=replace(cfg.orifice, law="flow_number"))
    kw = dict(models=("fixed",), speeds=(1000.0,), pressures=(5.0,))
    eta = {name: efficiency_points(c, **kw)[0]["volumetric_efficiency"]
           for name, c in (("default", cfg), ("ray", ray_cfg))}
    eta["chamber"] = efficiency_points(cfg, suction_edge="chamber", **kw)[0]["volumetric_efficiency"]
    eta["merritt"] = efficiency_points(cfg, orifice_law="merritt", **kw)[0]["volumetric_efficiency"]
    assert cfg.suction_port.closing_edge == "chamber" and cfg.orifice.law == "merritt"
    assert eta["default"] == eta["ray"]
    assert eta["chamber"] > eta["ray"] + 1e-3, eta
    assert eta["merritt"] > eta["ray"] + 1e-3, eta
