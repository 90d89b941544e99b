"""Tests of gerotor_twin.hydraulics.mixture (oil + free air + vapour, barotropic).

Tiers (stated per test): CLOSED FORM (the documented equations re-coded here
with plain ``math``, or hand-computed numbers), LITERATURE (Simscape's
published entrained-air bulk modulus), BEHAVIOUR (limits, continuity,
monotonicity, inverse, robustness, validation).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.hydraulics.mixture import (
    S_CLIP,
    Mixture,
    mixture_bulk_modulus,
    mixture_log_density,
    mixture_pressure,
    mixture_pressure_array,
    mixture_table,
)
from gerotor_twin.hydraulics.oil import OilProperties

#: parameter sets (β_L, α0, n, p_vap, p0) spanning the allowed ranges
SETS = [
    (1.5e9, 1e-3, 1.0, 2000.0, 101325.0),     # the default
    (1.6e9, 5e-3, 1.2, 3000.0, 1e5),
    (1.2e9, 0.5, 1.4, 0.0, 101325.0),         # very aerated, adiabatic, no vapour pressure
    (2.0e9, 1e-12, 1.0, 2000.0, 101325.0),    # practically air-free
    (1e7, 1e-6, 1.4, 5e4, 1e5),               # soft liquid, high vapour pressure
]


def volume_ref(p, beta_l, a0, n, pv, p0):
    """Mixture volume per unit volume at p0, independently coded."""
    return (1 - a0) * math.exp(-(p - p0) / beta_l) + a0 * ((p0 - pv) / (p - pv)) ** (1 / n)


def beta_ref(p, beta_l, a0, n, pv, p0):
    """β = V/(−dV/dp), independently coded."""
    v = volume_ref(p, beta_l, a0, n, pv, p0)
    dv = -(1 - a0) * math.exp(-(p - p0) / beta_l) / beta_l \
        - a0 * ((p0 - pv) / (p - pv)) ** (1 / n) / (n * (p - pv))
    return -v / dv


def test_mixture_log_density():
    """CLOSED FORM: s = −ln[(1−α0)e^{−(p−p0)/β_L} + α0((p0−p_vap)/(p−p_vap))^{1/n}]."""
    # hand-computed: β_L = 1.5e9, α0 = 0.005, n = 1, p_vap = 0, p0 = 1e5, p = 1e6:
    # V = 0.995·exp(−9e5/1.5e9) + 0.005·0.1 = 0.995·0.99940018 + 0.0005 = 0.99490318
    args = (1.5e9, 0.005, 1.0, 0.0, 1e5)
    assert mixture_log_density(1e6, *args) == pytest.approx(-math.log(0.99490318), abs=2e-9)
    # p = 0.5 bar abs: V = 0.995·exp(5e4/1.5e9) + 0.005·2 = 0.9950331672 + 0.01 = 1.0050331672
    assert mixture_log_density(5e4, *args) == pytest.approx(-math.log(1.0050331672), abs=2e-10)
    for prm in SETS:
        assert mixture_log_density(prm[4], *prm) == pytest.approx(0.0, abs=1e-15)
        for p in (prm[3] + 1.0, prm[3] + 500.0, 3e4 + prm[3], 1e5, 2e5, 1e6, 3e7):
            assert mixture_log_density(p, *prm) == pytest.approx(
                -math.log(volume_ref(p, *prm)), rel=1e-12, abs=1e-14)


def test_mixture_bulk_modulus():
    """CLOSED FORM: β = V/(−dV/dp) and dβ/dp (vs finite differences of the closed form)."""
    # hand-computed: β_L = 1.5e9, α0 = 0.005, n = 1, p_vap = 0, p0 = 1e5, at p = p0:
    # 1/β = 0.995/1.5e9 + 0.005/1e5 = 5.0663333e-8 → β = 1.9738e7 Pa
    assert mixture_bulk_modulus(1e5, 1.5e9, 0.005, 1.0, 0.0, 1e5)[0] == pytest.approx(
        1.0 / (0.995 / 1.5e9 + 0.005 / 1e5), rel=1e-13)
    for prm in SETS:
        pv = prm[3]
        for p in (pv + 1e-3, pv + 1.0, pv + 800.0, 5e4 + pv, 1e5, 3e5, 1e6, 1e7, 3e7):
            beta, dbeta = mixture_bulk_modulus(p, *prm)
            assert beta == pytest.approx(beta_ref(p, *prm), rel=1e-12)
            h = 1e-3 * (p - pv)          # larger steps lose digits in p ± h near p_vap
            fd = (beta_ref(p + h, *prm) - beta_ref(p - h, *prm)) / (2 * h)
            assert dbeta == pytest.approx(fd, rel=1e-5, abs=1e-9)
        # β = 1/(ds/dp): the two closed forms are consistent
        p = 0.5 * (pv + prm[4])
        h = 1e-4 * (p - pv)
        ds = (mixture_log_density(p + h, *prm) - mixture_log_density(p - h, *prm)) / (2 * h)
        assert 1.0 / ds == pytest.approx(mixture_bulk_modulus(p, *prm)[0], rel=1e-6)


def test_mixture_bulk_modulus_simscape():
    """LITERATURE: Simscape Hydraulic Fluid block's entrained-air modulus.

    E = E_l (1 + α(p_a/(p_a+p))^{1/n}) / (1 + α p_a^{1/n} E_l/(n (p_a+p)^{(n+1)/n})),
    p gauge, α = V_G/V_L at p_a (MathWorks documentation, Hydraulic Fluid block).
    Same physics with p_vap = 0 and an incompressible liquid VOLUME ratio; our
    exponential liquid differs by ≤ (p − p_a)/β_L in the ratio (≤ 7e-4 at 10 bar).
    """
    e_l, a0, pa = 1.5e9, 0.005, 101325.0
    alpha = a0 / (1 - a0)
    for n in (1.0, 1.4):
        for pg in (0.0, 0.5e5, 2e5, 5e5, 1e6):
            e_sim = e_l * (1 + alpha * (pa / (pa + pg)) ** (1 / n)) / (
                1 + alpha * pa ** (1 / n) * e_l / (n * (pa + pg) ** ((n + 1) / n)))
            ours = mixture_bulk_modulus(pa + pg, e_l, a0, n, 0.0, pa)[0]
            assert ours == pytest.approx(e_sim, rel=1e-3)


def test_mixture_liquid_limit():
    """BEHAVIOUR (limit): α0 → 0 gives β → β_L, s → (p−p0)/β_L, ρ → ρ_L e^s above p_vap."""
    beta_l, pv, p0 = 1.5e9, 2000.0, 101325.0
    for p in (2e4, 1e5, 1e6, 3e7):
        errs = []
        for a0 in (1e-3, 1e-6, 1e-9, 1e-12):
            m = Mixture(bulk_modulus_liquid_pa=beta_l, air_fraction=a0, vapour_pressure_pa=pv)
            errs.append(abs(m.bulk_modulus(p) / beta_l - 1.0))
            if a0 == 1e-12:
                assert m.bulk_modulus(p) == pytest.approx(beta_l, rel=1e-6)
                assert m.log_density(p) == pytest.approx((p - p0) / beta_l, abs=1e-11)
                assert m.density(p) == pytest.approx(870.0 * math.exp((p - p0) / beta_l),
                                                     rel=1e-9)
        assert errs == sorted(errs, reverse=True)   # monotone approach to the liquid
    # the default oil (0.1 % air) is stiff at delivery: at 27.5 bar gauge the gas term
    # 1e-3·(99325/2.85e6)/2.85e6 = 1.22e-11 1/Pa against 0.999/β_L = 6.66e-10: β = 0.982 β_L
    assert Mixture().bulk_modulus(27.5e5 + 101325.0) == pytest.approx(0.982 * beta_l, rel=1e-3)
    # and the mixture is soft at the inlet: β(1 atm) = 1/(0.999/β_L + 0.001/(p0 − p_vap))
    assert Mixture().bulk_modulus(p0) == pytest.approx(1 / (0.999 / beta_l + 1e-3 / (p0 - pv)),
                                                       rel=1e-12)


@pytest.mark.parametrize("prm", SETS)
def test_mixture_continuity_monotonicity(prm):
    """BEHAVIOUR: s(p) strictly increasing, β(p) increasing, both continuous on [p_vap, 300 bar]."""
    pv = prm[3]
    p = np.unique(np.concatenate([pv + np.logspace(-6, math.log10(2e5), 4000),
                                  np.linspace(pv + 1.0, 300e5, 6000)]))
    s = np.array([mixture_log_density(x, *prm) for x in p])
    b = np.array([mixture_bulk_modulus(x, *prm)[0] for x in p])
    db = np.array([mixture_bulk_modulus(x, *prm)[1] for x in p])
    assert np.all(np.isfinite(s)) and np.all(np.isfinite(b)) and np.all(np.isfinite(db))
    assert np.all(np.diff(s) > 0.0)
    assert np.all(np.diff(b) >= -1e-12 * b[1:])
    # continuity: each increment is bounded by the derivative bound over the step
    dp = np.diff(p)
    assert np.all(np.diff(s) <= dp / b[:-1] * (1 + 1e-9))      # 1/β decreasing → max at left
    assert np.all(np.diff(b) <= dp * np.maximum(db[:-1], db[1:]).clip(min=0) * 1.5 + 1e-6 * b[1:])
    # β → 0 at the vapour pressure, like the pure gas: β ≈ nΔ, dβ/dp → n once the bubbles
    # hold > 1 − 1e-8 of the volume, i.e. Δ < (p0 − p_vap)(α0/1e8)^n (if representable)
    assert mixture_bulk_modulus(pv, *prm) == (0.0, 0.0)
    delta = (prm[4] - pv) * (prm[1] / 1e8) ** prm[2]
    if pv + delta > pv:
        beta, db = mixture_bulk_modulus(pv + delta, *prm)
        d_true = (pv + delta) - pv
        assert beta == pytest.approx(prm[2] * d_true, rel=1e-6)
        assert db == pytest.approx(prm[2], rel=1e-6)


@pytest.mark.parametrize("prm", SETS)
def test_mixture_pressure_inverse(prm):
    """BEHAVIOUR: p(s(p)) = p to 1e-9 relative over [p_vap, 300 bar]; vectorised = scalar."""
    pv = prm[3]
    p = np.concatenate([pv + np.logspace(-3, math.log10(2e5), 500), np.linspace(1e5, 300e5, 500)])
    s = np.array([mixture_log_density(x, *prm) for x in p])
    back = mixture_pressure_array(s, *prm)
    assert np.all(np.abs(back - p) <= 1e-9 * p)
    assert back[17] == mixture_pressure(s[17], *prm)
    m = Mixture(bulk_modulus_liquid_pa=prm[0], air_fraction=prm[1], polytropic_index=prm[2],
                vapour_pressure_pa=prm[3], reference_pressure_pa=prm[4])
    np.testing.assert_array_equal(m.pressure(s), back)
    assert m.pressure(0.0) == pytest.approx(prm[4], rel=1e-12)


def test_mixture_no_nan_and_vapour_floor():
    """BEHAVIOUR: finite output for every finite input; p(s) never below p_vap."""
    huge = [-1e300, -1e9, -1.0, 0.0, 1.0, 1e9, 1e300]
    for prm in SETS:
        pv = prm[3]
        for p in huge + [pv, pv + 1e-300, pv + 1e-12, pv - 1.0]:
            s = mixture_log_density(p, *prm)
            beta, db = mixture_bulk_modulus(p, *prm)
            assert math.isfinite(s) and math.isfinite(beta) and math.isfinite(db)
            assert beta >= 0.0
        for s in huge + [-S_CLIP - 1, -S_CLIP, S_CLIP, -50.0, -5.0, 0.5]:
            p = mixture_pressure(s, *prm)
            assert math.isfinite(p) and p >= pv
        assert mixture_pressure(float("nan"), *prm) == pv
        # below the vapour floor s saturates at a finite, very negative value
        assert mixture_log_density(pv - 1e5, *prm) == mixture_log_density(pv, *prm) < -300.0


def test_mixture_kernels_compiled_match_python():
    """BEHAVIOUR: the numba kernels equal their pure-Python versions (round-off)."""
    prm = SETS[1]
    for p in (prm[3] + 0.5, 5e4, 2e6):
        assert mixture_log_density(p, *prm) == pytest.approx(
            getattr(mixture_log_density, 'py_func', mixture_log_density)(p, *prm), rel=1e-14, abs=1e-16)
        b, db = mixture_bulk_modulus(p, *prm)
        bp, dbp = getattr(mixture_bulk_modulus, 'py_func', mixture_bulk_modulus)(p, *prm)
        assert b == pytest.approx(bp, rel=1e-14) and db == pytest.approx(dbp, rel=1e-12, abs=1e-14)
    for s in (-3.0, 0.0, 0.02):
        assert mixture_pressure(s, *prm) == pytest.approx(getattr(mixture_pressure, 'py_func', mixture_pressure)(s, *prm),
                                                          rel=1e-13)


def test_mixture_from_oil_and_density():
    """CLOSED FORM: from_oil takes β_L(T), ρ_L(T) of the oil; ρ_ref = (1−α0)ρ_L + α0ρ_g."""
    oil = OilProperties.iso_vg(46)
    m = Mixture.from_oil(oil, 343.15, air_fraction=0.01)
    assert m.bulk_modulus_liquid_pa == oil.bulk_modulus(343.15)
    assert m.density_liquid_kg_m3 == oil.density(343.15)
    assert m.density_gas_kg_m3 == pytest.approx((101325.0 - 2000.0) / (287.05 * 343.15), rel=1e-14)
    rho_ref = 0.99 * oil.density(343.15) + 0.01 * m.density_gas_kg_m3
    assert m.reference_density_kg_m3 == pytest.approx(rho_ref, rel=1e-15)
    assert m.density(101325.0) == pytest.approx(rho_ref, rel=1e-14)
    # at 0.6 bar abs the bubbles have grown by (p0 − p_vap)/(p − p_vap) = 99325/58000
    w = 0.01 * 99325.0 / 58000.0
    v = 0.99 * math.exp(41325.0 / m.bulk_modulus_liquid_pa) + w
    assert m.density(60000.0) == pytest.approx(rho_ref / v, rel=1e-12)
    assert m.air_volume_fraction(60000.0) == pytest.approx(w / v, rel=1e-12)
    np.testing.assert_allclose(m.log_density(np.array([6e4, 1e6])),
                               [m.log_density(6e4), m.log_density(1e6)], rtol=0, atol=0)


@pytest.mark.parametrize("field, value", [
    ("air_fraction", 0.0),
    ("air_fraction", 0.9),
    ("air_fraction", float("nan")),
    ("polytropic_index", 0.9),
    ("vapour_pressure_pa", -1.0),
    ("vapour_pressure_pa", 60000.0),
    ("bulk_modulus_liquid_pa", 0.0),
    ("reference_pressure_pa", "atm"),
    ("density_liquid_kg_m3", -870.0),
])
def test_mixture_validation(field, value):
    """BEHAVIOUR: every bad field raises InputError naming the field, value and range."""
    with pytest.raises(InputError) as exc:
        Mixture(**{field: value})
    assert exc.value.field == f"mixture.{field}" and f"mixture.{field}" in str(exc.value)


def test_mixture_table_hermite():
    """BEHAVIOUR: table nodes are (p(s), β(p(s))); a 2048-node Hermite table on
    [s(1e4 Pa), s(350 bar)] reproduces p(s) to 1e-6 relative (measured ~1e-8)."""
    m = Mixture()
    args = m.kernel_args()
    s = np.linspace(m.log_density(1e4), m.log_density(350e5), 2048)
    p, dp = mixture_table(s, *args)
    np.testing.assert_array_equal(p, mixture_pressure_array(s, *args))
    assert all(dp[i] == mixture_bulk_modulus(p[i], *args)[0] for i in (0, 700, 2047))
    ds = s[1] - s[0]
    st = np.linspace(s[0], s[-1], 50001)[1:-1]
    i = np.minimum(((st - s[0]) / ds).astype(int), s.size - 2)
    t = (st - s[i]) / ds
    h = ((2 * t**3 - 3 * t**2 + 1) * p[i] + (t**3 - 2 * t**2 + t) * ds * dp[i]
         + (3 * t**2 - 2 * t**3) * p[i + 1] + (t**3 - t**2) * ds * dp[i + 1])
    exact = mixture_pressure_array(st, *args)
    assert np.max(np.abs(h - exact) / exact) < 1e-6


def test_mixture_pressure_inverse_random_parameters():
    """BEHAVIOUR: p(s(p)) = p to 1e-9 relative for 300 random parameter sets spanning the
    allowed ranges (β_L 1e7–1e11 Pa, α0 1e-12–0.5, n 1–1.4, p0 1e3–1e7 Pa, p_vap ≤ p0/2)
    and pressures from p_vap + 1 mPa to 300 bar (measured worst: ~7e-13 over 3000 sets)."""
    rng = np.random.default_rng(20261130)
    for _ in range(300):
        p0 = 10 ** rng.uniform(3, 7)
        prm = (10 ** rng.uniform(7, 11), 10 ** rng.uniform(-12, math.log10(0.5)),
               rng.uniform(1.0, 1.4), rng.uniform(0.0, 0.5 * p0), p0)
        pv = prm[3]
        p = np.concatenate([pv + 10 ** rng.uniform(-3, math.log10(max(p0, 1e5)), 20),
                            rng.uniform(pv, 300e5, 20)])
        p = p[p > pv]
        s = np.array([mixture_log_density(x, *prm) for x in p])
        back = mixture_pressure_array(s, *prm)
        assert np.all(np.abs(back - p) <= 1e-9 * p), prm


def test_mixture_vs_paper_eq23_fill_deficit():
    """CLOSED FORM: density deficit 1 − ρ(p)/ρ(p_atm) of a chamber filling below atmospheric.

    Eq. (23) (β*/1000 below p_atm, smoothed, fluid.log_density) charges the filling
    with ~(p_atm − p)/(β*/1000): 0.60 % at 0.9 bar abs, the artefact issue 13 names.
    The mixture's deficit is the bubbles' growth: 1 − 1/(0.999 + 0.001·99325/88000)
    = 0.0136 % at 0.9 bar with the default 0.1 % air, ~45x smaller.
    """
    from gerotor_twin.hydraulics.fluid import log_density
    p = 90000.0
    eq23 = 1 - math.exp(log_density(p, 1.5e9, 1000.0, 101325.0, 5000.0, 2000.0))
    mix = 1 - math.exp(Mixture().log_density(p))
    v = 0.999 * math.exp((101325.0 - p) / 1.5e9) + 0.001 * 99325.0 / 88000.0
    assert mix == pytest.approx(1 - 1 / v, rel=1e-9)
    assert mix == pytest.approx(1.362e-4, rel=1e-3)
    assert eq23 == pytest.approx(5.98e-3, rel=1e-2)
    assert eq23 / mix > 40
