"""The sub-step error scale Δp_ref: the larger of p_d − p_s and the chamber pressures' recent range.

Closed-form tests of the two small functions that make it (:func:`gerotor_twin.model.step_control.update_range`,
:func:`gerotor_twin.model.step_control.error_scale`), and behaviour tests that the range the model carries in its
state is the range of the waveform the error budget is stated on (docs/numerics.md, "Step control").
"""
import math

import numpy as np
import pytest

from gerotor_twin.config import load_config
from gerotor_twin.model.accuracy import reference_revolution
from gerotor_twin.model.family import family_dir
from gerotor_twin.model import kernel as K
from gerotor_twin.model import step_control as SC
from gerotor_twin.model.params import operating, workspace
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady


def _range_after(previous, pres, fade):
    ctrl = np.zeros(6)
    ctrl[K.CT_RANGE] = previous
    SC.update_range(ctrl, np.asarray(pres, float), len(pres), fade)
    return ctrl[K.CT_RANGE]


def test_pressure_range_is_the_highest_minus_the_lowest_sample():
    """Closed form: with nothing to fade (previous range 0) the range after a step is max_i p_i − min_i p_i
    over the chambers' pressures at the step's end; with a larger faded range, that."""
    pres = [1e5, 2e5, 0.9e5, 3e5]
    assert _range_after(0.0, pres, 0.9) == pytest.approx(3e5 - 0.9e5, rel=1e-15)
    assert _range_after(5e5, pres, 0.9) == pytest.approx(4.5e5, rel=1e-15)


@pytest.mark.parametrize("revolutions", [0.5, 1.0, 3.0])
def test_pressure_range_fades_by_one_e_per_revolution(revolutions):
    """Closed form: with the fade of the output step, a large range left alone over k revolutions of small
    steps is R·e^{−k}, unless the chambers' own spread is larger."""
    rpm, h = 3000.0, 1e-5
    omega = rpm * math.pi / 30.0
    fade = math.exp(-omega * h / (2.0 * math.pi))
    steps = round(revolutions * 2.0 * math.pi / (omega * h))
    r = 50e5
    for _ in range(steps):
        r = _range_after(r, [1e5, 1.1e5, 1e5], fade)
    assert r == pytest.approx(50e5 * math.exp(-steps * omega * h / (2.0 * math.pi)), rel=1e-9)
    assert _range_after(1e3, [1e5, 1.1e5, 1e5], fade) == pytest.approx(1e4, rel=1e-12)


def test_error_scale_is_the_larger_of_the_pressure_difference_and_the_range(cfg):
    """Closed form: Δp_ref = max(p_d − p_s, 1 bar, range) (:func:`step_control.error_scale`)."""
    km = PumpModel(cfg, "fixed").kernel
    ws = workspace(km.pc.n)
    ps = 1e5
    for pd, rng, want in ((29e5, 0.0, 28e5), (3e5, 40e5, 40e5), (1.2e5, 0.0, 1e5), (1.2e5, 0.5e5, 1e5)):
        op = operating(km, 300.0, ps, pd)
        ws.ctrl[K.CT_RANGE] = rng
        assert SC.error_scale(op, ws) == pytest.approx(want, rel=1e-15)


def test_a_run_split_at_step_boundaries_is_the_run_in_one_call(cfg):
    """Behaviour: the range is updated per output step, not per call, so two calls give the one call's
    state, range included (at 0.8 bar, where the range, not p_d − p_s, is the scale)."""
    from gerotor_twin.model.pump import Inputs
    m = PumpModel(cfg, "mobility")
    inp = Inputs(3000 * math.pi / 30, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + 0.8e5)
    h = m.step_size(inp.omega)
    s0 = m.initial_state(inp)
    a, _ = m.advance(s0, 60 * h, inp)
    b, _ = m.advance(s0, 25 * h, inp)
    b, _ = m.advance(b, 35 * h, inp)
    assert a.pressure_range > 3.0 * (inp.p_delivery - inp.p_suction)
    assert b.pressure_range == pytest.approx(a.pressure_range, rel=1e-9)
    assert np.allclose(a.pressures, b.pressures, rtol=1e-9)


@pytest.mark.parametrize("pump,rpm,bar", [("04_motorcycle_engine_oil", 7000.0, 0.6),
                                          ("06_car_engine_oil_notched", 7000.0, 0.8)])
def test_state_carries_the_range_of_the_reference_waveform(pump, rpm, bar):
    """Behaviour against a fresh tight reference (log-density measure, which does not use the scale): at the
    top speed and lowest delivery pressure of two engine-oil pumps of the family, the trapped chambers'
    spike makes the waveform's range many times p_d − p_s; the range the default run carries in its state
    is the reference waveform's own (highest peak − lowest sample), faded by at most one chamber period
    since the last spike: R/R_ref in [e^{−1/N}, 1] (a chamber spikes every 1/N revolution; the range fades
    by 1/e per revolution), each end widened by 3 % for the default's own error, so the error budget and
    the step control use one scale."""
    cfg = load_config(family_dir() / f"{pump}.yaml")
    ref = reference_revolution(cfg, rpm, bar, "mobility")
    ref_range = ref.peak_pressure - float(ref.chamber_pressures.min())
    res = run_steady(PumpModel(cfg, "mobility"), rpm, bar, max_revolutions=40, rtol=1e-6)
    assert ref_range > 5.0 * bar * 1e5
    ratio = res.state.pressure_range / ref_range
    assert 0.97 * math.exp(-1.0 / cfg.gears.chambers) <= ratio <= 1.03, ratio
