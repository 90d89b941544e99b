"""Default numerics against golden reference revolutions (golden tier).

The references in test/golden/ are revolutions at periodic steady state of the default pump,
mobility model, computed with tight numerics (ROS2 tolerance 1e-8 on ln(ρ/ρ₀), output step 8×
finer; test/golden/make_reference.py, git revision in each file). The default numerics must stay
within the error budget of issue 10 at each point: RMS chamber-pressure error ≤ 1 % of
(p_delivery − p_suction), |η error| ≤ 0.3 % relative, |peak-pressure error| ≤ 2 %.
A change of the default numerics (step, tolerance, error measure) that breaks it fails here.
"""
import pytest

from golden.make_reference import POINTS, path
from gerotor_twin.model.accuracy import BUDGET, Revolution, compare, reference_revolution
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady


@pytest.mark.parametrize("rpm,bar", POINTS)
def test_default_numerics_within_budget_of_the_golden_reference(cfg, rpm, bar):
    ref, meta = Revolution.load(path(rpm, bar))
    assert (meta["rpm"], meta["bar"], meta["model"]) == (rpm, bar, "mobility")
    res = run_steady(PumpModel(cfg, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
    err = compare(Revolution.of(res), ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    for key, bound in BUDGET.items():
        assert abs(err[key]) <= bound, (key, err[key])


@pytest.mark.slow
@pytest.mark.parametrize("rpm,bar", POINTS)
def test_golden_reference_is_reproduced_by_todays_model(cfg, rpm, bar):
    """The physics has not moved since the golden files were written (else regenerate them, on purpose)."""
    ref, _ = Revolution.load(path(rpm, bar))
    now = reference_revolution(cfg, rpm, bar, "mobility")
    err = compare(now, ref, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)
    assert abs(err["efficiency_error"]) < 1e-5
    assert err["rms_pressure_error"] < 1e-4
