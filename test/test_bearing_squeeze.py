"""Pure squeeze (omega = 0, constant load) — CLOSED-FORM / LITERATURE tests.

Reference: the short pi-film squeeze bearing, W = (mu R L^3 / c^3) I(eps) de/dt,
I(eps) = [(1 + 2 eps^2)(pi/2 + asin eps) + 3 eps sqrt(1 - eps^2)] / (1 - eps^2)^{5/2}
(half of the film, the converging side, carries load; cf. Hamrock, Fundamentals
of Fluid Film Lubrication, squeeze-film journal bearing; I is checked against
quadrature in test_bearing_closed_form.py).  Time to approach:
t(eps) = (mu R L^3 / (W c^2)) int_0^eps I(s) ds, integrated here by scipy quad.

* Method 1 is exact (short-bearing theory): round-off agreement.
* Mobility: Booker's closed-form mobility (Eq. (9)) is a fit of the same
  film; along the load line it gives W = pi mu R L^3 de/dt / (2 c^3 (1-eps)^{5/2}),
  within 0.5 % (eps = 0.1), 2.5 % (0.5), 5 % (0.9) of the exact value: a 6 %
  tolerance is the fit's accuracy, not slack.
* FDM: approaches the short-bearing value as L/D -> 0.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from gerotor_twin.bearing import TABLE1, make_bearing, simulate
from gerotor_twin.bearing.closed_form import squeeze_approach_speed, squeeze_load_factor

C = TABLE1.clearance_m


@pytest.mark.parametrize("eps", [0.0, 0.1, 0.5, 0.9])
@pytest.mark.parametrize("angle_deg", [-90.0, 20.0])
def test_squeeze_speed_short_and_mobility(eps, angle_deg):
    a = math.radians(angle_deg)
    u = np.array([math.cos(a), math.sin(a)])
    load_n = 700.0
    ref = squeeze_approach_speed(eps, load_n, TABLE1)
    for method, rtol in (("short", 1e-9), ("mobility", 0.06)):
        v = make_bearing(method, TABLE1).velocity(eps * C * u, load_n * u, 0.0)
        # moves straight towards the load
        assert abs(u[0] * v[1] - u[1] * v[0]) <= 1e-9 * np.linalg.norm(v)
        assert float(v @ u) == pytest.approx(ref, rel=rtol), method


def test_mobility_squeeze_formula_along_load():
    """Eq. (9) along the load: W = pi mu R L^3 de/dt / (2 c^3 (1 - eps)^{5/2})."""
    g = TABLE1
    for eps in (0.0, 0.3, 0.8):
        v = make_bearing("mobility", g).velocity([0.0, -eps * C], [0.0, -500.0], 0.0)
        fit = 500.0 * 2 * C ** 3 * (1 - eps) ** 2.5 / (math.pi * g.viscosity_pa_s * g.radius_m
                                                       * g.length_m ** 3)
        assert -v[1] == pytest.approx(fit, rel=1e-12)


@pytest.mark.parametrize("method,rtol", [("short", 1e-6), ("mobility", 0.06)])
def test_squeeze_approach_time(method, rtol):
    """Time-marched from e = 0: time to reach eps = 0.5 vs the integral of 1/speed."""
    g, load_n = TABLE1, 2.0
    scale = g.viscosity_pa_s * g.radius_m * g.length_m ** 3 / (load_n * C ** 2)
    t_ref = scale * quad(squeeze_load_factor, 0.0, 0.5, epsabs=0, epsrel=1e-12)[0]
    traj = simulate(make_bearing(method, g), [0.0, 0.0], [0.0, -load_n], 0.0, 1e-4,
                    1.6 * t_ref)
    eps = traj.eccentricity_ratio
    k = int(np.searchsorted(eps, 0.5))
    # linear interpolation of the crossing time
    frac = (0.5 - eps[k - 1]) / (eps[k] - eps[k - 1])
    t_cross = traj.t[k - 1] + frac * (traj.t[k] - traj.t[k - 1])
    assert t_cross == pytest.approx(t_ref, rel=rtol)
    assert np.all(np.abs(traj.e[:, 0]) < 1e-12 * C)  # straight down the load line


def test_fdm_squeeze_converges_to_short_bearing():
    errs = []
    for ld in (0.4, 0.2, 0.1, 0.05):
        g = TABLE1.with_length(ld * TABLE1.diameter_m)
        v = make_bearing("fdm", g, nx=320, ny=40).velocity([0.0, -0.5 * C], [0.0, -300.0], 0.0)
        errs.append(-v[1] / squeeze_approach_speed(0.5, 300.0, g) - 1.0)
    # the circumferential Poiseuille flow that the short theory drops relieves the film:
    # the finite bearing approaches faster, the excess falling ~ (L/D)^2
    assert all(e > 0 for e in errs)
    assert all(b < a / 2.5 for a, b in zip(errs, errs[1:]))
    assert errs[-1] < 0.005
