"""Tests of gerotor_twin.bearing.closed_form — CLOSED-FORM / LITERATURE tests.

The analytic short-bearing formulas are checked against independent numbers:
adaptive quadrature (scipy.integrate.quad) of the pi-film integrands written
out here, Ocvirk's classical load and attitude-angle formulas (Ocvirk 1952,
Hamrock "Fundamentals of Fluid Film Lubrication" ch. on short bearings), and
the known full-film squeeze integral pi (1 + 2 eps^2) / (1 - eps^2)^{5/2}.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from gerotor_twin.bearing import closed_form as cf
from gerotor_twin.bearing.geometry import TABLE1

OMEGA = 500 * 2 * math.pi / 60


def _quad(fun, a, b):
    # split at the film minimum (alpha = 0 mod 2 pi), where the integrands peak
    peaks = [2 * math.pi * k for k in range(math.ceil(a / (2 * math.pi)),
                                             math.floor(b / (2 * math.pi)) + 1)
             if a < 2 * math.pi * k < b]
    edges = [a, *peaks, b]
    return sum(quad(fun, lo, hi, limit=400, epsabs=1e-12, epsrel=1e-11)[0]
               for lo, hi in zip(edges, edges[1:]))


@pytest.mark.parametrize("eps,a,width", [(0.0, -1.0, math.pi), (0.3, 2.5, math.pi),
                                         (0.6, -4.0, 2.0), (0.9, 0.7, math.pi),
                                         (0.97, -3.0, 5.5), (0.5, 6.0, 2 * math.pi)])
def test_pi_film_integrals_match_quadrature(eps, a, width):
    b = a + width
    got = cf.pi_film_integrals(eps, a, b)
    den = lambda t: (1 - eps * math.cos(t)) ** 3  # noqa: E731
    ref = [_quad(lambda t: math.cos(t) ** 2 / den(t), a, b),
           _quad(lambda t: math.sin(t) * math.cos(t) / den(t), a, b),
           _quad(lambda t: math.sin(t) ** 2 / den(t), a, b)]
    np.testing.assert_allclose(got, ref, rtol=1e-9, atol=1e-9 * max(abs(r) for r in ref))


@pytest.mark.parametrize("eps", [0.05, 0.3, 0.6, 0.9, 0.99])
def test_steady_force_is_ocvirk(eps):
    """pi-film force with e_dot = 0 equals Ocvirk's W_r, W_t (written out here)."""
    g = TABLE1
    s = g.viscosity_pa_s * OMEGA * g.radius_m * g.length_m ** 3 / g.clearance_m ** 2
    wr = s * eps ** 2 / (1 - eps ** 2) ** 2
    wt = s * math.pi * eps / (4 * (1 - eps ** 2) ** 1.5)
    f = cf.short_bearing_force([eps * g.clearance_m, 0.0], [0.0, 0.0], OMEGA, g)
    # film force on the journal: towards the centre along e, +90 deg across (omega > 0)
    np.testing.assert_allclose(f, [-wr, wt], rtol=1e-12)
    assert cf.ocvirk_load_components(eps, g, OMEGA) == pytest.approx((wr, wt), rel=1e-12)
    assert cf.ocvirk_load(eps, g, OMEGA) == pytest.approx(math.hypot(wr, wt), rel=1e-12)
    assert math.tan(cf.ocvirk_attitude_angle(eps)) == pytest.approx(
        math.pi * math.sqrt(1 - eps ** 2) / (4 * eps), rel=1e-12)


@pytest.mark.parametrize("load", [1.0, 200.0, 1000.0, 5000.0, 1e5])
def test_ocvirk_eccentricity_inverts_load(load):
    eps = cf.ocvirk_eccentricity(load, TABLE1, OMEGA)
    assert 0 < eps < 1
    assert cf.ocvirk_load(eps, TABLE1, OMEGA) == pytest.approx(load, rel=1e-10)


def test_equilibrium_rotated_from_load_in_sense_of_rotation():
    """e = load direction rotated by +phi for omega > 0, by -phi for omega < 0."""
    load = np.array([0.0, -1000.0])
    e_pos = cf.ocvirk_equilibrium(load, TABLE1, OMEGA)
    e_neg = cf.ocvirk_equilibrium(load, TABLE1, -OMEGA)
    eps = cf.ocvirk_eccentricity(1000.0, TABLE1, OMEGA)
    phi = cf.ocvirk_attitude_angle(eps)
    assert math.atan2(e_pos[1], e_pos[0]) == pytest.approx(-math.pi / 2 + phi, abs=1e-12)
    assert math.atan2(e_neg[1], e_neg[0]) == pytest.approx(-math.pi / 2 - phi, abs=1e-12)
    # and the film force there balances the load (closed form against closed form)
    f = cf.short_bearing_force(e_pos, [0.0, 0.0], OMEGA, TABLE1)
    np.testing.assert_allclose(f, -load, rtol=1e-9, atol=1e-9 * 1000)


@pytest.mark.parametrize("eps", [0.0, 0.2, 0.5, 0.9, 0.99])
def test_squeeze_factor(eps):
    half = _quad(lambda t: math.cos(t) ** 2 / (1 - eps * math.cos(t)) ** 3, -math.pi / 2,
                 math.pi / 2)
    assert cf.squeeze_load_factor(eps) == pytest.approx(half, rel=1e-10)
    # full film (Hamrock): pi (1 + 2 eps^2) / (1 - eps^2)^{5/2}; the half film carries
    # more than half of it (the loaded half is the converging one)
    full = math.pi * (1 + 2 * eps ** 2) / (1 - eps ** 2) ** 2.5
    both = cf.pi_film_integrals(eps, -math.pi, math.pi)[0]
    assert both == pytest.approx(full, rel=1e-12)
    assert 0.5 * full <= cf.squeeze_load_factor(eps) + 1e-12


def test_squeeze_force_matches_speed():
    g = TABLE1
    eps, load = 0.4, 800.0
    v = cf.squeeze_approach_speed(eps, load, g)
    f = cf.short_bearing_force([0.0, -eps * g.clearance_m], [0.0, -v], 0.0, g)
    np.testing.assert_allclose(f, [0.0, load], rtol=1e-12, atol=1e-9)
