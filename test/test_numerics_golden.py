"""Default numerics against golden reference revolutions (golden tier).

The references in test/golden/ are revolutions at periodic steady state of the default pump,
mobility model, computed with tight numerics (ROS2 tolerance 1e-8 on ln(ρ/ρ₀), output step 8×
finer; test/golden/make_reference.py, git revision in each file). The default numerics must stay
within the error budget of issue 10 at each point: RMS chamber-pressure error ≤ 1 % of
(p_delivery − p_suction), |η error| ≤ 0.3 % relative, |peak-pressure error| ≤ 2 %.
A change of the default numerics (step, tolerance, error measure) that breaks it fails here.
"""
import numpy as np
import pytest

from dataclasses import replace

from golden.make_reference import LOW_POINTS, POINTS, path
from gerotor_twin.model.accuracy import BUDGET, Revolution, compare, reference_revolution
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady


def flow_number_law(cfg):
    """``cfg`` with the flow-number orifice law, the default before Merritt's law (fee6c52): the pump on which the
    spikes and tops below were found and measured (Merritt's default law fills a just-opened chamber
    differently, and those instances moved; the 78-point grid in docs/numerics.md covers it)."""
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
    clipped, sub-step cap ``rate_fraction`` 0.3, ``closing_tolerance`` 0.25) keep the whole budget, the
    peak of the closing chamber's spike included.  Before ∂f/∂t the RMS was 2.73 / 1.70 % at 5 / 15 bar,
    3000 rpm; with ∂f/∂t alone the 15-bar peak was +4.1 % (docs/numerics.md)."""
    ref, meta = Revolution.load(path(rpm, bar))
    assert (meta["rpm"], meta["bar"], meta["model"]) == (rpm, bar, "mobility")
    res = run_steady(PumpModel(cfg, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
    err = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    for key, bound in BUDGET.items():
        assert abs(err[key]) <= bound, (key, err[key])


def test_closing_tolerance_brings_the_spike_peak_within_budget(cfg):
    """Behaviour against fresh tight references (:func:`reference_revolution`), mobility, 1000 rpm / 5 bar,
    where the peak error is the solver's (the output grid misses 0.2 %).  With the gear moved after each output
    step (``gear_coupling: partitioned``), without the tighter tolerance on chambers whose delivery port closes
    (``closing_tolerance`` 1) the spike's peak overshoots beyond the 2 % budget (+3.9 % measured) and with the
    default 0.25 it is within (+1.73 %).  With the gear in the stages (default) the gear relieves part of the
    spike itself, and the bound on hidden tops (``top_tolerance``) takes more: +0.52 % with the factor 1,
    +0.29 % with 0.25 (+2.00 / +1.55 % without the bound).  Run on the pump whose suction kidney ends at a
    radial ray, where the spike is steepest: with the default chamber-cut kidney the chambers arrive filled
    and the factor-1 peaks are +1.53 % (partitioned) and −0.25 % (stages).  Flow-number law
    (:func:`flow_number_law`); with Merritt's the stages give +0.49 / −0.09 % and the partitioned gear
    +3.28 / +2.29 % (outside the budget even at 0.25: the stages are the default for that reason)."""
    rpm, bar = 1000.0, 5.0
    cfg = flow_number_law(replace(cfg, suction_port=replace(cfg.suction_port, closing_edge="ray")))
    pd = cfg.fluid.atmospheric_pa + bar * 1e5
    peak = {}
    for scheme in ("partitioned", "stages"):
        c0 = replace(cfg, numerics=replace(cfg.numerics, gear_coupling=scheme))
        ref = reference_revolution(c0, rpm, bar, "mobility")
        for factor in (1.0, cfg.numerics.closing_tolerance):
            c = replace(c0, numerics=replace(c0.numerics, closing_tolerance=factor))
            res = run_steady(PumpModel(c, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
            peak[scheme, factor] = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa,
                                           pd)["peak_pressure_error"]
    assert cfg.numerics.closing_tolerance == 0.25
    assert peak["partitioned", 1.0] > BUDGET["peak_pressure_error_gauge"], peak
    assert abs(peak["partitioned", 0.25]) <= BUDGET["peak_pressure_error_gauge"], peak
    assert abs(peak["stages", 0.25]) <= BUDGET["peak_pressure_error_gauge"], peak
    assert peak["stages", 0.25] < peak["stages", 1.0] - 0.002, peak


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


def test_rate_fraction_default_and_wired_through(cfg):
    """Behaviour: the packaged config and the dataclass default agree (0.3); a tighter cap takes more,
    shorter sub-steps over the same 40 ms at 5 bar than none (the cap binds on the spikes)."""
    from gerotor_twin.config import Numerics
    from gerotor_twin.model.pump import Inputs
    assert cfg.numerics.rate_fraction == Numerics().rate_fraction == 0.3
    inp = Inputs(314.159, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + 5e5)
    steps = {}
    for rf in (0.0, 0.1):
        m = PumpModel(replace(cfg, numerics=replace(cfg.numerics, rate_fraction=rf)), "mobility")
        st, out = m.advance(m.initial_state(inp), 0.04, inp)
        assert np.all(np.isfinite(out.chamber_pressures))
        steps[rf] = st.counts["substeps"]
    assert steps[0.1] > 1.2 * steps[0.0], steps


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
    the packaged config, whose defaults the error budget is measured for (the dataclass said 2° while
    config/pump.yaml said 1.5° until 29188e6; 2° misses the RMS budget at 3000 rpm, docs/numerics.md)."""
    from dataclasses import asdict
    from gerotor_twin.config import Numerics, parse_config
    assert asdict(Numerics()) == asdict(cfg.numerics)
    raw = cfg.to_dict()
    raw.pop("numerics")
    assert parse_config(raw).numerics == cfg.numerics


@pytest.mark.parametrize("value", [-0.1, 10.5, float("nan")])
def test_rate_fraction_out_of_range_is_refused_naming_the_field(value):
    from gerotor_twin.config import Numerics
    from gerotor_twin.errors import InputError
    with pytest.raises(InputError, match=r"numerics\.rate_fraction"):
        Numerics(rate_fraction=value)


@pytest.mark.parametrize("value", [0.0, 1.5, float("nan")])
def test_closing_tolerance_out_of_range_is_refused_naming_the_field(value):
    from gerotor_twin.config import Numerics
    from gerotor_twin.errors import InputError
    with pytest.raises(InputError, match=r"numerics\.closing_tolerance"):
        Numerics(closing_tolerance=value)


@pytest.mark.parametrize("value", [-0.1, 1.5, float("nan")])
def test_top_tolerance_out_of_range_is_refused_naming_the_field(value):
    from gerotor_twin.config import Numerics
    from gerotor_twin.errors import InputError
    with pytest.raises(InputError, match=r"numerics\.top_tolerance"):
        Numerics(top_tolerance=value)


def test_top_tolerance_finds_the_top_between_sub_steps(cfg):
    """Behaviour against a fresh tight reference (its log-density measure does not use the top bound),
    mobility, 2750 rpm / 9 bar, where the closing chamber's top fell between sub-steps: without the bound
    (``top_tolerance`` 0) the peak output misses it by more than the 2 % budget (−2.30 % measured), with
    the default 0.25 it is within half of it (−0.42 %).  Flow-number law (:func:`flow_number_law`); with
    Merritt's this top is not hidden (+0.05 % either way)."""
    rpm, bar = 2750.0, 9.0
    cfg = flow_number_law(cfg)
    pd = cfg.fluid.atmospheric_pa + bar * 1e5
    ref = reference_revolution(cfg, rpm, bar, "mobility")
    peak = {}
    for factor in (0.0, cfg.numerics.top_tolerance):
        c = replace(cfg, numerics=replace(cfg.numerics, top_tolerance=factor))
        res = run_steady(PumpModel(c, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
        peak[factor] = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, pd)["peak_pressure_error"]
    assert cfg.numerics.top_tolerance == 0.25
    assert abs(peak[0.0]) > BUDGET["peak_pressure_error_gauge"], peak
    assert abs(peak[0.25]) <= 0.5 * BUDGET["peak_pressure_error_gauge"], peak
