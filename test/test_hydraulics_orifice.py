"""Tests of gerotor_twin.hydraulics.orifice — CLOSED-FORM tests.

References are the closed-form limits of Eq. (21) of [1] with the flow-number
law Cd = Cd_max·tanh(2λ/λ_crit): the turbulent limit Cd_max·A·√(2Δp/ρ), the
laminar limit Q = 2·a·Cd_max·A·Δp/ρ with a = 2D_h/(ν λ_crit), tanh(2) at
λ = λ_crit, odd symmetry; derivatives against central finite differences,
continuity at the small-argument series switch from both sides.
"""
from __future__ import annotations

import itertools
import math

import pytest

from gerotor_twin.hydraulics.orifice import (
    ORIFICE_SERIES_SWITCH,
    discharge_coefficient,
    orifice_flow,
)

RHO, MU = 870.0, 0.0391
CD, LC = 0.7, 1000.0
AREA = 1e-5


def a_coef(area=AREA, rho=RHO, mu=MU, lc=LC):
    d_h = math.sqrt(4 * area / math.pi)
    return 2 * d_h / ((mu / rho) * lc)


def dp_of_z(z, area=AREA):
    """Δp at which 2λ/λ_crit = z (v = z/a, Δp = ρ v²/2)."""
    v = z / a_coef(area)
    return 0.5 * RHO * v * v


def test_discharge_coefficient():
    assert discharge_coefficient(0.0, CD, LC) == 0.0
    assert discharge_coefficient(LC, CD, LC) == pytest.approx(CD * math.tanh(2.0), rel=1e-15)
    assert discharge_coefficient(1e3 * LC, CD, LC) == pytest.approx(CD, rel=1e-15)  # turbulent
    lam = 1e-3 * LC  # laminar: Cd ≈ 2 Cd_max λ/λ_crit
    assert discharge_coefficient(lam, CD, LC) == pytest.approx(2 * CD * lam / LC, rel=1e-5)
    assert discharge_coefficient(-LC, CD, LC) == discharge_coefficient(LC, CD, LC)
    assert discharge_coefficient(5.0, CD, 0.0) == CD  # λ_crit ≤ 0: always turbulent
    # monotone non-decreasing in λ and bounded by Cd_max
    vals = [discharge_coefficient(x, CD, LC) for x in (0, 1, 10, 100, 1e3, 1e4)]
    assert vals == sorted(vals) and max(vals) <= CD


def test_orifice_flow():
    a = a_coef()
    # turbulent limit (z ≈ 40): Cd → Cd_max
    dp = dp_of_z(40.0)
    q, dq = orifice_flow(dp, AREA, CD, LC, RHO, MU)
    assert q == pytest.approx(CD * AREA * math.sqrt(2 * dp / RHO), rel=1e-14)
    assert dq == pytest.approx(CD * AREA / (RHO * math.sqrt(2 * dp / RHO)), rel=1e-12)
    # laminar limit: Q = 2 a Cd_max A Δp/ρ, derivative equal at Δp = 0
    lam_slope = 2 * a * CD * AREA / RHO
    assert orifice_flow(0.0, AREA, CD, LC, RHO, MU) == (0.0, pytest.approx(lam_slope, rel=1e-15))
    for dp in (1e-12, 1e-8, dp_of_z(1e-5)):
        q, dq = orifice_flow(dp, AREA, CD, LC, RHO, MU)
        assert q == pytest.approx(lam_slope * dp, rel=1e-9)
        assert dq == pytest.approx(lam_slope, rel=1e-9)
    # Eq. (21) with Cd from discharge_coefficient at the flow number
    for dp in (1.0, 1e3, 1e5, 3e6):
        v = math.sqrt(2 * dp / RHO)
        lam = math.sqrt(4 * AREA / math.pi) * v / (MU / RHO)
        cd = CD * math.tanh(2 * lam / LC)
        q = orifice_flow(dp, AREA, CD, LC, RHO, MU)[0]
        assert q == pytest.approx(cd * AREA * v, rel=1e-14)
    # odd symmetry of Q, even derivative
    for dp in (1e-9, 0.3, 50.0, dp_of_z(ORIFICE_SERIES_SWITCH), 2e5, 3e7):
        qp, dqp = orifice_flow(dp, AREA, CD, LC, RHO, MU)
        qm, dqm = orifice_flow(-dp, AREA, CD, LC, RHO, MU)
        assert qm == -qp and dqm == dqp and qp > 0.0
    # derivative vs central finite differences, incl. Δp = 0
    f = lambda x: orifice_flow(x, AREA, CD, LC, RHO, MU)[0]  # noqa: E731
    for dp in (0.0, 1e-6, 0.01, 1.0, 30.0, 1e3, 1e5, 2.5e6):
        h = max(1e-4 * abs(dp), 1e-7)
        fd = (f(dp + h) - f(dp - h)) / (2 * h)
        assert orifice_flow(dp, AREA, CD, LC, RHO, MU)[1] == pytest.approx(fd, rel=1e-6)
    # continuity at the small-argument series switch (value and derivative)
    ps = dp_of_z(ORIFICE_SERIES_SWITCH)
    lo = orifice_flow(ps * (1 - 1e-9), AREA, CD, LC, RHO, MU)
    hi = orifice_flow(ps * (1 + 1e-9), AREA, CD, LC, RHO, MU)
    assert hi[1] == pytest.approx(lo[1], rel=1e-12)
    assert hi[0] == pytest.approx(lo[0], rel=1e-8)
    fd = (hi[0] - lo[0]) / (2e-9 * ps)
    assert fd == pytest.approx(lo[1], rel=1e-5)
    # closed orifice
    assert orifice_flow(1e5, 0.0, CD, LC, RHO, MU) == (0.0, 0.0)
    assert orifice_flow(-1e5, -1e-6, CD, LC, RHO, MU) == (0.0, 0.0)


def test_orifice_flow_always_finite():
    for dp, area, mu, rho, lc in itertools.product(
            (0.0, 1e-300, -1e-12, 1.0, -1e9, 1e300),
            (0.0, 1e-30, 1e-5, 1.0),
            (0.0, 1e-12, 0.04),
            (0.0, 870.0),
            (0.0, 1000.0)):
        q, dq = orifice_flow(dp, area, CD, lc, rho, mu)
        assert math.isfinite(q) and math.isfinite(dq) and dq >= 0.0
