"""A sub-step that fails is never silent, and one output step's work is bounded (behaviour tier).

The kernel abandons an output step when a sub-step at the smallest size gives a non-finite state
(``kernel.STEP_NONFINITE``) or when ``numerics.max_substep_attempts`` sub-steps do not finish it
(``kernel.STEP_WORK_BOUND``); ``PumpModel.advance`` raises :class:`SolverFailure` naming the time, the
angle and the reason, and the twin resets the model, counts the reset and says it (docs/node.md).
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from gerotor_twin.config import load_config
from gerotor_twin.geometry.tables import DV
from gerotor_twin.model import kernel as K
from gerotor_twin.model.pump import Inputs, PumpModel, SolverFailure

W = 3000 * math.pi / 30          # [rad/s]


def _inputs(cfg, bar=10.0):
    return Inputs(W, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + bar * 1e5)


def _poison(model, column=DV, value=math.nan):
    """``model`` with one column of its own copy of the geometry table set to ``value`` (a non-finite
    right-hand side wherever the chambers are)."""
    tab = model.kernel.tab
    rows = tab.rows.copy()
    rows[:, column] = value
    model.kernel = model.kernel._replace(tab=tab._replace(rows=rows))
    return model


@pytest.mark.parametrize("gear", ["fixed", "mobility"])
def test_non_finite_right_hand_side_is_a_solver_failure_not_a_frozen_state(gear):
    """Behaviour: with a non-finite dV/dθ the first sub-step cannot be made finite at any size; the call
    raises :class:`SolverFailure` (a ``FloatingPointError``) naming the reason, and the abandoned step is
    counted, instead of returning the unchanged pressures with the angle and time advanced."""
    cfg = load_config()
    m = PumpModel(cfg, gear)
    inp = _inputs(cfg)
    s, _ = m.advance(m.initial_state(inp), 0.01, inp)
    _poison(m)
    with pytest.raises(SolverFailure, match="non-finite") as exc:
        m.advance(s, 0.002, inp)
    assert isinstance(exc.value, FloatingPointError) and "shaft angle" in str(exc.value)
    assert m._ws.ctrl[K.CT_STATUS] == K.STEP_NONFINITE


def test_one_output_step_does_at_most_the_bounded_work():
    """Behaviour (a stiff burst): a tolerance of 1e-12 asks for about 1e5 sub-steps per output step (the
    smallest sub-step is 1e-5 of it); the step is abandoned after ``numerics.max_substep_attempts`` (2000)
    attempts, so one call's work has a bound the node can rely on, and the failure is raised, not a silent
    loss of accuracy.  The tight references raise the bound and finish."""
    cfg = load_config()
    tight = replace(cfg, numerics=replace(cfg.numerics, tolerance=1e-12, log_density_tolerance=1e-12))
    m = PumpModel(tight, "fixed")
    inp = _inputs(cfg)
    s0 = m.initial_state(inp)
    with pytest.raises(SolverFailure, match="sub-steps did not finish") as exc:
        m.advance(s0, 5 * m.step_size(inp.omega), inp)
    assert "max_substep_attempts = 2000" in str(exc.value)
    done = m._ws  # the attempts of the abandoned step: accepted + rejected ≤ the bound
    assert done.ctrl[K.CT_STATUS] == K.STEP_WORK_BOUND


def test_normal_running_is_never_abandoned():
    """Behaviour: on the default pump at low and rated pressure the bound is far away (no step abandoned,
    the counter in ``PumpState.counts`` stays 0)."""
    cfg = load_config()
    m = PumpModel(cfg, "mobility")
    for bar in (0.5, 27.5):
        inp = _inputs(cfg, bar)
        s, _ = m.advance(m.initial_state(inp), 0.05, inp)
        assert s.counts["abandoned_steps"] == 0 and np.all(np.isfinite(s.pressures))


def test_the_twin_resets_on_a_solver_failure_and_says_it():
    """Behaviour: the twin core turns the failure into a counted reset with the reason in its events, and
    runs on once the model is sound again."""
    from gerotor_twin.twin import TwinCore
    cfg = load_config()
    m = PumpModel(cfg, "fixed")
    core = TwinCore(m)
    ms, pd = 1_000_000, cfg.fluid.atmospheric_pa + 10e5
    for t in range(0, 100, 5):
        core.add_sample("shaft_speed", W, t * ms, t * ms)
        core.add_sample("delivery_pressure", pd, t * ms, t * ms)
        core.tick(t * ms)
    good = m.kernel
    _poison(m)
    for t in range(100, 120, 5):
        core.add_sample("shaft_speed", W, t * ms, t * ms)
        core.add_sample("delivery_pressure", pd, t * ms, t * ms)
        core.tick(t * ms)
    assert core.stats["resets"]["solver_failure"] >= 1
    assert any("solver failure" in text and "non-finite" in text for _, text in core.pop_events())
    m.kernel = good
    for t in range(120, 200, 5):
        core.add_sample("shaft_speed", W, t * ms, t * ms)
        core.add_sample("delivery_pressure", pd, t * ms, t * ms)
        core.tick(t * ms)
    assert core.status == "running" and np.all(np.isfinite(core.state.pressures))


@pytest.mark.parametrize("value", [0, 9, 2.5, 1e8])
def test_max_substep_attempts_out_of_range_is_refused_naming_the_field(value):
    """Behaviour: the bound is an integer in [10, 1e7]; anything else is one error naming it."""
    from gerotor_twin.config import Numerics
    from gerotor_twin.errors import InputError
    with pytest.raises(InputError, match=r"numerics\.max_substep_attempts"):
        Numerics(max_substep_attempts=value)
