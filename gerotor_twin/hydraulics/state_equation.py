"""The oil's barotropic state equation as the hot loop uses it: ln ρ ⇄ p.

The pump model carries the log-density s = ln(ρ/ρ₀) of every volume as its
state (mass balance exact) and needs the pressure p(s) in every right-hand
side.  Two fluid models share one :class:`StateEquation` (field ``kind``):

``MIXTURE`` (the default, ``fluid_model: mixture``)
    oil + free air + vapour of :mod:`gerotor_twin.hydraulics.mixture`: s(p)
    and β(p) in closed form; p(s) from a cubic Hermite table uniform in s up to
    p = :data:`MIXTURE_TABLE_HI_PA` (exact slopes dp/ds = β at the nodes),
    and the safeguarded Newton solve
    :func:`~gerotor_twin.hydraulics.mixture.mixture_pressure` outside it
    (pressure peaks, deep cavitation).  The table's spacing is that of
    :data:`MIXTURE_NODES` nodes between p = :data:`MIXTURE_TABLE_LO_PA` and
    :data:`MIXTURE_TABLE_HI_PA`; with it the table reaches down to
    :data:`MIXTURE_CAVITATION_MARGIN_PA` above the vapour pressure, in at most
    :data:`MIXTURE_MAX_NODES` nodes: the chambers of a pump at its top speed and a
    low delivery pressure spend a fifth to a third of the revolution below 0.1 bar,
    where the Newton solve is several times the table's cost (docs/performance.md).
    β between nodes is the derivative of the same cubic.
``PAPER`` (``fluid_model: paper``)
    Eq. (23) of [1], smoothed, with a vapour floor
    (:func:`gerotor_twin.hydraulics.fluid.log_density` defines s(p) =
    ∫ dp/β(p)); this module inverts it:

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

import functools
import math
from typing import NamedTuple

import numpy as np

from .._jit import njit
from .fluid import Fluid, bulk_modulus, log_density
from .mixture import AirContent, mixture_bulk_modulus, mixture_log_density, mixture_pressure, mixture_table

__all__ = ["exp_small", "StateEquation", "state_equation", "pressure_of", "state_of", "log_density_of", "bulk_modulus_of",
           "BAND_NODES", "MIXTURE_NODES", "MIXTURE_MAX_NODES", "PAPER", "MIXTURE", "FLUID_MODELS", "convert_log_density",
           "with_liquid_modulus", "hermite_coefficients", "port_states"]

BAND_NODES = 1024   #: nodes of the Hermite table of p(s) inside the switch band (paper)
MIXTURE_NODES = 2048          #: nodes of the Hermite table of p(s) of the mixture
MIXTURE_TABLE_LO_PA = 1e4     #: MIXTURE_NODES nodes span [this, MIXTURE_TABLE_HI_PA]: the table's spacing [Pa]
MIXTURE_TABLE_HI_PA = 5e7     #: highest pressure of the mixture table [Pa] (Newton above)
MIXTURE_CAVITATION_MARGIN_PA = 300.0  #: the table reaches down to p_vap + this at that spacing [Pa] (Newton below)
MIXTURE_MAX_NODES = 16384     #: at most this many nodes (more free air: the table stops higher) [-]
#: A volume counts as cavitating (kernel counter) where free gas + vapour take more than this
#: share of the mixture volume (mixture model) [-].
CAVITATION_GAS_SHARE = 0.01
PAPER, MIXTURE = 0, 1         #: values of StateEquation.kind
FLUID_MODELS = {"paper": PAPER, "mixture": MIXTURE}   #: config names of the fluid models


class StateEquation(NamedTuple):
    """Constants of the state equation for the compiled kernels (absolute pressures).

    ``kind`` selects the model; the fields marked (paper) / (mixture) have that
    meaning only for that model.
    """
    beta_liquid: float      #: β* (paper) or β_L (mixture), bulk modulus of the liquid [Pa]
    ratio: float            #: β*/β below atmospheric pressure [-] (1000 in Eq. (23)) (paper)
    p_atm: float            #: atmospheric pressure: switch of Eq. (23), p₀ of the mixture [Pa]
    band: float             #: width of the smoothed switch [Pa] (paper)
    p_vap: float            #: vapour pressure [Pa]
    p_lo: float             #: p_atm − band/2 (paper); below it a volume counts as cavitating [Pa]
    p_hi: float             #: p_atm + band/2 (paper); top of the p(s) table (mixture) [Pa]
    s_lo: float             #: ln(ρ/ρ₀) at the start of the p(s) table [-]
    s_hi: float             #: ln(ρ/ρ₀) at its end [-]
    band_c: np.ndarray      #: the table's cubic per interval of s, (nodes − 1, 4) [Pa] (:func:`hermite_coefficients`)
    inv_ds: float           #: 1 / the table's node spacing in s [-]
    kind: int = PAPER       #: PAPER or MIXTURE
    air_fraction: float = 0.0       #: α₀, free air volume fraction at p_atm [-] (mixture)
    polytropic_index: float = 1.0   #: n of the air [-] (mixture)


@njit(inline="always")
def bulk_modulus_of(p, eos):
    """β(p) [Pa] of the fluid model of ``eos`` (closed forms)."""
    if eos.kind == MIXTURE:
        return mixture_bulk_modulus(p, eos.beta_liquid, eos.air_fraction, eos.polytropic_index, eos.p_vap,
                                    eos.p_atm)[0]
    return bulk_modulus(p, eos.beta_liquid, eos.ratio, eos.p_atm, eos.band, eos.p_vap)[0]


@njit
def log_density_of(p, eos):
    """s = ln(ρ(p)/ρ₀) [-]: closed forms (paper: outside the band, the exact quadrature inside)."""
    if eos.kind == MIXTURE:
        return mixture_log_density(p, eos.beta_liquid, eos.air_fraction, eos.polytropic_index, eos.p_vap,
                                   eos.p_atm)
    if p >= eos.p_hi:
        return eos.s_hi + (p - eos.p_hi) / eos.beta_liquid
    return log_density(p, eos.beta_liquid, eos.ratio, eos.p_atm, eos.band, eos.p_vap)


@njit(inline="always")
def exp_small(s):
    """ρ/ρ₀ = e^s of a log-density s: a Taylor polynomial for |s| < 0.01 (relative error < 2e-15), exp otherwise."""
    if -0.01 < s < 0.01:
        return 1.0 + s * (1.0 + s * 0.5 * (1.0 + s / 3.0 * (1.0 + 0.25 * s * (1.0 + 0.2 * s))))
    return math.exp(s)


@njit(inline="always")
def pressure_of(s, eos):
    r"""Absolute pressure p(s) [Pa], the inverse of :func:`log_density_of`.

    Notes
    -----
    Vapour floor (β = β_l σ(2 − σ), σ = (p − p_vap)/L, L = p_lo − p_vap,
    β_l = β*/ratio): inverting s = s_lo + L/(2β_l) ln(σ/(2 − σ)) gives

    .. math::
        p = p_{vap} + L\,\frac{2E}{1 + E},\qquad E = e^{2β_l (s - s_{lo})/L}

    Mixture: the Hermite table inside [s_lo, s_hi], the Newton solve outside.
    """
    if eos.kind == MIXTURE:
        if eos.s_lo <= s <= eos.s_hi:
            return _hermite(s, eos)[0]
        return mixture_pressure(s, eos.beta_liquid, eos.air_fraction, eos.polytropic_index, eos.p_vap,
                                eos.p_atm)
    if s >= eos.s_hi:
        return eos.p_hi + (s - eos.s_hi) * eos.beta_liquid          # liquid, β = β*
    if s <= eos.s_lo:                                                # vapour floor
        width = eos.p_lo - eos.p_vap
        x = 2.0 * (s - eos.s_lo) * (eos.beta_liquid / eos.ratio) / width
        if x < -700.0:
            return eos.p_vap
        big_e = math.exp(x)
        return eos.p_vap + width * 2.0 * big_e / (1.0 + big_e)
    return _hermite(s, eos)[0]


def hermite_coefficients(band_p: np.ndarray, band_dp: np.ndarray, ds: float) -> np.ndarray:
    r"""The cubic Hermite table of p(s) through nodes uniform in s as one cubic per interval, (nodes − 1, 4) [Pa].

    Parameters
    ----------
    band_p : ndarray
        p at the nodes [Pa].
    band_dp : ndarray
        dp/ds = β at the nodes [Pa].
    ds : float
        The node spacing in s [-].

    Notes
    -----
    On interval i, with t = (s − s_i)/Δs ∈ [0, 1], m = Δs·dp/ds at its two ends, the Hermite cubic is

    .. math::
        p = c_0 + t\,(c_1 + t\,(c_2 + t\,c_3)),\quad c_0 = p_i,\ c_1 = m_i,\
        c_2 = 3(p_{i+1} - p_i) - 2m_i - m_{i+1},\ c_3 = 2(p_i - p_{i+1}) + m_i + m_{i+1}

    (the Hermite basis functions collected in t): one row of four numbers per lookup and Horner's rule, in
    place of two rows of two tables and the basis polynomials.  The same cubic up to rounding.
    """
    p0, p1 = band_p[:-1], band_p[1:]
    m0, m1 = ds * band_dp[:-1], ds * band_dp[1:]
    return np.ascontiguousarray(np.stack([p0, m0, 3.0 * (p1 - p0) - 2.0 * m0 - m1, 2.0 * (p0 - p1) + m0 + m1],
                                         axis=1))


@njit(inline="always")
def _hermite(s, eos):
    """(p, dp/ds) [Pa] of the cubic Hermite table of ``eos`` at s in [s_lo, s_hi] (:func:`hermite_coefficients`)."""
    u = (s - eos.s_lo) * eos.inv_ds
    i = min(max(int(u), 0), eos.band_c.shape[0] - 1)
    t = u - i
    c1, c2, c3 = eos.band_c[i, 1], eos.band_c[i, 2], eos.band_c[i, 3]
    p = eos.band_c[i, 0] + t * (c1 + t * (c2 + t * c3))
    dp = (c1 + t * (2.0 * c2 + 3.0 * t * c3)) * eos.inv_ds
    return p, dp


@njit(inline="always")
def state_of(s, eos):
    """(p [Pa], β [Pa]) of log-density s: :func:`pressure_of` and β(p) in one call (β = β* in the liquid).

    Mixture inside its table: β is the slope of the same cubic, within 2.1e-6
    (relative) of the closed form; the table's p(s) is within 0.011 Pa of the exact
    inverse (default mixture, 1e4 Pa – 500 bar, measured; test_kernel).  β only
    enters the Jacobian and the error weights, not the mass balance.
    """
    if eos.kind == MIXTURE:
        if eos.s_lo <= s <= eos.s_hi:
            return _hermite(s, eos)
        p = pressure_of(s, eos)
        return p, bulk_modulus_of(p, eos)
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


def state_equation(fluid: Fluid, model: str = "paper", air: AirContent | None = None) -> StateEquation:
    """Build the :class:`StateEquation` of a validated fluid.

    Parameters
    ----------
    fluid : Fluid
        ρ₀, β of the liquid, atmospheric and vapour pressure (and Eq. (23)'s
        ratio and band for ``paper``) [SI].
    model : {"paper", "mixture"}
        Fluid model (see the module docstring).
    air : AirContent, optional
        Free air content and polytropic index of the mixture (default
        :class:`~gerotor_twin.hydraulics.mixture.AirContent`).

    Cost: ≈ 3 ms (paper: the band table), ≈ 5–10 ms (mixture: one Newton solve per table node; the last 64
    mixture tables are kept).
    """
    if model not in FLUID_MODELS:
        from ..errors import InputError
        raise InputError("fluid_model", model, " | ".join(FLUID_MODELS))
    if model == "mixture":
        return _mixture_equation(fluid, air if air is not None else AirContent())
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
                         p_lo=p_lo, p_hi=p_hi, s_lo=s_lo, s_hi=s_hi,
                         band_c=hermite_coefficients(band_p, band_dp, (s_hi - s_lo) / (BAND_NODES - 1)),
                         inv_ds=(BAND_NODES - 1) / (s_hi - s_lo))


def _mixture_equation(fluid: Fluid, air: AirContent) -> StateEquation:
    """:class:`StateEquation` of the oil–air–vapour mixture (Hermite table of p(s) over the pump's range).

    The table depends on five numbers only; the last 64 are kept (a calibration or a run-steady sweep builds
    models at the same oil temperatures over and over; the arrays are shared and never written)."""
    return _mixture_equation_of(float(fluid.bulk_modulus_pa), float(air.air_fraction), float(air.polytropic_index),
                                float(fluid.vapour_pressure_pa), float(fluid.atmospheric_pa))


@functools.lru_cache(maxsize=64)
def _mixture_equation_of(beta_l: float, alpha0: float, n: float, p_vap: float, p_atm: float) -> StateEquation:
    args = (beta_l, alpha0, n, p_vap, p_atm)
    s_hi = mixture_log_density(MIXTURE_TABLE_HI_PA, *args)
    ds = (s_hi - mixture_log_density(max(MIXTURE_TABLE_LO_PA, p_vap + 1.0), *args)) / (
        MIXTURE_NODES - 1)
    s_floor = mixture_log_density(p_vap + MIXTURE_CAVITATION_MARGIN_PA, *args)
    nodes = int(min(MIXTURE_MAX_NODES, max(MIXTURE_NODES, math.ceil((s_hi - s_floor) / ds) + 1)))
    s_lo = s_hi - (nodes - 1) * ds
    p_tab, dp_tab = mixture_table(np.linspace(s_lo, s_hi, nodes), *args)
    # cavitating: gas + vapour above CAVITATION_GAS_SHARE of the volume, α₀(p₀ − p_v)/(p − p_v) ≈ share
    p0, pv = p_atm, p_vap
    p_cav = min(p0, pv + alpha0 * (p0 - pv) / CAVITATION_GAS_SHARE)
    return StateEquation(beta_liquid=beta_l, ratio=1.0, p_atm=p0, band=0.0, p_vap=pv,
                         p_lo=p_cav, p_hi=MIXTURE_TABLE_HI_PA, s_lo=s_lo, s_hi=s_hi,
                         band_c=hermite_coefficients(p_tab, dp_tab, (s_hi - s_lo) / (nodes - 1)),
                         inv_ds=(nodes - 1) / (s_hi - s_lo), kind=MIXTURE, air_fraction=alpha0, polytropic_index=n)


def with_liquid_modulus(eos: StateEquation, fluid: Fluid, model: str, air: AirContent | None) -> StateEquation:
    """The state equation of ``fluid`` reusing ``eos`` where it can (oil temperature changes).

    Eq. (23) (``paper``): every β of the law is β* times a function of p alone, so
    s(p) ∝ 1/β* and the band table carries over exactly, rescaled (p nodes kept,
    slopes × k, s bounds / k, k = β*_new/β*_old): ≈ 10 µs instead of the ≈ 3–25 ms
    of the bisection.  The mixture's table depends on β_L nonlinearly: rebuilt (≈ 2 ms), unless it is
    one of the last 64 built.
    """
    same = (fluid.cavitation_ratio, fluid.atmospheric_pa, fluid.switch_band_pa, fluid.vapour_pressure_pa) == \
        (eos.ratio, eos.p_atm, eos.band, eos.p_vap)
    if model != "paper" or eos.kind != PAPER or not same:
        return state_equation(fluid, model, air)
    k = fluid.bulk_modulus_pa / eos.beta_liquid
    return eos._replace(beta_liquid=fluid.bulk_modulus_pa, s_lo=eos.s_lo / k, s_hi=eos.s_hi / k,
                        inv_ds=eos.inv_ds * k)


@njit
def port_states(p_s, p_d, eos):
    """(ln(ρ(p_s)/ρ₀), ln(ρ(p_d)/ρ₀), β(p_d) [Pa], ρ(p_d)/ρ₀) of the suction and delivery pressures p_s, p_d [Pa]:
    what each ``advance`` call derives from its inputs (:func:`gerotor_twin.model.params.operating`), in one
    compiled call (each call from Python unboxes ``eos``: one instead of four)."""
    s_d = log_density_of(p_d, eos)
    return log_density_of(p_s, eos), s_d, bulk_modulus_of(p_d, eos), exp_small(s_d)


def convert_log_density(y: np.ndarray, old: StateEquation, new: StateEquation) -> np.ndarray:
    """Log-densities under ``new`` with the same pressures as ``y`` under ``old`` [-] (pressures continuous).

    Used when the oil properties change (temperature): the pressure of every
    volume is kept, its ln(ρ/ρ₀) is recomputed with the new state equation.  One compiled
    call (element-wise calls from Python cost ≈ 1 ms each in argument unboxing).
    """
    return _convert_log_density(np.ascontiguousarray(y, dtype=np.float64), old, new)


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def _convert_log_density(y, old, new):
    out = np.empty_like(y)
    for i in range(y.size):
        out[i] = log_density_of(pressure_of(y[i], old), new)
    return out
