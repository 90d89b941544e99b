"""The oil's barotropic state equation as the hot loop uses it: ln ρ ⇄ p.

The pump model carries the log-density s = ln(ρ/ρ₀) of every volume as its
state (mass balance exact) and needs the pressure p(s) in every right-hand
side.  :func:`gerotor_twin.hydraulics.fluid.log_density` defines s(p) =
∫ dp/β(p) with β of Eq. (23) of [1] smoothed; this module inverts it:

* liquid (p ≥ p_hi = p_atm + b/2, β = β*): p = p_hi + β*(s − s_hi), closed form;
* vapour floor (p < p_lo = p_atm − b/2): closed form (partial fractions, see
  :func:`~gerotor_twin.hydraulics.fluid.log_density`);
* switch band (p_lo ≤ p < p_hi): cubic Hermite interpolation of p(s) on
  :data:`BAND_NODES` nodes uniform in s, with the exact slopes dp/ds = β(p)
  at the nodes (nodes found by bisection on the exact s(p)).  Measured
  interpolation error ≤ 2e-4 Pa for the default oil (test_state_equation).

:class:`StateEquation` holds the constants and the band table (one named
structure, fields in SI); :func:`state_equation` builds it from a validated
:class:`~gerotor_twin.hydraulics.fluid.Fluid`.

References
----------
.. [1] The paper, sec. 3.5, Eq. (23) (``../shared/paper``).
"""
from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .._jit import njit
from .fluid import Fluid, bulk_modulus, log_density

__all__ = ["StateEquation", "state_equation", "pressure_of", "state_of", "log_density_of", "bulk_modulus_of",
           "BAND_NODES"]

BAND_NODES = 1024   #: nodes of the Hermite table of p(s) inside the switch band


class StateEquation(NamedTuple):
    """Constants of the state equation for the compiled kernels (absolute pressures)."""
    beta_liquid: float      #: β*, bulk modulus of the liquid [Pa]
    ratio: float            #: β*/β below atmospheric pressure [-] (1000 in Eq. (23))
    p_atm: float            #: switch pressure of Eq. (23) [Pa]
    band: float             #: width of the smoothed switch [Pa]
    p_vap: float            #: vapour pressure [Pa]
    p_lo: float             #: p_atm − band/2 [Pa]
    p_hi: float             #: p_atm + band/2 [Pa]
    s_lo: float             #: ln(ρ/ρ₀) at p_lo [-]
    s_hi: float             #: ln(ρ/ρ₀) at p_hi [-]
    band_p: np.ndarray      #: (BAND_NODES,) pressure at nodes uniform in s over [s_lo, s_hi] [Pa]
    band_dp: np.ndarray     #: (BAND_NODES,) dp/ds = β at those nodes [Pa]


@njit(inline="always")
def bulk_modulus_of(p, eos):
    """β(p) [Pa] of :func:`~gerotor_twin.hydraulics.fluid.bulk_modulus` for a :class:`StateEquation`."""
    return bulk_modulus(p, eos.beta_liquid, eos.ratio, eos.p_atm, eos.band, eos.p_vap)[0]


@njit
def log_density_of(p, eos):
    """s = ln(ρ(p)/ρ₀) [-]: closed forms outside the band, the exact quadrature inside."""
    if p >= eos.p_hi:
        return eos.s_hi + (p - eos.p_hi) / eos.beta_liquid
    return log_density(p, eos.beta_liquid, eos.ratio, eos.p_atm, eos.band, eos.p_vap)


@njit(inline="always")
def pressure_of(s, eos):
    r"""Absolute pressure p(s) [Pa], the inverse of :func:`log_density_of`.

    Notes
    -----
    Vapour floor (β = β_l σ(2 − σ), σ = (p − p_vap)/L, L = p_lo − p_vap,
    β_l = β*/ratio): inverting s = s_lo + L/(2β_l) ln(σ/(2 − σ)) gives

    .. math::
        p = p_{vap} + L\,\frac{2E}{1 + E},\qquad E = e^{2β_l (s - s_{lo})/L}
    """
    if s >= eos.s_hi:
        return eos.p_hi + (s - eos.s_hi) * eos.beta_liquid          # liquid, β = β*
    if s <= eos.s_lo:                                                # vapour floor
        width = eos.p_lo - eos.p_vap
        x = 2.0 * (s - eos.s_lo) * (eos.beta_liquid / eos.ratio) / width
        if x < -700.0:
            return eos.p_vap
        big_e = math.exp(x)
        return eos.p_vap + width * 2.0 * big_e / (1.0 + big_e)
    n = eos.band_p.shape[0]
    ds = (eos.s_hi - eos.s_lo) / (n - 1)
    u = (s - eos.s_lo) / ds
    i = min(int(u), n - 2)
    t = u - i
    t2 = t * t
    t3 = t2 * t
    return ((2.0 * t3 - 3.0 * t2 + 1.0) * eos.band_p[i] + (t3 - 2.0 * t2 + t) * ds * eos.band_dp[i]
            + (3.0 * t2 - 2.0 * t3) * eos.band_p[i + 1] + (t3 - t2) * ds * eos.band_dp[i + 1])


@njit(inline="always")
def state_of(s, eos):
    """(p [Pa], β [Pa]) of log-density s: :func:`pressure_of` and β(p) in one call (β = β* in the liquid)."""
    if s >= eos.s_hi:
        return eos.p_hi + (s - eos.s_hi) * eos.beta_liquid, eos.beta_liquid
    p = pressure_of(s, eos)
    return p, bulk_modulus_of(p, eos)


@njit
def _band_nodes(s_nodes, p_lo, p_hi, beta_star, ratio, p_atm, band, p_vap, p_out, dp_out):
    for k in range(s_nodes.shape[0]):
        lo, hi = p_lo, p_hi
        for _ in range(200):                       # bisection: s(p) is strictly increasing
            mid = 0.5 * (lo + hi)
            if log_density(mid, beta_star, ratio, p_atm, band, p_vap) < s_nodes[k]:
                lo = mid
            else:
                hi = mid
            if hi - lo <= 1e-10 * p_hi:
                break
        p_out[k] = 0.5 * (lo + hi)
        dp_out[k] = bulk_modulus(p_out[k], beta_star, ratio, p_atm, band, p_vap)[0]


def state_equation(fluid: Fluid) -> StateEquation:
    """Build the :class:`StateEquation` of a validated fluid (≈ 3 ms: the band table)."""
    args = (fluid.bulk_modulus_pa, fluid.cavitation_ratio, fluid.atmospheric_pa, fluid.switch_band_pa,
            fluid.vapour_pressure_pa)
    p_lo = fluid.atmospheric_pa - 0.5 * fluid.switch_band_pa
    p_hi = fluid.atmospheric_pa + 0.5 * fluid.switch_band_pa
    s_lo, s_hi = log_density(p_lo, *args), log_density(p_hi, *args)
    s_nodes = np.linspace(s_lo, s_hi, BAND_NODES)
    band_p, band_dp = np.empty(BAND_NODES), np.empty(BAND_NODES)
    _band_nodes(s_nodes, p_lo, p_hi, *args, band_p, band_dp)
    band_p[0], band_p[-1] = p_lo, p_hi
    band_dp[0] = bulk_modulus(p_lo, *args)[0]
    band_dp[-1] = bulk_modulus(p_hi, *args)[0]
    return StateEquation(beta_liquid=fluid.bulk_modulus_pa, ratio=fluid.cavitation_ratio,
                         p_atm=fluid.atmospheric_pa, band=fluid.switch_band_pa, p_vap=fluid.vapour_pressure_pa,
                         p_lo=p_lo, p_hi=p_hi, s_lo=s_lo, s_hi=s_hi, band_p=band_p, band_dp=band_dp)
