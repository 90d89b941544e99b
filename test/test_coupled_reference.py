"""The independent reference for the gear on its teeth (model/coupled_reference.py): pressures and gear position
integrated together by Radau IIA, the contact as a relaxed complementarity problem.

Tiers: CLOSED FORM (its right-hand side: the mobility velocity itself where no gap closes; where one would, the
gap's rate is held at −g/τ and never below, checked by finite differences of the gap tables) and BEHAVIOUR (from
one periodic state of the new-pump-clearance pump 07, the twin with ``gear_coupling: constrained`` follows the
reference over 20 output steps, the unconstrained ``stages`` scheme does not; the revolutions of the reference
chain their shaft angles; where two lobes touch, its right-hand side is continuous).  The full revolution against the
reference is a benchmark (docs/numerics.md, "The tooth contact as a constraint"), not a test: ≈ 10 min.
"""
import math
from dataclasses import replace

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from gerotor_twin.bearing.mobility import mobility_kernel
from gerotor_twin.config import load_config
from gerotor_twin.model import coupled_reference as CR
from gerotor_twin.model import kernel as K
from gerotor_twin.model.contact import contact, gap_coefficients, gap_value
from gerotor_twin.model.family import family_dir
from gerotor_twin.model.loads import outer_gear_load
from gerotor_twin.model.params import operating
from gerotor_twin.model.pump import Inputs, PumpModel
from gerotor_twin.model.steady import run_steady
from gerotor_twin.model.tooth_constraint import gap_normal, two_smallest

RPM, BAR = 1650.0, 27.5


def _with(cfg, scheme):
    return replace(cfg, numerics=replace(cfg.numerics, gear_coupling=scheme))


@pytest.fixture(scope="module")
def setup():
    """07 (tip 10 µm) at 1650 rpm / 27.5 bar: the constrained twin's periodic state, and the reference's pieces."""
    cfg = load_config(family_dir() / "07_default_gear_set_new.yaml")
    twin = PumpModel(_with(cfg, "constrained"), "mobility")
    state = run_steady(twin, RPM, BAR, max_revolutions=40, rtol=1e-6).state
    m = PumpModel(cfg, "mobility")
    inp = Inputs(RPM * math.pi / 30, cfg.boundary.suction_pressure_pa, cfg.fluid.atmospheric_pa + BAR * 1e5)
    op = operating(m.kernel, inp.omega, inp.p_suction, inp.p_delivery)
    tau = math.radians(CR.RELAXATION_DEG) / inp.omega
    return cfg, m, inp, op, tau, state


def _rhs(m, op, tau, state, e, t=0.0):
    z = np.concatenate([state.log_density, e])
    z[m.N] = 0.0
    out = np.empty(m.N + 3)
    CR.coupled_rhs(t, z, state.theta, tau, m.kernel, op, m._ws, out, True)   # the types of CR._system's calls
    return z, out


def _free_velocity(m, op, state, e):
    """M(e, F) of sec. 2.2 under the load of Eqs. (24)-(27) at the state's pressures."""
    km, pc = m.kernel, m.kernel.pc
    h, cmat = np.empty(m.N), np.empty((m.N, 9))
    _x, _y, _g, kc = contact(km.tab, m.N, pc.tip_clearance, state.theta, e[0], e[1], h, cmat)
    pres = np.empty(m.N + 1)
    K.to_pressures(state.log_density, km, pres)
    fx, fy, _c, _u = outer_gear_load(pres, state.theta, op.omega, e[0], e[1], kc, km)
    bp = (pc.housing_clearance, pc.width, 2.0 * pc.journal_radius, pc.viscosity)
    return np.array(mobility_kernel(e[0], e[1], fx, fy, op.omega * (m.N - 1) / m.N, bp))


def _gap(m, theta, e, k):
    c = np.empty(9)
    gap_coefficients(m.kernel.tab, theta, k, c)
    return gap_value(c, m.kernel.pc.tip_clearance, e[0], e[1], 0.0)


def test_off_the_teeth_the_gear_moves_with_the_mobility(setup):
    """Closed form: at the housing's centre every tip gap is δ, far from closing within τ: ė = M(e, F) exactly."""
    _cfg, m, _inp, op, tau, state = setup
    e = np.zeros(2)
    _z, out = _rhs(m, op, tau, state, e)
    assert np.array_equal(out[m.N + 1:], _free_velocity(m, op, state, e))


def test_on_the_teeth_a_closing_gap_is_held_and_none_penetrates(setup):
    """Closed form: at the periodic state the gear is on the teeth and its free velocity closes the nearest gap
    faster than g/τ; with the reaction the gap's rate dg/dt = n·ė + ∂g/∂θ ω (finite differences of the tables
    along the motion) is −g/τ for that lobe and ≥ −g/τ for every lobe."""
    _cfg, m, _inp, op, tau, state = setup
    e = state.eccentricity
    _z, out = _rhs(m, op, tau, state, e)
    v, v_free = out[m.N + 1:], _free_velocity(m, op, state, e)
    dt = 1e-9
    gaps = np.array([_gap(m, state.theta, e, k) for k in range(m.N)])
    rate = np.array([(_gap(m, state.theta + op.omega * dt, e + v * dt, k) - gaps[k]) / dt for k in range(m.N)])
    rate_free = np.array([(_gap(m, state.theta + op.omega * dt, e + v_free * dt, k) - gaps[k]) / dt
                          for k in range(m.N)])
    k = int(np.argmin(gaps))
    assert rate_free[k] < -gaps[k] / tau - 1e-4                     # the free motion would run into lobe k
    assert rate[k] == pytest.approx(-gaps[k] / tau, abs=1e-5)        # held [m/s]
    assert np.all(rate >= -gaps / tau - 1e-5)


def test_the_constrained_twin_follows_the_coupled_reference(setup):
    """Behaviour: from the same periodic state, over 20 output steps (30°), the twin with the tooth constraint stays
    within 0.5 µm and 2 bar of the reference that integrates pressures and gear position together; the stages'
    scheme (free velocity in the step, pull-back after it) leaves it by microns and tens of bar (measured
    2026-12-04: 0.135 µm / 0.57 bar against 1.7 µm / 23.9 bar)."""
    cfg, m, inp, op, tau, state = setup
    h = m.step_size(inp.omega)
    z, _out = _rhs(m, op, tau, state, state.eccentricity)
    f, _atol = CR._system(m, op, state.theta, tau)
    atol = np.full(m.N + 3, 1e-9)
    atol[m.N + 1:] = 1e-11
    ts = h * np.arange(1, 21)
    # as in coupled_revolution: scipy's num_jac multiplies the increment of the delivered volume, on which f does not
    # depend, by 10 at every Jacobian, without a bound; past ≈ 300 Jacobians it overflows (its column stays zero)
    with np.errstate(over="ignore"):
        ref = solve_ivp(f, (0.0, ts[-1]), z, method="Radau", rtol=1e-7, atol=atol, t_eval=ts).y
    p_ref = np.empty((ts.size, m.N + 1))
    for i in range(ts.size):
        K.to_pressures(ref[:m.N + 1, i], m.kernel, p_ref[i])
    err = {}
    for scheme in ("constrained", "stages"):
        _s, o = PumpModel(_with(cfg, scheme), "mobility").advance(state, ts[-1], inp)
        err[scheme] = (np.hypot(*(o.eccentricity - ref[m.N + 1:].T).T).max(),
                       np.abs(o.chamber_pressures - p_ref[:, :m.N]).max())
    assert err["constrained"][0] < 0.5e-6 and err["constrained"][1] < 2e5, err
    assert err["stages"][0] > 1e-6 and err["stages"][1] > 10e5, err


def test_each_revolution_of_the_reference_starts_where_the_last_ended(setup, monkeypatch):
    """Closed form: a chamber's tables repeat with the chamber period 2πN/(N − 1), not with 2π, so the settling
    revolutions and the recorded one must run at θ₀ + 2πk, k = 0, 1, …: with the right-hand side stubbed (ż = 0,
    the angles it is called at recorded) the calls cover [θ₀, θ₀ + 2π·revolutions] once, and the recorded
    revolution's samples are at θ₀ + 2π(revolutions − 1) + ωh·(1, 2, …).  (A revolution restarted at θ₀ puts
    every chamber one position off: on 07 at 1650 rpm / 27.5 bar its first samples then differ from the twin's
    by 16 bar, its RMS against the twin 1.13 % of the range instead of 0.25 %, measured 2026-12-06.)"""
    _cfg, m, inp, op, _tau, state = setup
    seen = []

    def stub(t, z, theta0, tau, km, op_, ws, out, full=True):
        seen.append(theta0 + op_.omega * t)
        out[:] = 0.0
    monkeypatch.setattr(CR, "coupled_rhs", stub)
    revolutions = 3
    rev, _e = CR.coupled_revolution(m, RPM, BAR, state, revolutions=revolutions)
    two_pi = 2.0 * math.pi
    assert min(seen) == pytest.approx(state.theta, abs=1e-9)
    assert max(seen) == pytest.approx(state.theta + revolutions * two_pi, abs=1e-9)
    h = m.step_size(inp.omega)
    expected = state.theta + (revolutions - 1) * two_pi + inp.omega * h * np.arange(1, rev["theta"].size + 1)
    np.testing.assert_allclose(rev["theta"], expected, rtol=0, atol=1e-9)


def _wedged(m, theta, e):
    """A position at which the two lobes nearest contact both touch (gaps 0), by Newton from e, and the lobes."""
    km = m.kernel
    cm = np.empty((m.N, 9))
    contact(km.tab, m.N, km.pc.tip_clearance, theta, e[0], e[1], np.empty(m.N), cm)
    k1, k2, _g1, _g2 = two_smallest(cm, km.pc.tip_clearance, e[0], e[1])
    e = np.array(e, dtype=float)
    for _ in range(30):
        g = np.array([gap_value(cm[k], km.pc.tip_clearance, e[0], e[1], 0.0) for k in (k1, k2)])
        jac = np.array([gap_normal(cm[k], e[0], e[1]) for k in (k1, k2)])
        e -= np.linalg.solve(jac, g)
    return e, k1, k2


def test_two_lobes_at_contact_share_the_contact_force(setup):
    """Closed form: the load of Eq. (26) with the gear wedged between two lobes (both gaps 0) is the mean of the two
    lobes' loads; with one lobe ε = HANDOVER_M open, the nearer lobe's alone; far from contact, the smallest gap's
    lobe's (``kc``, as in the twin)."""
    _cfg, m, _inp, op, _tau, state = setup
    km = m.kernel
    pres = np.empty(m.N + 1)
    K.to_pressures(state.log_density, km, pres)
    ex, ey = state.eccentricity

    def load(k):
        return np.array(outer_gear_load(pres, state.theta, op.omega, ex, ey, k, km)[:2])
    k1, k2 = 1, 2
    both = np.array(CR._handover_load(pres, state.theta, op.omega, ex, ey, 0, k1, k2, 0.0, 0.0, km))
    np.testing.assert_allclose(both, 0.5 * (load(k1) + load(k2)), rtol=1e-12)
    eps = CR.HANDOVER_M
    one = np.array(CR._handover_load(pres, state.theta, op.omega, ex, ey, 0, k1, k2, 0.0, eps, km))
    np.testing.assert_allclose(one, load(k1), rtol=1e-12)
    far = np.array(CR._handover_load(pres, state.theta, op.omega, ex, ey, 3, k1, k2, 2 * eps, 3 * eps, km))
    np.testing.assert_allclose(far, load(3), rtol=1e-12)
    assert np.abs(load(k1) - load(k2)).max() > 1.0          # the lobes' loads differ [N]: the mean is a choice


def test_the_reference_is_continuous_where_the_gear_is_wedged(setup):
    """Behaviour: at a position where two lobes touch, moves of 1e-15 m (round-off) change ė by less than 1 µm/s.
    With the contact force on whichever lobe round-off makes the smaller gap they change it by millimetres per
    second (6 mm/s here), and Radau stalls at such a wedge (07 at 1650 rpm / 27.5 bar, 237°, measured 2026-12-06)."""
    _cfg, m, _inp, op, tau, state = setup
    e, _k1, _k2 = _wedged(m, state.theta, state.eccentricity)
    _z, base = _rhs(m, op, tau, state, e)
    base = base.copy()
    rng = np.random.default_rng(0)
    for _ in range(8):
        _z, out = _rhs(m, op, tau, state, e + rng.normal(0.0, 1e-15, 2))
        assert np.abs(out[m.N + 1:] - base[m.N + 1:]).max() < 1e-6

