"""Tests of gerotor_twin.hydraulics.fluid — CLOSED-FORM tests.

Reference values come from closed forms and limits written out here, never
from the code under test: Eq. (23) of [1] and its smoothing by the cubic
Hermite step, the vapour floor β*/r·σ(2−σ), the closed-form integrals of 1/β
in the constant-β and floor regions, and (switch band only) an independent
adaptive quadrature (scipy.integrate.quad) of an independently coded 1/β.
Derivatives are checked against central finite differences, continuity at
every region switch by evaluating both sides.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import quad

from gerotor_twin.errors import InputError
from gerotor_twin.hydraulics import fluid as F
from gerotor_twin.hydraulics.fluid import Fluid, bulk_modulus, density_ratio, log_density

BETA = 1.5e9
RATIO = 1000.0
PATM = 101325.0
BAND = 5000.0
PVAP = 2000.0
ARGS = (BETA, RATIO, PATM, BAND, PVAP)
P_LO = PATM - BAND / 2
P_HI = PATM + BAND / 2
WIDTH = P_LO - PVAP
BLOW = BETA / RATIO


def beta_ref(p, beta_star=BETA, ratio=RATIO, p_atm=PATM, band=BAND, p_vap=PVAP):
    """Independent coding of the documented β(p) (Eq. (23) smoothed + vapour floor)."""
    x = min(max((p - p_atm + band / 2) / band, 0.0), 1.0)
    w = 3 * x**2 - 2 * x**3
    b23 = beta_star / ratio + (beta_star - beta_star / ratio) * w
    s = min(max((p - p_vap) / (p_atm - band / 2 - p_vap), 0.0), 1.0)
    return b23 * (1 - (1 - s) ** 2)


def fd(f, x, h):
    return (f(x + h) - f(x - h)) / (2 * h)


# ---------------------------------------------------------------------------
# Fluid container
# ---------------------------------------------------------------------------
def test_fluid_defaults_and_kernel_params():
    fl = Fluid()
    kp = fl.kernel_params()
    assert kp.dtype == np.float64 and kp.shape == (F.N_FLUID_PARAMS,)
    assert kp[F.FP_DENSITY] == 870.0
    assert kp[F.FP_VISCOSITY] == 0.0391
    assert kp[F.FP_BULK_MODULUS] == 1.5e9
    assert kp[F.FP_CAVITATION_RATIO] == 1000.0
    assert kp[F.FP_ATMOSPHERIC] == 101325.0
    assert kp[F.FP_VAPOUR] == 2000.0
    assert kp[F.FP_SWITCH_BAND] == 5000.0
    with pytest.raises(Exception):
        fl.density_kg_m3 = 1.0  # frozen


@pytest.mark.parametrize("field, value", [
    ("density_kg_m3", 0.0),
    ("density_kg_m3", float("nan")),
    ("viscosity_pa_s", -1e-3),
    ("bulk_modulus_pa", float("inf")),
    ("cavitation_ratio", 0.5),
    ("atmospheric_pa", 0.0),
    ("switch_band_pa", 0.0),
    ("vapour_pressure_pa", -1.0),
    ("vapour_pressure_pa", 99000.0),   # inside the switch band
    ("density_kg_m3", "heavy"),
])
def test_fluid_validation(field, value):
    with pytest.raises(InputError) as exc:
        Fluid(**{field: value})
    assert exc.value.field == f"fluid.{field}"
    assert f"fluid.{field}" in str(exc.value)


def test_fluid_coerces_to_float():
    fl = Fluid(density_kg_m3=850, cavitation_ratio=1)
    assert isinstance(fl.density_kg_m3, float) and fl.cavitation_ratio == 1.0


# ---------------------------------------------------------------------------
# bulk_modulus
# ---------------------------------------------------------------------------
def test_bulk_modulus():
    # closed-form values in every region
    assert bulk_modulus(P_HI, *ARGS) == (BETA, 0.0)
    assert bulk_modulus(1e8, *ARGS) == (BETA, 0.0)
    b, db = bulk_modulus(PATM, *ARGS)            # x = 1/2 → w = 1/2
    assert b == pytest.approx(0.5 * (BETA + BLOW), rel=1e-15)
    assert db == pytest.approx((BETA - BLOW) * 1.5 / BAND, rel=1e-14)  # 6x(1-x)/band
    assert bulk_modulus(P_LO, *ARGS)[0] == pytest.approx(BLOW, rel=1e-15)
    b, db = bulk_modulus(PVAP + 0.5 * WIDTH, *ARGS)  # σ = 1/2 → φ = 3/4
    assert b == pytest.approx(0.75 * BLOW, rel=1e-14)
    assert db == pytest.approx(BLOW * 1.0 / WIDTH, rel=1e-14)  # 2(1-σ)/L
    assert bulk_modulus(PVAP, *ARGS) == (0.0, 0.0)
    assert bulk_modulus(-1e6, *ARGS) == (0.0, 0.0)

    # against the independently coded formula on a dense grid
    for p in np.linspace(-1e4, 2e5, 2001):
        assert bulk_modulus(p, *ARGS)[0] == pytest.approx(beta_ref(p), rel=1e-13, abs=1e-9)

    # continuity (C0 everywhere, C1 at the band edges and at the floor's top)
    max_slope = 1.5 * BETA / BAND  # max |dβ/dp|, at the band centre
    for ps in (PVAP, P_LO, P_HI):
        eps = 1e-6
        lo, hi = bulk_modulus(ps - eps, *ARGS), bulk_modulus(ps + eps, *ARGS)
        assert abs(hi[0] - lo[0]) <= 2 * eps * max_slope
    for ps in (P_LO, P_HI):
        eps = 1e-7
        assert abs(bulk_modulus(ps - eps, *ARGS)[1]) < 1e-3 * (BETA / BAND)
        assert abs(bulk_modulus(ps + eps, *ARGS)[1]) < 1e-3 * (BETA / BAND)

    # analytic derivative against finite differences in every region
    f = lambda p: bulk_modulus(p, *ARGS)[0]  # noqa: E731
    for p in [PVAP + 1.0, 3e4, 7e4, P_LO - 10.0, P_LO + 10.0, PATM - 700.0, PATM, PATM + 1234.0,
              P_HI - 10.0, P_HI + 10.0, 3e5]:
        d_an = bulk_modulus(p, *ARGS)[1]
        d_fd = fd(f, p, 1e-3)
        assert d_an == pytest.approx(d_fd, rel=1e-6, abs=1e-6 * BETA / BAND)

    # Eq. (23) of [1] recovered as the band shrinks (just below p_atm the floor
    # factor is 1 - (1 - σ)² ≈ 1)
    for p, expected in [(PATM + 1.0, BETA), (PATM - 1.0, BLOW), (5e5, BETA), (PATM - 100.0, BLOW)]:
        assert bulk_modulus(p, BETA, RATIO, PATM, 1e-3, PVAP)[0] == pytest.approx(expected,
                                                                                  rel=1e-5)

    # ratio = 1: no switch, only the vapour floor
    assert bulk_modulus(PATM - 2000.0, BETA, 1.0, PATM, BAND, PVAP)[0] == BETA


# ---------------------------------------------------------------------------
# log_density, density_ratio
# ---------------------------------------------------------------------------
def s_band_ref(p, **kw):
    """∫_{p_atm}^{p} dp'/β(p') by adaptive quadrature of the independent β."""
    val, _ = quad(lambda q: 1.0 / beta_ref(q, **kw), PATM, p, epsabs=0.0, epsrel=1e-13,
                  limit=400)
    return val


def test_log_density():
    assert log_density(PATM, *ARGS) == 0.0
    # constant β (ratio = 1) above the floor: s = (p - p_atm)/β*
    for p in [P_LO, 9.9e4, PATM + 1.0, P_HI, 1e6, 3e7]:
        assert log_density(p, BETA, 1.0, PATM, BAND, PVAP) == pytest.approx((p - PATM) / BETA,
                                                                             rel=1e-13, abs=1e-19)
    # constant-β region: closed-form difference
    s1, s2 = log_density(2e5, *ARGS), log_density(3e7, *ARGS)
    assert s2 - s1 == pytest.approx((3e7 - 2e5) / BETA, rel=1e-12)
    # floor region: s = S_lo + L/(2 β_l) ln(σ/(2-σ))
    s_lo = log_density(P_LO, *ARGS)
    for sig in [0.9, 0.5, 0.1, 1e-3, 1e-9]:
        p = PVAP + sig * WIDTH
        sig = (p - PVAP) / WIDTH  # the σ actually represented by the float p
        expected = s_lo + WIDTH / (2 * BLOW) * math.log(sig / (2 - sig))
        assert log_density(p, *ARGS) == pytest.approx(expected, rel=1e-12)
    # switch band: independent adaptive quadrature
    for p in [P_LO, P_LO + 1.0, P_LO + 50.0, PATM - 1000.0, PATM - 1.0, PATM + 1.0, PATM + 999.0,
              P_HI, 1.1e5]:
        assert log_density(p, *ARGS) == pytest.approx(s_band_ref(p), rel=1e-11, abs=1e-16)
    # a much larger cavitation ratio (sharper band integrand) and a tiny one
    for ratio in (1e6, 1.0001):
        kw = dict(ratio=ratio)
        for p in [P_LO, PATM - 2000.0, PATM - 200.0, P_HI]:
            assert log_density(p, BETA, ratio, PATM, BAND, PVAP) == pytest.approx(
                s_band_ref(p, **kw), rel=1e-10, abs=1e-16)

    # d s/dp = 1/β by finite differences across all regions and at the switches
    f = lambda p: log_density(p, *ARGS)  # noqa: E731
    for p in [PVAP + 500.0, 2e4, 6e4, P_LO - 5.0, P_LO, P_LO + 5.0, PATM - 1500.0, PATM,
              PATM + 1100.0, P_HI - 5.0, P_HI, P_HI + 5.0, 2e5, 3e7]:
        h = 1e-2
        assert fd(f, p, h) == pytest.approx(1.0 / beta_ref(p), rel=1e-6)

    # continuity at the region boundaries
    for ps in (P_LO, P_HI):
        for eps in (1e-6, 1e-3):
            assert abs(f(ps + eps) - f(ps - eps)) <= 2.5 * eps / beta_ref(ps) + 1e-15

    # p → p_vap⁺: → -inf; at and below p_vap a large negative finite number
    below = [f(PVAP), f(PVAP - 1.0), f(-1e9)]
    assert all(math.isfinite(v) for v in below)
    assert below[0] == below[1] == below[2]
    assert f(PVAP) < f(PVAP + 1e-6) < f(PVAP + 1.0) < s_lo
    # monotone (β ≥ 0) on a grid through every region
    grid = np.linspace(0.0, 2e5, 4001)
    vals = np.array([f(p) for p in grid])
    assert np.all(np.diff(vals) >= 0.0) and np.all(np.isfinite(vals))


def test_density_ratio():
    # constant β: ρ(p1)/ρ(p2) = exp((p1 - p2)/β*)
    r = density_ratio(3e6, 2e5, BETA, 1.0, PATM, BAND, PVAP)
    assert r == pytest.approx(math.exp((3e6 - 2e5) / BETA), rel=1e-13)
    r = density_ratio(3e6, 2e5, *ARGS)
    assert r == pytest.approx(math.exp((3e6 - 2e5) / BETA), rel=1e-12)
    assert density_ratio(5e4, 5e4, *ARGS) == 1.0
    for a, b in [(5e4, 3e6), (PATM, P_LO - 100.0), (PVAP + 1.0, 1e7)]:
        assert density_ratio(a, b, *ARGS) * density_ratio(b, a, *ARGS) == pytest.approx(1.0,
                                                                                     rel=1e-13)
    # at the vapour floor: tiny but finite, never overflows
    lo, hi = density_ratio(PVAP, 1e7, *ARGS), density_ratio(1e7, PVAP, *ARGS)
    assert 0.0 < lo < 1e-6 and math.isfinite(hi)
    assert math.isfinite(density_ratio(PVAP, 1e7, BETA, 1.0, PATM, BAND, 1e-3))
    # huge cavitation ratio with the state at the floor: exponent clipped, still finite
    assert math.isfinite(density_ratio(1e7, 0.0, BETA, 1e6, PATM, BAND, PVAP))
