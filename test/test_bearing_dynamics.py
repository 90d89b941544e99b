"""Dynamic loads, load through zero, metal contact — CLOSED-FORM / LITERATURE tests.

* Synchronously rotating load (Booker's "omega_bar" principle): seen from the
  load, the film has the effective speed omega - 2 omega_load, so the orbit
  radius is Ocvirk's eps for |omega - 2 omega_load| and the centre lags or
  leads the load by the Ocvirk attitude angle (closed form, Ocvirk 1952 /
  Booker 1965).  Method 1 must match to integration accuracy; the mobility
  method within its fit accuracy (1 %, 1 deg as for a steady load).
* Mobility vs Method 1 on a rotating load of varying magnitude: the two are
  the same short pi-film bearing, the mobility being Booker's closed-form fit
  of it (load error up to ~11 % at eps = 0.9, see test_bearing_short.py); the
  trajectories must stay within 3 % of the clearance of each other.
* No NaN when the load passes through zero; contact never gives eps >= 1 and
  is reported as ContactEvent.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from gerotor_twin.bearing import EPS_CONTACT, TABLE1, ContactEvent, make_bearing, simulate
from gerotor_twin.bearing.closed_form import ocvirk_attitude_angle, ocvirk_eccentricity

OMEGA = 500 * 2 * math.pi / 60
C = TABLE1.clearance_m
E0 = C * np.array([0.0997, 0.0071])
FAST_FDM = {"nx": 64, "ny": 9}


def _rotating(magnitude, omega_load):
    def load(t):
        t = np.asarray(t, dtype=float)
        return magnitude * np.stack([np.cos(omega_load * t), np.sin(omega_load * t)], axis=-1)
    return load


@pytest.mark.parametrize("method,eps_rtol,att_tol", [("short", 1e-5, 1e-3),
                                                      ("mobility", 0.01, 1.0)])
@pytest.mark.parametrize("omega_load", [OMEGA, -OMEGA / 2, 2 * OMEGA])
def test_synchronous_rotating_load(method, eps_rtol, att_tol, omega_load):
    load_n = 1500.0
    traj = simulate(make_bearing(method, TABLE1), E0, _rotating(load_n, omega_load), OMEGA,
                    2e-5, 0.5)
    w_eff = OMEGA - 2 * omega_load
    eps_ref = ocvirk_eccentricity(load_n, TABLE1, w_eff)
    att_ref = math.degrees(ocvirk_attitude_angle(eps_ref)) * math.copysign(1.0, w_eff)
    tail = slice(-2000, None)
    eps = traj.eccentricity_ratio[tail]
    rel = np.arctan2(traj.e[tail, 1], traj.e[tail, 0]) - omega_load * traj.t[tail]
    att = np.degrees((rel + math.pi) % (2 * math.pi) - math.pi)
    assert np.all(np.abs(eps / eps_ref - 1) < eps_rtol)
    assert np.all(np.abs(att - att_ref) < att_tol)


def test_mobility_vs_method1_rotating_varying_load():
    def load(t):
        t = np.asarray(t, dtype=float)
        mag = 1200.0 + 800.0 * np.sin(3 * OMEGA * t)
        ang = -math.pi / 2 + 0.6 * OMEGA * t
        return np.stack([mag * np.cos(ang), mag * np.sin(ang)], axis=-1)

    period = 2 * math.pi / OMEGA
    tr = {m: simulate(make_bearing(m, TABLE1), E0, load, OMEGA, 1e-4, 3 * period)
          for m in ("mobility", "short")}
    d = np.hypot(*(tr["mobility"].e - tr["short"].e).T) / C
    print(f"\nmobility vs Method 1, rotating load: max |de| = {d.max():.4f} c")
    assert d.max() < 0.03
    assert max(t.eccentricity_ratio.max() for t in tr.values()) > 0.6  # a demanding orbit


@pytest.mark.parametrize("method", ["mobility", "short", "fdm", "fixed"])
def test_load_through_zero_no_nan(method):
    opts = FAST_FDM if method == "fdm" else {}

    def load(t):  # magnitude crosses zero 10 times/s, direction also turns
        t = np.asarray(t, dtype=float)
        mag = 1500.0 * np.cos(2 * math.pi * 5 * t)
        return np.stack([mag * np.cos(OMEGA * t / 3), mag * np.sin(OMEGA * t / 3)], axis=-1)

    traj = simulate(make_bearing(method, TABLE1, **opts), E0, load, OMEGA, 1e-4, 0.3)
    assert np.all(np.isfinite(traj.e)) and np.all(np.isfinite(traj.e_dot))
    assert np.all(traj.eccentricity_ratio < 1.0)
    # exactly zero load at t = 0.05 s (a sample): the film carries nothing
    model = make_bearing(method, TABLE1, **opts)
    v = model.velocity(traj.e[500], [0.0, 0.0], OMEGA)
    assert np.all(np.isfinite(v))


@pytest.mark.parametrize("method", ["mobility", "short", "fdm"])
@pytest.mark.parametrize("omega", [0.0, OMEGA])
def test_contact_is_clamped_and_reported(method, omega):
    opts = FAST_FDM if method == "fdm" else {}
    load = [0.0, -1e6]  # Ocvirk needs eps > 0.99 at 500 rpm; squeeze runs into the wall
    traj = simulate(make_bearing(method, TABLE1, **opts), [0.0, 0.0], load, omega, 1e-4, 0.2)
    eps = traj.eccentricity_ratio
    assert np.all(np.isfinite(traj.e))
    assert eps.max() <= EPS_CONTACT * (1 + 1e-12)
    assert traj.contact and len(traj.events) >= 1
    ev = traj.events[0]
    assert isinstance(ev, ContactEvent)
    assert 0.0 < ev.t_start <= ev.t_end <= traj.t[-1]
    assert ev.eps_limit == EPS_CONTACT and ev.max_contact_force_n > 0
    assert "metal contact" in str(ev)
    # in contact the journal does not move outwards
    k = np.flatnonzero(eps >= EPS_CONTACT * (1 - 1e-12))
    radial = np.sum(traj.e[k] * traj.e_dot[k], axis=1)
    assert np.all(radial <= 1e-12 * C * C * max(OMEGA, 1.0))
    assert np.all(np.isfinite(traj.contact_force))


def test_custom_contact_limit_and_no_contact_flag():
    traj = simulate(make_bearing("mobility", TABLE1), E0, [0.0, -1000.0], OMEGA, 1e-4, 0.2,
                    eps_max=0.8)
    assert traj.contact and traj.eccentricity_ratio.max() <= 0.8 + 1e-12
    ok = simulate(make_bearing("mobility", TABLE1), E0, [0.0, -1000.0], OMEGA, 1e-4, 0.2)
    assert not ok.contact and ok.events == ()


def test_fixed_model_does_not_move():
    traj = simulate(make_bearing("fixed", TABLE1), E0, _rotating(900.0, OMEGA), OMEGA, 1e-4, 0.05)
    assert np.all(traj.e == E0) and np.all(traj.e_dot == 0)
    np.testing.assert_allclose(traj.film_force, -traj.load)
    np.testing.assert_allclose(traj.min_film_thickness, C - math.hypot(*E0))


def test_scalar_and_vectorised_load_functions_agree():
    vec = _rotating(700.0, OMEGA)
    scalar = lambda t: [700.0 * math.cos(OMEGA * t), 700.0 * math.sin(OMEGA * t)]  # noqa: E731
    model = make_bearing("mobility", TABLE1)
    a = simulate(model, E0, vec, OMEGA, 1e-4, 0.01)
    b = simulate(model, E0, scalar, OMEGA, 1e-4, 0.01)
    np.testing.assert_array_equal(a.e, b.e)
    assert a.t[-1] == pytest.approx(0.01) and len(a.t) == 101


@pytest.mark.parametrize("method", ["mobility", "short"])
def test_rk4_is_fourth_order(method):
    """Step halving near the equilibrium orbit of a slowly rotating load: the
    end-point differences fall 16x per halving.  (From the centre, the first
    milliseconds are a fast transient, ~2000 1/s, too stiff for a clean order.)"""
    from gerotor_twin.bearing.closed_form import ocvirk_equilibrium
    model = make_bearing(method, TABLE1)
    e0 = 0.9 * ocvirk_equilibrium([1500.0, 0.0], TABLE1, OMEGA)
    load = _rotating(1500.0, 0.3 * OMEGA)
    ends = [simulate(model, e0, load, OMEGA, dt, 0.04).e[-1] for dt in (8e-4, 4e-4, 2e-4, 1e-4)]
    d = [np.linalg.norm(a - b) for a, b in zip(ends, ends[1:])]
    for a, b in zip(d, d[1:]):
        assert 14.0 < a / b < 18.0
