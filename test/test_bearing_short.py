"""Method 1 (short bearing) and the mobility method — CLOSED-FORM tests.

References, all independent of the code under test:
* the analytic pi-film force (closed_form.short_bearing_force: Booker-type
  integrals in closed form, checked against quadrature elsewhere);
* a brute-force trapezoidal integration, written here, of the paper's
  Eq. (4) pressure (evaluated by ``short_bearing.pressure`` in its polar form)
  over theta and z, keeping positive values only (Eq. (5));
* for the mobility method: the velocity it returns must make the exact
  short pi-film force balance the load, up to the accuracy of Booker's
  closed-form fit (Eq. (9) corrected): the mobility's derivation assumes the
  same cavitated (pi-film) short bearing.  Fit accuracy, measured over random
  states: |F| within 1.5 % (eps < 0.3), 3.5 % (< 0.5), 6.5 % (< 0.7), 11 % (< 0.9),
  13 % (< 0.95); direction within 0.3 - 2.7 deg.
"""
from __future__ import annotations

import math

import numba
import numpy as np
import pytest

from gerotor_twin.bearing import TABLE1, make_bearing, mobility_velocity
from gerotor_twin.bearing.closed_form import short_bearing_force
from gerotor_twin.bearing.short_bearing import pressure

OMEGA = 500 * 2 * math.pi / 60
C = TABLE1.clearance_m


def _random_states(n, seed, eps_max=0.98):
    rng = np.random.default_rng(seed)
    for k in range(n):
        eps = rng.uniform(0.0, eps_max)
        a = rng.uniform(-math.pi, math.pi)
        e = eps * C * np.array([math.cos(a), math.sin(a)])
        e_dot = rng.normal(size=2) * 10.0 ** rng.uniform(-5, -2)
        omega = (OMEGA, 0.0, -OMEGA, 3 * OMEGA)[k % 4]
        yield e, e_dot, omega


def test_method1_force_matches_closed_form():
    model = make_bearing("short", TABLE1)
    for e, e_dot, omega in _random_states(300, 1):
        ref = short_bearing_force(e, e_dot, omega, TABLE1)
        got = model.film_force(e, e_dot, omega)
        np.testing.assert_allclose(got, ref, rtol=1e-10, atol=1e-10 * np.linalg.norm(ref))


@pytest.mark.parametrize("eps,phi,eps_dot,phi_dot", [
    (0.6, 0.3, 0.0, 0.0), (0.3, -2.0, 2.0, 5.0), (0.8, 1.0, -1.5, 40.0), (0.0, 0.0, 1.0, 0.0)])
def test_method1_force_is_eq4_integrated(eps, phi, eps_dot, phi_dot):
    """Brute-force Eqs. (4)-(5): trapezoid over theta and z of max(p, 0)."""
    g = TABLE1
    theta = np.linspace(0.0, 2 * math.pi, 20001)[:-1]
    z = np.linspace(-g.length_m / 2, g.length_m / 2, 41)
    p = np.maximum(pressure(theta[:, None], z[None, :], eps, phi, eps_dot, phi_dot, OMEGA, g), 0)
    pz = np.trapezoid(p, z, axis=1)
    dth = theta[1] - theta[0]
    ref = -g.radius_m * dth * np.array([np.sum(pz * np.cos(theta)), np.sum(pz * np.sin(theta))])
    e = eps * C * np.array([math.cos(phi), math.sin(phi)])
    e_dot = C * (eps_dot * np.array([math.cos(phi), math.sin(phi)])
                 + eps * phi_dot * np.array([-math.sin(phi), math.cos(phi)]))
    got = make_bearing("short", g).film_force(e, e_dot, OMEGA)
    # z: the trapezoid of a parabola is off by (dz/L)^2 = 1/1600; theta grid is fine
    np.testing.assert_allclose(got, ref * (1 + 1 / 1600.0), rtol=2e-4,
                               atol=2e-4 * np.linalg.norm(ref))


def test_method1_velocity_balances_load():
    model = make_bearing("short", TABLE1)
    rng = np.random.default_rng(7)
    for e, _, omega in _random_states(300, 2, eps_max=0.99):
        load = rng.uniform(1.0, 2e4) * np.array([math.cos(a := rng.uniform(0, 7)), math.sin(a)])
        v = model.velocity(e, load, omega)
        f = short_bearing_force(e, v, omega, TABLE1)
        np.testing.assert_allclose(f, -load, atol=1e-9 * np.linalg.norm(load))


def test_short_load():
    """Closed form: ``short_load`` is Method 1 read the other way, the load under which the journal moves at ė is
    minus the analytic pi-film force at ė (1e-9), and its ∂ė/∂F is the central difference of Method 1's velocity
    (its Newton solve) in the load (1e-5 of |G|)."""
    from gerotor_twin.bearing.short_bearing import short_load
    model = make_bearing("short", TABLE1)
    for e, e_dot, omega in _random_states(200, 5, eps_max=0.95):
        got = np.array(short_load(e[0], e[1], e_dot[0], e_dot[1], omega, model.params))
        load = -short_bearing_force(e, e_dot, omega, TABLE1)
        np.testing.assert_allclose(got[:2], load, rtol=0.0, atol=1e-9 * np.linalg.norm(load))
        d = 1e-5 * np.linalg.norm(load)
        fd = np.column_stack([(model.velocity(e, load + d * u, omega) - model.velocity(e, load - d * u, omega)) / (2 * d)
                              for u in np.eye(2)])
        np.testing.assert_allclose(got[2:].reshape(2, 2), fd, rtol=0.0, atol=1e-5 * np.abs(fd).max())


def test_zero_load_gives_half_speed_whirl():
    """No load, no film force: the centre turns at omega/2 (v = 0)."""
    e = np.array([0.3 * C, -0.2 * C])
    expect = 0.5 * OMEGA * np.array([-e[1], e[0]])
    for name in ("mobility", "short"):
        np.testing.assert_allclose(make_bearing(name, TABLE1).velocity(e, [0.0, 0.0], OMEGA),
                                   expect, rtol=1e-14)


@pytest.mark.parametrize("eps_lo,eps_hi,mag_tol,ang_tol_deg", [
    (0.0, 0.3, 0.02, 0.5), (0.3, 0.5, 0.04, 1.0), (0.5, 0.7, 0.07, 2.0), (0.7, 0.9, 0.12, 3.0)])
def test_mobility_balances_pi_film_force(eps_lo, eps_hi, mag_tol, ang_tol_deg):
    """Independent check of the mobility sign/definition conventions."""
    model = make_bearing("mobility", TABLE1)
    rng = np.random.default_rng(11)
    for k in range(300):
        eps = rng.uniform(eps_lo, eps_hi)
        a = rng.uniform(-math.pi, math.pi)
        e = eps * C * np.array([math.cos(a), math.sin(a)])
        b = rng.uniform(-math.pi, math.pi)
        load = rng.uniform(10, 5000) * np.array([math.cos(b), math.sin(b)])
        omega = (OMEGA, 0.0, -OMEGA)[k % 3]
        v = model.velocity(e, load, omega)
        carried = -short_bearing_force(e, v, omega, TABLE1)
        assert np.linalg.norm(carried) / np.linalg.norm(load) == pytest.approx(1.0, abs=mag_tol)
        ang = math.degrees(math.atan2(load[0] * carried[1] - load[1] * carried[0], load @ carried))
        assert abs(ang) < ang_tol_deg


def test_mobility_film_force_is_inverse_of_velocity():
    model = make_bearing("mobility", TABLE1)
    rng = np.random.default_rng(3)
    for e, _, omega in _random_states(100, 4, eps_max=0.95):
        load = rng.uniform(1.0, 1e4) * np.array([math.cos(a := rng.uniform(0, 7)), math.sin(a)])
        v = model.velocity(e, load, omega)
        np.testing.assert_allclose(model.film_force(e, v, omega), -load,
                                   atol=1e-8 * np.linalg.norm(load))


def test_mobility_kernel_callable_from_numba():
    """The pump model's compiled loop calls the scalar kernel directly."""
    g = TABLE1
    c, length, diameter, mu = g.clearance_m, g.length_m, g.diameter_m, g.viscosity_pa_s

    @numba.njit
    def outer(n):
        ex, ey = 0.0, 0.0
        for _ in range(n):
            dx, dy = mobility_velocity(ex, ey, 0.0, -1000.0, 52.36, c, length, diameter, mu)
            ex += 1e-4 * dx
            ey += 1e-4 * dy
        return ex, ey

    ex, ey = outer(10)
    assert math.isfinite(ex) and ey < 0.0
    v = make_bearing("mobility", g).velocity([0.0, 0.0], [0.0, -1000.0], 52.36)
    assert v[1] < 0.0 and v[0] == pytest.approx(0.0, abs=1e-18)


def test_mobility_linearised():
    """Closed form: ``mobility_linearised`` returns the mobility's velocity bit for bit and G = ∂ė/∂F by the chain
    rule; G against central differences of ``mobility_velocity`` (step 1e-5 |F|, truncation ≈ 1e-9 relative)
    within 1e-6 of |G| over random states up to ε 0.98, loads of 1 N to 100 kN and both senses of rotation, and at
    zero load the forward difference of 1 N it documents."""
    from gerotor_twin.bearing.mobility import mobility_linearised
    g = TABLE1
    args = (g.clearance_m, g.length_m, g.diameter_m, g.viscosity_pa_s)
    rng = np.random.default_rng(5)
    for e, _, omega in _random_states(400, 6):
        b = rng.uniform(-math.pi, math.pi)
        f = 10.0 ** rng.uniform(0, 5) * np.array([math.cos(b), math.sin(b)])
        out = mobility_linearised(e[0], e[1], f[0], f[1], omega, *args)
        assert out[:2] == mobility_velocity(e[0], e[1], f[0], f[1], omega, *args)
        d = 1e-5 * np.linalg.norm(f)
        cols = []
        for step in (np.array([d, 0.0]), np.array([0.0, d])):
            hi = np.array(mobility_velocity(e[0], e[1], *(f + step), omega, *args))
            lo = np.array(mobility_velocity(e[0], e[1], *(f - step), omega, *args))
            cols.append((hi - lo) / (2 * d))
        want = np.column_stack(cols)
        np.testing.assert_allclose(np.reshape(out[2:], (2, 2)), want, atol=1e-6 * np.abs(want).max())
    e = np.array([0.3, -0.2]) * C
    v0 = np.array(mobility_velocity(e[0], e[1], 0.0, 0.0, OMEGA, *args))
    out = mobility_linearised(e[0], e[1], 0.0, 0.0, OMEGA, *args)
    for j, unit in enumerate(((1.0, 0.0), (0.0, 1.0))):
        col = np.array(mobility_velocity(e[0], e[1], *unit, OMEGA, *args)) - v0
        assert (out[2 + j], out[4 + j]) == tuple(col)
