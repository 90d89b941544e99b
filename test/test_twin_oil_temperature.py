"""The twin core follows the oil temperature: measured while fresh, else the reference with a WARN (behaviour)."""
import math

import pytest

from gerotor_twin.io import messages as m
from gerotor_twin.twin import TwinCore, TwinSettings
from gerotor_twin.twin.events import EventLog
from gerotor_twin.twin.oil_temperature import MEASURED, REFERENCE, STALE, OilTemperature

MS = 1_000_000
NS = 1_000_000_000
W = 2000 * math.pi / 30
PD = 101325.0 + 20e5


@pytest.fixture(scope="module")
def model():
    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    return PumpModel(load_config(), "fixed")


def test_oil_temperature_sources():
    """Behaviour: fresh sample → its value [K]; none → reference, no event; stale → reference + one WARN."""
    ev = EventLog(period_ns=NS)
    ot = OilTemperature(313.15, stale_timeout_s=0.5, events=ev)
    assert ot.at(0, None) is None and ot.source == REFERENCE and not ot.warn and ev.pop() == []
    assert ot.at(NS, (70.0, NS - 100 * MS)) == pytest.approx(343.15)
    assert ot.source == MEASURED
    assert ot.at(2 * NS, (70.0, NS - 100 * MS)) is None            # 1.1 s old
    assert ot.source == STALE and ot.warn and ot.fallbacks == 1
    (level, text), = ev.pop()
    assert level == 1 and "oil_temperature stale" in text and "40 °C" in text
    assert ot.report() == {"oil_temperature_c": pytest.approx(40.0), "oil_temperature_source": STALE,
                           "oil_temperature_fallbacks": 1, "oil_temperature_lead_k": 0.0}


@pytest.mark.parametrize("tau", [1.0, 3.0, 10.0])
def test_thermometer_lag_compensation_on_a_ramp(tau):
    """Closed form: a first-order sensor (τ) on a ramp T = T0 + r·t reads T0 + r·(t − τ(1 − e^(−t/τ)));
    once e^(−t/τ) is negligible the compensated value T_m + τ·dT_m/dt equals the true T exactly.
    Uncompensated, the reading is r·τ low."""
    r, t0c = 0.4, 30.0                                        # K/s, °C
    true = lambda t: t0c + r * t                              # noqa: E731
    read = lambda t: t0c + r * (t - tau * (1 - math.exp(-t / tau)))   # noqa: E731
    comp = OilTemperature(313.15, 0.5, EventLog(period_ns=NS), sensor_tau_s=tau)
    plain = OilTemperature(313.15, 0.5, EventLog(period_ns=NS))
    t_end = 20 * tau
    for k in range(int(t_end * 5) + 1):                       # 5 Hz readings, model asks at each
        t = k * 0.2
        sample = (read(t), int(round(t * NS)))
        got, raw = comp.at(sample[1], sample), plain.at(sample[1], sample)
    assert got - 273.15 == pytest.approx(true(t_end), abs=1e-6)
    assert raw - 273.15 == pytest.approx(true(t_end) - r * tau, abs=1e-6)
    assert comp.report()["oil_temperature_lead_k"] == pytest.approx(r * tau, rel=1e-6)


def test_thermometer_lag_compensation_restarts_with_the_source():
    """Behaviour: readings stamped back in time (a restarted source) start a new window: no lead from a
    slope across the restart."""
    comp = OilTemperature(313.15, 0.5, EventLog(period_ns=NS), sensor_tau_s=3.0)
    for k in range(20):
        comp.at(k * NS // 5, (30.0 + k, k * NS // 5))
    assert comp.report()["oil_temperature_lead_k"] > 0
    assert comp.at(NS // 10, (50.0, NS // 10)) == pytest.approx(323.15)
    assert comp.report()["oil_temperature_lead_k"] == 0.0


def _run(core, t0_ms, t1_ms, temp_c=None):
    for t in range(t0_ms, t1_ms, 5):
        core.add_sample("shaft_speed", W, t * MS, t * MS)
        core.add_sample("delivery_pressure", PD, t * MS, t * MS)
        if temp_c is not None:
            core.add_sample("oil_temperature", temp_c, t * MS, t * MS)
        core.tick(t * MS)


def test_core_uses_the_measured_temperature_then_falls_back_with_a_warn(model):
    """Behaviour: 70 °C samples set the model to 343.15 K (μ at 70 °C); when they stop, after the stale
    timeout the model returns to the 40 °C reference and /diagnostics says WARN with the reason."""
    s = TwinSettings(max_span_s=math.inf, stale_timeout_s=0.5)
    core = TwinCore(model, s)
    _run(core, 0, 300, temp_c=70.0)
    assert model.temperature_k == pytest.approx(343.15, abs=0.06)     # filtered, within the update step
    assert model.kernel.pc.viscosity == pytest.approx(model.config.fluid_at(model.temperature_k).viscosity_pa_s)
    diag = core.diagnostics(300 * MS)
    st = diag["status"][0]
    vals = {kv["key"]: kv["value"] for kv in st["values"]}
    assert vals["oil_temperature_source"] == MEASURED
    assert float(vals["oil_temperature_c"]) == pytest.approx(70.0, abs=0.1)
    _run(core, 300, 1200)                                              # speed and pressure only
    assert model.temperature_k == model.config.reference_temperature_k
    diag = core.diagnostics(1200 * MS)
    st = diag["status"][0]
    assert st["level"] == m.DIAG_WARN and "oil temperature stale" in st["message"]
    assert any("oil_temperature stale" in text for _lvl, text in core.pop_events())


def test_out_of_range_and_nan_temperatures_are_rejected_and_counted(model):
    """Behaviour: NaN and 250 °C (outside the oil laws' −40…200 °C) are rejected by reason; the model keeps
    the last good value."""
    core = TwinCore(model, TwinSettings(max_span_s=math.inf))
    assert core.add_sample("oil_temperature", 60.0, 1, 1)
    assert not core.add_sample("oil_temperature", float("nan"), 2, 2)
    assert not core.add_sample("oil_temperature", 250.0, 3, 3)
    rej = core.input_report(10)["oil_temperature"]["rejected"]
    assert {k: v for k, v in rej.items() if v} == {"nonfinite": 1, "out_of_range": 1}
    assert "[-40, 200] °C" in core.input_report(10)["oil_temperature"]["last_error"]
