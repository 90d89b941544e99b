"""Default numerics against golden reference revolutions (golden tier).

The references in test/golden/ are revolutions at periodic steady state of the default pump,
mobility model, computed with tight numerics (ROS2 tolerance 1e-8 on ln(ρ/ρ₀), output step 16×
finer; test/golden/make_reference.py, git revision in each file). The default numerics must stay
within the error budget (``model.accuracy.BUDGET``) at each point: RMS chamber-pressure error ≤ 1 % of
the reference waveform's range, |η error| ≤ 0.3 % relative, |peak-pressure error| ≤ 2 % (gauge), flow
RMS ≤ 1 %.  A change of the default numerics (step, tolerance, error measure) that breaks it fails here.
The step-control constant ``closing_tolerance`` is shown necessary, for both events it holds (a closing
chamber's spike, a refilled chamber's fill front), on pumps of the family (config/pumps/) against fresh
tight references (behaviour tier).
"""
import numpy as np
import pytest

from dataclasses import replace

from golden.make_reference import LOW_POINTS, POINTS, path
from gerotor_twin.config import load_config
from gerotor_twin.model.accuracy import BUDGET, Revolution, compare, reference_revolution
from gerotor_twin.model.family import family_dir
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady


def flow_number_law(cfg):
    """``cfg`` with the flow-number orifice law: the pump on which the output grid's miss below was found
    (Merritt's default law fills a just-opened chamber differently, and the instance moves)."""
    return replace(cfg, orifice=replace(cfg.orifice, law="flow_number"))


@pytest.mark.parametrize("rpm,bar", POINTS)
def test_default_numerics_within_budget_of_the_golden_reference(cfg, rpm, bar):
    ref, meta = Revolution.load(path(rpm, bar))
    assert (meta["rpm"], meta["bar"], meta["model"]) == (rpm, bar, "mobility")
    res = run_steady(PumpModel(cfg, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
    err = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    for key, bound in BUDGET.items():
        assert abs(err[key]) <= bound, (key, err[key])


@pytest.mark.parametrize("rpm,bar", LOW_POINTS)
def test_default_numerics_within_budget_below_the_rated_pressure(cfg, rpm, bar):
    """Golden: below the rated pressure the defaults (∂f/∂t in the stages with the closing ports' share
    clipped, ``closing_tolerance`` 0.15) keep the whole budget, the
    peak of the closing chamber's spike included.  Before ∂f/∂t the RMS was 2.73 / 1.70 % at 5 / 15 bar,
    3000 rpm; with ∂f/∂t alone the 15-bar peak was +4.1 % (docs/numerics.md)."""
    ref, meta = Revolution.load(path(rpm, bar))
    assert (meta["rpm"], meta["bar"], meta["model"]) == (rpm, bar, "mobility")
    res = run_steady(PumpModel(cfg, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
    err = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    for key, bound in BUDGET.items():
        assert abs(err[key]) <= bound, (key, err[key])


def _family_errors(pump: str, rpm: float, bar: float, field: str, values) -> dict:
    """Budget figures (:func:`compare`) of the mobility model on a family pump with ``numerics.field`` at
    each of ``values``, against one fresh tight reference (log-density measure: it uses none of these fields)."""
    cfg = load_config(family_dir() / f"{pump}.yaml")
    ref = reference_revolution(cfg, rpm, bar, "mobility")
    pd = cfg.fluid.atmospheric_pa + bar * 1e5
    err = {}
    for v in values:
        c = replace(cfg, numerics=replace(cfg.numerics, **{field: v}))
        res = run_steady(PumpModel(c, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
        err[v] = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, pd)
    return err


def _family_peak_errors(pump: str, rpm: float, bar: float, field: str, values) -> dict:
    """Peak error (gauge) of :func:`_family_errors` at each value."""
    return {v: e["peak_pressure_error_gauge"] for v, e in _family_errors(pump, rpm, bar, field, values).items()}


@pytest.mark.parametrize("pump,rpm,bar", [("09_power_pack", 1800.0, 2.0), ("11_gearbox_lube", 1800.0, 0.6)])
def test_closing_tolerance_brings_the_spike_peak_within_budget(pump, rpm, bar):
    """Behaviour against a fresh tight reference, mobility, two pumps of the family: without the tighter
    tolerance on chambers whose delivery port closes (``closing_tolerance`` 1) the spike's peak is missed by
    more than the 2 % budget (−2.3 % on 09 at 1800 rpm / 2 bar, −4.2 % on 11 at 1800 rpm / 0.6 bar, measured
    2026-12-05 with the default ``gear_coupling: constrained``), with the default 0.15 it is within (−0.1 /
    −1.3 %).  Over the family grid (docs/numerics.md) the factor 1 puts 8 more of the 54 points outside the budget.
    (07 at 1650 rpm / 27.5 bar showed it too against the reference 8× finer, −2.8 against −1.6 %; against the
    converged reference, 16× finer, its peak is outside with the factor as well, −2.13 %: that miss is the gear's,
    issue 37.)  (10 no longer shows it anywhere on its grid: the defect check
    across a closing port, step_control, and the tooth constraint hold its spikes to −2.0 % at most without the
    factor.)"""
    from gerotor_twin.config import Numerics
    peak = _family_peak_errors(pump, rpm, bar, "closing_tolerance", (1.0, Numerics().closing_tolerance))
    assert Numerics().closing_tolerance == 0.15
    assert abs(peak[1.0]) > BUDGET["peak_pressure_error_gauge"], peak
    assert abs(peak[0.15]) <= BUDGET["peak_pressure_error_gauge"], peak


def test_closing_tolerance_keeps_the_fill_front_of_a_refilled_chamber(cfg):
    """Behaviour against a fresh tight reference, mobility, 09 (power pack) at 1050 rpm / 2 bar: a chamber
    filled back from the delivery kidney through a still tiny port rises from suction to delivery pressure
    within a few degrees, and ROS2's embedded estimate hardly sees the front.  The closing tolerance holds a
    chamber whose delivery port has just opened too: without it (``closing_tolerance`` 1) the front lags, the
    largest pointwise error is 5.6 % of the waveform's range, the RMS 0.37 % and the peak −3.8 % (over the 2 %
    budget); with the default 0.15 2.0 %, 0.14 % and −0.9 % (measured 2026-12-05).  The packaged config and the
    dataclass default agree."""
    from gerotor_twin.config import Numerics
    assert cfg.numerics.closing_tolerance == Numerics().closing_tolerance == 0.15
    err = _family_errors("09_power_pack", 1050.0, 2.0, "closing_tolerance", (1.0, 0.15))
    assert err[1.0]["max_pressure_error_of_range"] > 0.04, err
    assert err[0.15]["max_pressure_error_of_range"] < 0.03, err
    assert err[1.0]["rms_pressure_error_of_range"] > 2.0 * err[0.15]["rms_pressure_error_of_range"], err
    assert abs(err[1.0]["peak_pressure_error_gauge"]) > BUDGET["peak_pressure_error_gauge"], err
    assert abs(err[0.15]["peak_pressure_error_gauge"]) <= BUDGET["peak_pressure_error_gauge"], err


def test_peak_output_sees_the_spike_the_output_grid_misses(cfg):
    """Behaviour against a fresh tight reference, fixed centre, 2250 rpm / 14 bar, where the 1.5° output grid
    samples the closing chamber's ≈ 2° wide spike far from its top: the reference itself, read at the
    default's output angles, misses more than the whole budget (−2.03 % measured), and so does the default's
    sampled waveform (−2.21 %), while the model's peak output (``Outputs.chamber_peak_pressures``, from the
    ROS2 sub-steps) is within it (+0.53 %).  Each row's peak is at least both of its step's end pressures.
    Flow-number law (:func:`flow_number_law`): with Merritt's the grid misses −1.58 % there, less than the
    budget, so the point no longer shows the grid's miss (sampled −3.12 %, peak output −1.03 %)."""
    rpm, bar = 2250.0, 14.0
    cfg = flow_number_law(cfg)
    ref = reference_revolution(cfg, rpm, bar, "fixed")
    res = run_steady(PumpModel(cfg, "fixed"), rpm, bar, max_revolutions=40, rtol=1e-6)
    err = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    assert err["peak_sampling_error"] < -BUDGET["peak_pressure_error_gauge"], err     # the grid alone misses > 2 %
    assert abs(err["peak_pressure_error"]) <= BUDGET["peak_pressure_error_gauge"], err
    assert err["peak_pressure_error"] > err["sampled_peak_error"] + 0.01, err   # sees the top between samples
    o = res.outputs
    assert np.all(o.chamber_peak_pressures >= o.chamber_pressures)
    assert np.all(o.chamber_peak_pressures[1:] >= o.chamber_pressures[:-1])


@pytest.mark.parametrize("model,rpm", [("fixed", 1375.0), ("mobility", 2500.0)])
def test_the_delivery_flow_of_a_stiff_open_chamber_is_within_budget(model, rpm):
    """Behaviour against a fresh tight reference: a worn 80-bar pump not in the family
    (test/data/pump_80bar_worn.yaml) at its top pressure, where a chamber wide open to the delivery port relaxes
    far faster than a sub-step.  Its pressure comes out of the stepper within 0.01 bar of the reference, and the
    port flow G·(p_j − p_d) multiplies that by the port's conductance: the delivery flow sampled from the
    right-hand side at the output step's end read 1.18 % (fixed centre, 1375 rpm) and 1.68 % (mobility, 2500 rpm)
    of the mean flow against the reference, over the 1 % budget, while the output step's delivered volume was
    within 0.2 % of the reference's.  The flow taken as the rate of that volume from the last sub-step's stages
    (``kernel._delivery_flow``) reads 0.56 % and 0.86 % (measured 2026-12-07; docs/numerics.md, "The delivery
    flow at the output points"); the rest of the budget holds too."""
    from pathlib import Path
    bar = 80.0
    cfg = load_config(Path(__file__).parent / "data" / "pump_80bar_worn.yaml")
    ref = reference_revolution(cfg, rpm, bar, model)
    res = run_steady(PumpModel(cfg, model), rpm, bar, max_revolutions=40, rtol=1e-6)
    err = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    for key, bound in BUDGET.items():
        assert abs(err[key]) <= bound, (key, err[key])


@pytest.mark.slow
@pytest.mark.parametrize("rpm,bar", POINTS + LOW_POINTS)
def test_golden_reference_is_reproduced_by_todays_model(cfg, rpm, bar):
    """The physics has not moved since the golden files were written (else regenerate them, on purpose)."""
    ref, _ = Revolution.load(path(rpm, bar))
    now = reference_revolution(cfg, rpm, bar, "mobility")
    err = compare(now, ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    assert abs(err["efficiency_error"]) < 1e-5
    assert err["rms_pressure_error"] < 1e-4


def test_peak_error_splits_into_solver_and_output_grid_closed_form():
    """Closed form: a pressure p_s + A(1 + cos(θ − θ_pk)) per chamber, whose peak p_s + 2A both runs report
    as their peak output; the reference sampled every 0.25°, the "default" on a 2° grid whose nearest
    sample is 0.7° from the peak.  With an exact solution the peak error is 0 and the sampled waveform's
    is the grid's alone, (cos 0.7° − 1) / 2; with a solution b·2A too high everywhere (its peak output
    too) the peak error and the solver part are b, the grid part unchanged."""
    import math

    from gerotor_twin.model.accuracy import Revolution, compare
    ps, amp, pk = 1e5, 5e5, math.radians(90.7)
    wave = lambda th: ps + amp * (1.0 + np.cos(th - pk))     # noqa: E731 - one-line closed form
    fine = np.radians(np.arange(1, 1441) * 0.25)              # (0, 2π], 0.25° samples
    coarse = np.radians(np.arange(1, 181) * 2.0)              # every 8th fine sample
    ref = Revolution(fine, np.column_stack([wave(fine)] * 2), np.ones(fine.size), 0.9, 1.0, ps + 2 * amp)
    for bias in (0.0, 0.01):
        p = wave(coarse) + bias * 2 * amp
        test = Revolution(coarse, np.column_stack([p, p]), np.ones(coarse.size), 0.9, 1.0,
                          ps + 2 * amp * (1 + bias))
        e = compare(test, ref, ps, ps + 2 * amp)
        grid = (math.cos(math.radians(0.7)) - 1.0) / 2.0
        assert e["peak_pressure_error"] == pytest.approx(bias, rel=1e-9, abs=1e-12)
        assert e["peak_sampling_error"] == pytest.approx(grid, rel=1e-6)
        assert e["peak_numerics_error"] == pytest.approx(bias, rel=1e-6, abs=1e-12)
        assert e["sampled_peak_error"] == pytest.approx(grid + bias, rel=1e-6)


def test_numerics_defaults_of_the_dataclass_are_those_of_the_packaged_config(cfg):
    """Behaviour: a pump YAML without a ``numerics`` section (a user's own pump) gets the same numerics as
    the packaged config, whose defaults the error budget is measured for (an output step of 2° instead of 1.5°
    misses the RMS budget at 3000 rpm, docs/numerics.md)."""
    from dataclasses import asdict
    from gerotor_twin.config import Numerics, parse_config
    assert asdict(Numerics()) == asdict(cfg.numerics)
    raw = cfg.to_dict()
    raw.pop("numerics")
    assert parse_config(raw).numerics == cfg.numerics


@pytest.mark.parametrize("value", [0.0, 1.5, float("nan")])
def test_closing_tolerance_out_of_range_is_refused_naming_the_field(value):
    from gerotor_twin.config import Numerics
    from gerotor_twin.errors import InputError
    with pytest.raises(InputError, match=r"numerics\.closing_tolerance"):
        Numerics(closing_tolerance=value)
