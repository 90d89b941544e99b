"""Fluid model: constant density/viscosity and the pressure-dependent bulk modulus.

The paper's fluid model (section 3.5 and Eq. (23) of [1]) keeps density and
viscosity constant and represents cavitation "in a very simplified way" by
dropping the bulk modulus by three orders of magnitude below atmospheric
pressure.  The step of Eq. (23) is smoothed here (C¹, over a pressure band) and a
vapour floor is added so that the stiff implicit integrator sees a
differentiable β(p) and the chamber pressure can never fall below the vapour
pressure.

Everything called from the pump model's time loop is a numba-compiled scalar
kernel taking plain floats; :class:`Fluid` is the validated, user-facing
container that packs its values into a float64 array for those kernels
(:meth:`Fluid.kernel_params`, index order given by the ``FP_*`` constants).

=====================  ======================================================
name                   content
=====================  ======================================================
:class:`Fluid`         validated fluid properties, ``kernel_params()``
``FP_*``               index of each property in ``Fluid.kernel_params()``
:func:`bulk_modulus`   β(p) and dβ/dp, Eq. (23) of [1] smoothed + vapour floor
:func:`log_density`    ln(ρ(p)/ρ₀) = ∫ dp/β from p_atm, barotropic density
:func:`density_ratio`  ρ(p_up)/ρ(p_down)
=====================  ======================================================

All pressures are ABSOLUTE [Pa].

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", section 3.5, Eq. (23)
   (``/work/shared/paper/gerotor-micromotion-paper.md``).
.. [2] H. E. Merritt, *Hydraulic Control Systems*, Wiley, 1967, ch. 2
   (bulk modulus, effective bulk modulus of an oil with entrained gas).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.errors import InputError, check_range

__all__ = [
    "Fluid",
    "bulk_modulus",
    "log_density",
    "density_ratio",
    "FP_DENSITY",
    "FP_VISCOSITY",
    "FP_BULK_MODULUS",
    "FP_CAVITATION_RATIO",
    "FP_ATMOSPHERIC",
    "FP_VAPOUR",
    "FP_SWITCH_BAND",
    "N_FLUID_PARAMS",
    "LOG_DENSITY_FLOOR_S",
]

# --------------------------------------------------------------------------
# Index order of Fluid.kernel_params() (the order of the dataclass fields).
# --------------------------------------------------------------------------
FP_DENSITY = 0           #: ρ₀, density at p_atm [kg/m³]
FP_VISCOSITY = 1         #: μ, dynamic viscosity [Pa·s]
FP_BULK_MODULUS = 2      #: β*, bulk modulus of the liquid [Pa]
FP_CAVITATION_RATIO = 3  #: β*/β below atmospheric pressure [-] (1000 in [1])
FP_ATMOSPHERIC = 4       #: p_atm, switch pressure of Eq. (23), absolute [Pa]
FP_VAPOUR = 5            #: p_vap, vapour pressure, absolute [Pa]
FP_SWITCH_BAND = 6       #: width of the smoothed switch of Eq. (23) [Pa]
N_FLUID_PARAMS = 7       #: length of Fluid.kernel_params()

# --------------------------------------------------------------------------
# Numerical guards (kernels must never return NaN/inf for finite input).
# --------------------------------------------------------------------------
_BAND_MIN = 1e-6        # [Pa] smallest switch band used by the kernels
_FLOOR_WIDTH_MIN = 1e-6  # [Pa] smallest vapour-floor width used by the kernels
_S_MIN = 1e-300          # smallest normalised floor coordinate in log_density
_EXP_ARG_MAX = 700.0     # |exponent| cap in density_ratio (exp(709) overflows)

#: Sentinel-free floor of :func:`log_density`: at and below the vapour pressure
#: the kernel evaluates the floor-region closed form at s = 1e-300, i.e. it
#: returns a large negative but finite number (ln(1e-300) ≈ -690.8 times the
#: floor scale L/(2β*/ratio)).
LOG_DENSITY_FLOOR_S = _S_MIN

# Gauss–Legendre nodes/weights on [-1, 1] for the switch-band integral of
# log_density.  24 nodes in the sinh-mapped variable (see _band_integral) give
# a relative error below ~2e-13 for cavitation ratios up to 1e7.
_GL_N = 24
_GL_X, _GL_W = np.polynomial.legendre.leggauss(_GL_N)
_GL_X = np.ascontiguousarray(_GL_X, dtype=np.float64)
_GL_W = np.ascontiguousarray(_GL_W, dtype=np.float64)


# ==========================================================================
# User-facing container
# ==========================================================================
@dataclass(frozen=True)
class Fluid:
    """Validated properties of the working fluid (SI, absolute pressures).

    Parameters
    ----------
    density_kg_m3 : float
        Density ρ₀ at atmospheric pressure [kg/m³]. Default 870 (mineral oil).
    viscosity_pa_s : float
        Dynamic viscosity μ [Pa·s]. Default 0.0391 (ISO VG46 near 40 °C).
    bulk_modulus_pa : float
        Bulk modulus β* of the liquid above atmospheric pressure [Pa].
        Default 1.5e9.
    cavitation_ratio : float
        Factor by which β drops below atmospheric pressure, β*/β [-];
        1000 in Eq. (23) of [1]. Must be >= 1 (1 disables the switch).
    atmospheric_pa : float
        Pressure of the switch of Eq. (23) (relative pressure 0), absolute [Pa].
        Default 101325.
    vapour_pressure_pa : float
        Vapour pressure, absolute [Pa]; β → 0 there (vapour floor). Default 2000.
    switch_band_pa : float
        Width of the smoothed switch of Eq. (23) around ``atmospheric_pa`` [Pa].
        Default 5000.

    Raises
    ------
    InputError
        Naming ``fluid.<field>``, the value and the allowed range, if a value is
        not finite, out of range, or if the vapour floor would overlap the
        switch band (``vapour_pressure_pa`` must be below
        ``atmospheric_pa - switch_band_pa/2``).

    Examples
    --------
    >>> Fluid().kernel_params()[FP_BULK_MODULUS]
    1500000000.0
    """

    density_kg_m3: float = 870.0
    viscosity_pa_s: float = 0.0391
    bulk_modulus_pa: float = 1.5e9
    cavitation_ratio: float = 1000.0
    atmospheric_pa: float = 101325.0
    vapour_pressure_pa: float = 2000.0
    switch_band_pa: float = 5000.0

    def __post_init__(self) -> None:
        def put(name: str, value: float) -> None:
            object.__setattr__(self, name, value)

        put("density_kg_m3", check_range("fluid.density_kg_m3", self.density_kg_m3,
                                         0.0, 1e5, lo_open=True, unit="kg/m^3"))
        put("viscosity_pa_s", check_range("fluid.viscosity_pa_s", self.viscosity_pa_s,
                                          0.0, 1e3, lo_open=True, unit="Pa s"))
        put("bulk_modulus_pa", check_range("fluid.bulk_modulus_pa", self.bulk_modulus_pa,
                                           0.0, 1e13, lo_open=True, unit="Pa"))
        put("cavitation_ratio", check_range("fluid.cavitation_ratio", self.cavitation_ratio,
                                            1.0, 1e6))
        put("atmospheric_pa", check_range("fluid.atmospheric_pa", self.atmospheric_pa,
                                          0.0, 1e8, lo_open=True, unit="Pa"))
        put("switch_band_pa", check_range("fluid.switch_band_pa", self.switch_band_pa,
                                          0.0, 2.0 * self.atmospheric_pa, lo_open=True,
                                          hi_open=True, unit="Pa"))
        p_lo = self.atmospheric_pa - 0.5 * self.switch_band_pa
        v = check_range("fluid.vapour_pressure_pa", self.vapour_pressure_pa, 0.0, None,
                        unit="Pa")
        if not v < p_lo:
            raise InputError(
                "fluid.vapour_pressure_pa", self.vapour_pressure_pa, f"[0, {p_lo:g}) Pa",
                reason="the vapour floor must lie below the switch band "
                       "atmospheric_pa - switch_band_pa/2")
        put("vapour_pressure_pa", v)

    def kernel_params(self) -> np.ndarray:
        """Pack the properties for the numba kernels.

        Returns
        -------
        params : numpy.ndarray
            float64 array of length :data:`N_FLUID_PARAMS`; index with the
            ``FP_*`` constants (``FP_DENSITY``, ``FP_VISCOSITY``,
            ``FP_BULK_MODULUS``, ``FP_CAVITATION_RATIO``, ``FP_ATMOSPHERIC``,
            ``FP_VAPOUR``, ``FP_SWITCH_BAND``) [SI].
        """
        out = np.empty(N_FLUID_PARAMS, dtype=np.float64)
        out[FP_DENSITY] = self.density_kg_m3
        out[FP_VISCOSITY] = self.viscosity_pa_s
        out[FP_BULK_MODULUS] = self.bulk_modulus_pa
        out[FP_CAVITATION_RATIO] = self.cavitation_ratio
        out[FP_ATMOSPHERIC] = self.atmospheric_pa
        out[FP_VAPOUR] = self.vapour_pressure_pa
        out[FP_SWITCH_BAND] = self.switch_band_pa
        return out


# ==========================================================================
# Kernels
# ==========================================================================
@njit(inline="always")
def bulk_modulus(p, beta_star, ratio, p_atm, band, p_vap):
    r"""Bulk modulus β(p) of Eq. (23) of [1], C¹-smoothed, with a vapour floor.

    Parameters
    ----------
    p : float
        Absolute pressure [Pa].
    beta_star : float
        Bulk modulus of the liquid β* (above atmospheric pressure) [Pa].
    ratio : float
        Cavitation ratio β*/β below atmospheric pressure [-] (1000 in [1]).
    p_atm : float
        Atmospheric (switch) pressure, absolute [Pa].
    band : float
        Width of the smoothed switch [Pa].
    p_vap : float
        Vapour pressure, absolute [Pa].

    Returns
    -------
    beta : float
        Bulk modulus [Pa]; 0 at and below ``p_vap``.
    dbeta_dp : float
        Its derivative with respect to p [-] (Pa/Pa).

    Notes
    -----
    Eq. (23) of [1] is the step β = β* for p − p_atm ≥ 0 and β*/1000 below.
    It is smoothed with the cubic Hermite step over a band of width ``band``:

    .. math::
        x = \mathrm{clip}\left(\frac{p - p_{atm} + b/2}{b}, 0, 1\right),\quad
        w = 3x^2 - 2x^3,\quad
        \beta_{23} = \frac{\beta^*}{r} + \left(\beta^* - \frac{\beta^*}{r}\right) w

    so β₂₃ = β* above p_atm + b/2, β*/r below p_atm − b/2, and C¹ in between
    (dw/dx = 0 at both ends).

    Vapour floor (our addition, not in [1]): with p_lo = p_atm − b/2,

    .. math::
        s = \mathrm{clip}\left(\frac{p - p_{vap}}{p_{lo} - p_{vap}}, 0, 1\right),
        \quad \varphi = 1 - (1 - s)^2,\quad \beta = \beta_{23}\,\varphi

    φ = 1 (and dφ/dp = 0) at p_lo, so β stays C¹ there; below p_vap β = 0.
    Why: the chamber pressure obeys dp/dt = β/V·(ΣQ − dV/dt), and near
    p_vap β ≈ 2(β*/r)(p − p_vap)/(p_lo − p_vap), so p − p_vap decays at
    most exponentially and never crosses zero: the model can never predict a
    pressure below the vapour pressure however strong the suction.  β is only
    C⁰ at p_vap itself (dβ/dp jumps from 0 to 2β*/(r (p_lo − p_vap))).

    Validity: the caller (:class:`Fluid`) guarantees β* > 0, r ≥ 1, b > 0 and
    p_vap < p_atm − b/2; non-positive ``band`` or floor width are floored at
    1e-6 Pa so the kernel stays finite.

    References
    ----------
    .. [1] Eq. (23), section 3.5 of the paper (``gerotor-micromotion-paper.md``).
    .. [2] H. E. Merritt, *Hydraulic Control Systems*, Wiley, 1967, ch. 2 (bulk modulus).
    """
    bw = band if band > _BAND_MIN else _BAND_MIN
    r = ratio if ratio > 1.0 else 1.0
    beta_low = beta_star / r
    # --- smoothed switch of Eq. (23) ---
    x = (p - p_atm + 0.5 * bw) / bw
    if x <= 0.0:
        beta23 = beta_low
        dbeta23 = 0.0
    elif x >= 1.0:
        beta23 = beta_star
        dbeta23 = 0.0
    else:
        w = x * x * (3.0 - 2.0 * x)
        dw = 6.0 * x * (1.0 - x) / bw
        beta23 = beta_low + (beta_star - beta_low) * w
        dbeta23 = (beta_star - beta_low) * dw
    # --- vapour floor ---
    width = p_atm - 0.5 * bw - p_vap
    if width < _FLOOR_WIDTH_MIN:
        width = _FLOOR_WIDTH_MIN
    s = (p - p_vap) / width
    if s <= 0.0:
        return 0.0, 0.0
    if s >= 1.0:
        return beta23, dbeta23
    phi = s * (2.0 - s)
    dphi = 2.0 * (1.0 - s) / width
    return beta23 * phi, dbeta23 * phi + beta23 * dphi


@njit
def _band_integral(x, beta_star, ratio, bw):
    r"""∫ from x'=1/2 to x of b·dx'/β₂₃(x') [-] (x in [0, 1], the band coordinate).

    With K = r − 1, β₂₃ = (β*/r)(1 + K w(x)).  The integrand is a narrow
    Lorentzian-like peak of width ~1/√(3K) at x = 0 for large r, so the
    quadrature runs in u = asinh(k x), k = √(3K), where

    .. math::
        \frac{dx}{1 + K w(x)} = \frac{\cosh u\,du}{k\,(\cosh^2 u - \tfrac{2}{3k}\sinh^3 u)}

    is smooth (its nearest singularities are ~π/2 away in u).  For k ≤ 1 the
    integrand is smooth in x and Gauss–Legendre runs in x directly.
    """
    r = ratio if ratio > 1.0 else 1.0
    K = r - 1.0
    scale = bw * r / beta_star  # b / (β*/r)
    k = math.sqrt(3.0 * K)
    acc = 0.0
    if k > 1.0:
        ua = math.asinh(0.5 * k)
        ub = math.asinh(k * x)
        mid = 0.5 * (ua + ub)
        half = 0.5 * (ub - ua)
        c = 2.0 / (3.0 * k)
        for i in range(_GL_N):
            e = math.exp(mid + half * _GL_X[i])  # u ≤ asinh(k) < 710: no overflow
            ei = 1.0 / e
            sh = 0.5 * (e - ei)  # absolute error ~1e-16: harmless, sh enters as sh³
            ch = 0.5 * (e + ei)
            acc += _GL_W[i] * ch / (ch * ch - c * sh * sh * sh)
        return scale * half * acc / k
    mid = 0.5 * (0.5 + x)
    half = 0.5 * (x - 0.5)
    for i in range(_GL_N):
        t = mid + half * _GL_X[i]
        acc += _GL_W[i] / (1.0 + K * t * t * (3.0 - 2.0 * t))
    return scale * half * acc


@njit
def log_density(p, beta_star, ratio, p_atm, band, p_vap):
    r"""Logarithm of the barotropic density ratio, s = ln(ρ(p)/ρ₀) = ∫ dp'/β(p').

    Parameters
    ----------
    p : float
        Absolute pressure [Pa].
    beta_star : float
        Bulk modulus of the liquid β* [Pa].
    ratio : float
        Cavitation ratio β*/β below atmospheric pressure [-].
    p_atm : float
        Atmospheric (switch) pressure, absolute [Pa]; ρ(p_atm) = ρ₀.
    band : float
        Width of the smoothed switch [Pa].
    p_vap : float
        Vapour pressure, absolute [Pa].

    Returns
    -------
    s : float
        ln(ρ(p)/ρ₀) [-], with ds/dp = 1/β(p) (β of :func:`bulk_modulus`).

    Notes
    -----
    .. math::
        s(p) = \int_{p_{atm}}^{p} \frac{dp'}{\beta(p')},\qquad
        \rho(p) = \rho_0\, e^{s(p)},\qquad \frac{d\rho}{dp} = \frac{\rho}{\beta}

    is the density consistent with β(p) of :func:`bulk_modulus`
    (barotropic fluid, [2]).  By region, with p_lo,hi = p_atm ∓ b/2,
    L = p_lo − p_vap, β_l = β*/r:

    * p ≥ p_hi (β = β*): s = S_hi + (p − p_hi)/β*  (closed form);
    * p_lo ≤ p ≤ p_hi (switch band): fixed 24-node Gauss–Legendre quadrature of
      1/β₂₃ in the sinh-mapped band coordinate (precomputed nodes), relative
      error < 2e-13 for r ≤ 1e7;
    * p_vap < p < p_lo (vapour floor, β = β_l σ(2 − σ), σ = (p − p_vap)/L):
      partial fractions of 1/(σ(2 − σ)) give
      s = S_lo + L/(2β_l) · ln(σ/(2 − σ))  (closed form);
    * p ≤ p_vap: s → −∞ as p → p_vap⁺; the kernel returns the floor formula
      at σ = 1e-300 (:data:`LOG_DENSITY_FLOOR_S`), a large negative finite
      number, so that ρ → ~0 but nothing overflows.

    S_hi and S_lo are the band integrals at its ends, so s is continuous at
    p_lo and p_hi to round-off by construction.

    Cost: one 24-node quadrature per call in every region (the anchors S_lo,
    S_hi are recomputed, the kernel keeps no state), about 0.2 µs compiled.
    Only β (:func:`bulk_modulus`, ~10 ns) is needed by the pressure ODE.
    """
    bw = band if band > _BAND_MIN else _BAND_MIN
    p_lo = p_atm - 0.5 * bw
    p_hi = p_atm + 0.5 * bw
    if p >= p_hi:
        return _band_integral(1.0, beta_star, ratio, bw) + (p - p_hi) / beta_star
    if p >= p_lo:
        return _band_integral((p - p_lo) / bw, beta_star, ratio, bw)
    r = ratio if ratio > 1.0 else 1.0
    beta_low = beta_star / r
    width = p_lo - p_vap
    if width < _FLOOR_WIDTH_MIN:
        width = _FLOOR_WIDTH_MIN
    sig = (p - p_vap) / width
    if sig < _S_MIN:
        sig = _S_MIN
    s_lo = _band_integral(0.0, beta_star, ratio, bw)
    return s_lo + 0.5 * width / beta_low * math.log(sig / (2.0 - sig))


@njit
def density_ratio(p_up, p_down, beta_star, ratio, p_atm, band, p_vap):
    r"""Ratio of barotropic densities ρ(p_up)/ρ(p_down).

    Parameters
    ----------
    p_up : float
        Absolute pressure of the numerator state [Pa].
    p_down : float
        Absolute pressure of the denominator state [Pa].
    beta_star : float
        Bulk modulus of the liquid β* [Pa].
    ratio : float
        Cavitation ratio β*/β below atmospheric pressure [-].
    p_atm : float
        Atmospheric (switch) pressure, absolute [Pa].
    band : float
        Width of the smoothed switch [Pa].
    p_vap : float
        Vapour pressure, absolute [Pa].

    Returns
    -------
    ratio : float
        ρ(p_up)/ρ(p_down) [-].

    Notes
    -----
    .. math::
        \frac{\rho(p_{up})}{\rho(p_{down})} = \exp\left(s(p_{up}) - s(p_{down})\right)

    with s of :func:`log_density`.  The exponent is clipped to ±700 so the
    result is finite even when one pressure is at the vapour floor.
    """
    d = log_density(p_up, beta_star, ratio, p_atm, band, p_vap) - \
        log_density(p_down, beta_star, ratio, p_atm, band, p_vap)
    if d > _EXP_ARG_MAX:
        d = _EXP_ARG_MAX
    elif d < -_EXP_ARG_MAX:
        d = -_EXP_ARG_MAX
    return math.exp(d)
