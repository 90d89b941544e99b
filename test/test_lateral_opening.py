"""The lateral gap opening with the pressure load (``clearances.lateral_opening_m_per_pa``).

Tiers: closed form (the gap s₀ + c·max(Δp, 0); the lateral conductances ∝ s³ of the sector law, Eq. (20)-type
Poiseuille flow); behaviour against an independent route (a loaded pump equals a rigid pump whose clearance is
the loaded gap, at any oil temperature and in both boundary modes; the gap re-evaluated only when it moved);
bad input (the config's range); closed form on a synthetic truth (a map made by the twin at a known opening is
recovered within its 95 % interval, and the rigid gaps cannot represent it).
"""
import dataclasses
import math

import numpy as np
import pytest

from gerotor_twin.config import load_config, parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.model.params import at_load, lateral_gap
from gerotor_twin.model.pump import LOAD_GAP_STEP, Inputs, PumpModel

#: an opening of 2 µm per bar [m/Pa]
OPENING = 2e-11


def _with(cfg, opening=OPENING, lateral=None):
    c = dataclasses.replace(cfg.clearances, lateral_opening_m_per_pa=opening,
                            lateral_m=cfg.clearances.lateral_m if lateral is None else lateral)
    return dataclasses.replace(cfg, clearances=c)


def test_lateral_gap():
    """Closed form: 100 µm opening by 2 µm/bar at 20 bar → 140 µm; a negative Δp does not close it; a rigid pump
    keeps its clearance."""
    cfg = _with(load_config())
    cfg = _with(cfg, lateral=100e-6)
    assert lateral_gap(cfg, 20e5) == pytest.approx(140e-6, rel=1e-12)
    assert lateral_gap(cfg, -5e5) == 100e-6
    assert lateral_gap(_with(cfg, 0.0), 20e5) == 100e-6


def test_at_load_scales_the_lateral_conductances_as_the_gap_cubed():
    """Closed form: every lateral path (lobe, suction–delivery ring, drain) is laminar sector flow ∝ h³/μ, so at
    the gap s₀ + cΔp each conductance is (1 + cΔp/s₀)³ times the unloaded one; the viscosity and the other
    constants are untouched."""
    cfg = _with(load_config())
    m = PumpModel(cfg)
    pc0 = m.kernel.pc
    dp = 15e5
    pc1 = at_load(m.kernel, cfg, m.lateral, dp).pc
    ratio = (1 + OPENING * dp / cfg.clearances.lateral_m) ** 3
    for f in ("g_lateral", "g_suction_delivery", "g_drain"):
        assert getattr(pc1, f) == pytest.approx(ratio * getattr(pc0, f), rel=1e-12)
    assert pc1._replace(g_lateral=0.0, g_suction_delivery=0.0, g_drain=0.0) == \
        pc0._replace(g_lateral=0.0, g_suction_delivery=0.0, g_drain=0.0)


def test_loaded_pump_is_the_rigid_pump_at_the_loaded_gap():
    """Behaviour, against an independent route: a pump whose lateral gap opens by c per Pa, advanced at a
    delivery pressure p_d, is the rigid pump whose clearance is s₀ + c(p_d − p_s): the same chamber pressures,
    eccentricity and delivery flow, bit for bit, at the reference oil temperature and at 60 °C (the load and
    the temperature composed in either order)."""
    base = load_config()
    p_s = base.boundary.suction_pressure_pa
    inp = Inputs(omega=2000 * math.pi / 30, p_suction=p_s, p_delivery=p_s + 20e5, oil_temperature=333.15)
    loaded = PumpModel(_with(base))
    rigid = PumpModel(_with(base, 0.0, lateral=lateral_gap(_with(base), 20e5)))
    runs = []
    for m in (loaded, rigid):
        s = m.initial_state(inp)
        s, out = m.advance(s, 20 * m.step_size(inp.omega), inp)
        runs.append((s.pressures, s.eccentricity, out.delivery_flow))
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)
    assert loaded.load_dp == 20e5
    loaded.set_temperature(303.15)               # back to 30 °C after the load: still the loaded gap
    rigid.set_temperature(303.15)
    for f in ("g_lateral", "g_suction_delivery", "g_drain", "viscosity"):
        assert getattr(loaded.kernel.pc, f) == getattr(rigid.kernel.pc, f)


def test_gap_re_evaluated_only_when_it_moved():
    """Behaviour: a change of Δp that moves the gap by less than LOAD_GAP_STEP of s₀ keeps the kernel (no
    rebuild); a larger one rebuilds it; a rigid pump never does."""
    cfg = _with(load_config())
    m = PumpModel(cfg)
    m.set_load(10e5)
    km = m.kernel
    small = 0.5 * LOAD_GAP_STEP * cfg.clearances.lateral_m / OPENING
    m.set_load(10e5 + small)
    assert m.kernel is km and m.load_dp == 10e5
    m.set_load(10e5 + 3 * small)
    assert m.kernel is not km and m.load_dp == 10e5 + 3 * small
    rigid = PumpModel(load_config())
    km = rigid.kernel
    rigid.set_load(25e5)
    assert rigid.kernel is km


def test_restriction_mode_loads_with_the_delivery_line_pressure():
    """Behaviour: with the delivery line a state (``boundary.mode: restriction``), the gap follows the line's
    pressure at the start of each output step, not the tank pressure given as the delivery input."""
    raw = load_config().to_dict()
    raw["boundary"]["mode"] = "restriction"
    raw["clearances"]["lateral_opening_m_per_pa"] = OPENING
    m = PumpModel(parse_config(raw))
    p_s = m.config.boundary.suction_pressure_pa
    inp = Inputs(omega=3000 * math.pi / 30, p_suction=p_s, p_delivery=p_s)
    s = m.initial_state(inp)
    for _ in range(40):
        line = s.pressures[m.N]
        s, _ = m.advance(s, 5 * m.step_size(inp.omega), inp)
    assert line - p_s > 1e5                          # the restriction loads the pump
    assert abs(m.load_dp - (line - p_s)) * OPENING <= LOAD_GAP_STEP * m.config.clearances.lateral_m


def test_config_range():
    """Bad input: a negative opening or one above 1e-9 m/Pa is refused naming the field and range; absent
    means rigid; the value survives the round trip through ``to_dict``."""
    raw = load_config().to_dict()
    raw["clearances"]["lateral_opening_m_per_pa"] = -1e-12
    with pytest.raises(InputError, match=r"clearances.lateral_opening_m_per_pa.*\[0, 1e-09\] m/Pa"):
        parse_config(raw)
    raw["clearances"]["lateral_opening_m_per_pa"] = 3e-11
    assert parse_config(parse_config(raw).to_dict()).clearances.lateral_opening_m_per_pa == 3e-11
    del raw["clearances"]["lateral_opening_m_per_pa"]
    assert parse_config(raw).clearances.lateral_opening_m_per_pa == 0.0


#: a map of the default pump whose lateral gaps open by 3 µm per bar: two speeds, four pressures, 50 °C
TRUE_OPENING = 3e-11
MAP_POINTS = [(rpm * math.pi / 30, 101325.0 + bar * 1e5, 50.0) for rpm in (1200, 2600) for bar in (3, 10, 17, 25)]


@pytest.fixture(scope="module")
def opening_map():
    from gerotor_twin.calibration.map_synth import synthetic_map
    raw = load_config().to_dict()
    raw["clearances"]["lateral_opening_m_per_pa"] = TRUE_OPENING
    return synthetic_map(raw, MAP_POINTS, source="opening.csv")


def test_map_fit_recovers_the_opening(opening_map):
    """Closed form (synthetic truth, the twin's own model): fitting the opening to the map recovers 3e-11 m/Pa
    inside its 95 % interval with the efficiency error below 0.05 pt; the rigid gaps' common factor cannot
    make the Δp(1 + cΔp/s₀)³ of the loaded gap (error above 1 pt)."""
    from gerotor_twin.calibration.command import calibrate_records
    res = calibrate_records(opening_map, ["opening.csv"], params=("lateral_opening",), holdout=0, jobs=1)["fit"]
    op = res["parameters"][0]
    assert op["identifiable"] and op["ci95"][0] <= TRUE_OPENING <= op["ci95"][1]
    assert res["eta_error"]["max_abs"] < 5e-4
    rigid = calibrate_records(opening_map, ["opening.csv"], params=("tip", "lateral"), holdout=0, jobs=1)["fit"]
    assert rigid["eta_error"]["max_abs"] > 0.01


def test_bench_pump_emulates_the_opening():
    """Behaviour: a bench pump file's ``clearances.lateral_opening_m_per_pa`` reaches the emulated pump: the flow
    it loses against the rigid bench pump grows faster than Δp (leakage ∝ Δp[(1 + cΔp/s₀)³ − 1] ≈ 3cΔp²/s₀:
    25 times more at 25 bar than at 5 bar for a small opening; asked: more than 10 times), and the resolved
    description records the value."""
    from gerotor_twin.bench_emulator.bench_pump import parse_bench_pump
    from gerotor_twin.calibration.bench_steady import SteadyBench
    rigid = SteadyBench.of(parse_bench_pump({}))
    opened = SteadyBench.of(parse_bench_pump({"pump": {"clearances": {"lateral_opening_m_per_pa": 5e-12}}}))
    p_atm, omega = rigid.p_atm_pa, 1500 * math.pi / 30
    lost = [rigid.true_flow(omega, p_atm + bar * 1e5, 50.0) - opened.true_flow(omega, p_atm + bar * 1e5, 50.0)
            for bar in (5, 25)]
    assert lost[0] > 0 and lost[1] > 10 * lost[0]
    assert opened.bench_pump.resolved(load_config(), opened.spec).lateral_opening == 5e-12


def test_display_value():
    """Closed form: an opening of 5.07e-12 m/Pa is shown as 0.507 µm/bar (1 µm/bar = 1e-11 m/Pa), a clearance of
    34.506e-6 m as 34.506 µm, a unitless factor with four decimals."""
    from gerotor_twin.calibration.fit_model import display_value
    assert display_value(5.07e-12, "m/Pa") == "0.507 µm/bar"
    assert display_value(34.506e-6, "m") == "34.506 µm"
    assert display_value(0.96, "-") == "0.9600"
