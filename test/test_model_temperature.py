"""The pump model at the oil temperature: kernel properties, leakage scaling, continuity (closed form / behaviour)."""
import math

import numpy as np
import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.hydraulics.state_equation import pressure_of
from gerotor_twin.model.pump import TEMPERATURE_STEP_K, Inputs, PumpModel

W = 2000 * math.pi / 30
PS, PD = 101325.0, 101325.0 + 20e5
T1, T2 = 303.15, 343.15        # 30 and 70 °C


@pytest.fixture
def model(cfg):
    return PumpModel(cfg, "fixed")


def test_kernel_properties_follow_the_oil(cfg, model):
    """Closed form: at T the kernel holds μ(T), ρ(T) and β_L(T) of the config's oil (ratio form of fluid_at)."""
    oil, ref = cfg.oil, cfg.reference_temperature_k
    model.set_temperature(T2)
    pc, eos = model.kernel.pc, model.kernel.eos
    assert pc.viscosity == pytest.approx(cfg.fluid.viscosity_pa_s * oil.viscosity(T2) / oil.viscosity(ref), rel=1e-12)
    assert pc.density == pytest.approx(cfg.fluid.density_kg_m3 * oil.density(T2) / oil.density(ref), rel=1e-12)
    assert eos.beta_liquid == pytest.approx(1.5e9 * (1 - 2.866e-3 * (T2 - 313.15)), rel=1e-12)


def test_leakage_at_fixed_clearances_scales_as_the_viscosity_ratio(model):
    """Closed form: the lateral, suction–delivery and drain conductances and the drain / suction–delivery
    flows at the same imposed pressures scale exactly as μ(T1)/μ(T2) between two temperatures."""
    model.set_temperature(T1)
    pc1 = model.kernel.pc
    inp1 = Inputs(W, PS, PD, T1)
    s, o1 = model.advance(model.initial_state(inp1), 0.02, inp1)
    model.set_temperature(T2)
    pc2 = model.kernel.pc
    _, o2 = model.advance(s, 0.02, Inputs(W, PS, PD, T2))
    ratio = pc1.viscosity / pc2.viscosity
    assert 4.0 < ratio < 6.0                       # VG46-like oil, 30 → 70 °C
    for f in ("g_lateral", "g_suction_delivery", "g_drain"):
        assert getattr(pc2, f) / getattr(pc1, f) == pytest.approx(ratio, rel=1e-12), f
    assert o2.leak_drain.mean() / o1.leak_drain.mean() == pytest.approx(ratio, rel=1e-12)
    assert o2.leak_suction_delivery.mean() / o1.leak_suction_delivery.mean() == pytest.approx(ratio, rel=1e-12)


def test_temperature_change_keeps_the_pressures_continuous(model):
    """Behaviour: a temperature step re-evaluates the properties and converts ln ρ so that every
    pressure is unchanged (to round-off)."""
    inp = Inputs(W, PS, PD, 313.15)
    s, _ = model.advance(model.initial_state(inp), 0.03, inp)
    p_before = np.array([pressure_of(v, model.kernel.eos) for v in s.log_density])
    y = model.set_temperature(353.15, s.log_density.copy())
    p_after = np.array([pressure_of(v, model.kernel.eos) for v in y])
    assert not np.allclose(y, s.log_density, rtol=0, atol=1e-9)       # the state did change ...
    assert np.allclose(p_after, p_before, rtol=1e-9, atol=1e-3)       # ... its pressures did not


def test_small_temperature_moves_do_not_rebuild(model):
    """Behaviour: within TEMPERATURE_STEP_K of the last evaluation nothing is rebuilt (the hot loop keeps
    its structures); beyond it, it is."""
    model.set_temperature(313.15)
    km = model.kernel
    model.set_temperature(313.15 + 0.9 * TEMPERATURE_STEP_K)
    assert model.kernel is km
    model.set_temperature(313.15 + 1.1 * TEMPERATURE_STEP_K)
    assert model.kernel is not km


def test_bad_temperature_input(model):
    """Behaviour: NaN and out-of-range oil temperatures raise InputError naming the field and range."""
    for bad in (float("nan"), 100.0, 600.0):
        with pytest.raises(InputError) as ei:
            model.check_inputs(Inputs(W, PS, PD, bad))
        assert ei.value.field == "oil_temperature"


def test_paper_state_equation_is_rescaled_not_rebuilt(cfg):
    """Closed form: eq. (23)'s s(p) ∝ 1/β*, so the rescaled table at 77 °C inverts like a freshly built one
    (within the table's stated 2e-4 Pa) and s(p) agrees exactly."""
    from gerotor_twin.hydraulics.state_equation import log_density_of
    from gerotor_twin.model.params import kernel_model
    c = cfg.with_fluid_model("paper")
    m = PumpModel(c, "fixed")
    m.set_temperature(350.0)
    fresh = kernel_model(c, m.tables, m.lateral, temperature_k=350.0).eos
    for p in (3e3, 5e4, 99e3, 101e3, 103e3, 2e6):
        assert log_density_of(p, m.kernel.eos) == pytest.approx(log_density_of(p, fresh), rel=1e-12, abs=1e-300)
        assert abs(pressure_of(log_density_of(p, fresh), m.kernel.eos) - p) <= 2e-4
