r"""Barotropic mixture of oil, free (entrained) air and vapour: ρ(p), β(p), p(s).

Replaces the step of Eq. (23) of the paper by a physical model in the same
role as :mod:`gerotor_twin.hydraulics.fluid`: the state of every volume
stays s = ln(ρ/ρ_ref) of the MIXTURE (mass balance exact), and s(p), β(p) =
dp/ds are closed forms; p(s) is a safeguarded Newton iteration on the closed
form (vectorised builder for the kernel's Hermite tables).

The model (per unit mixture volume at the reference pressure p₀):

* liquid, constant isothermal bulk modulus β_L:
  V_L = (1 − α₀) exp(−(p − p₀)/β_L);
* free air in small bubbles, polytropic with index n, sharing each bubble with
  saturated vapour (Dalton: p = p_gas + p_vap, surface tension neglected):
  V_G = α₀ ((p₀ − p_vap)/(p − p_vap))^{1/n};
* the vapour's mass is neglected (at 2 kPa an oil vapour of M ≈ 300 g/mol has
  ρ_v ≈ 0.2 kg/m³, ~3·10⁻⁴ of the oil's: negligible while cavities hold less than
  a few % of the volume), so the mixture mass is that of oil + air and
  ρ ∝ 1/(V_L + V_G).

Hence, with ρ_ref the mixture density at p₀,

.. math::
    s(p) = -\ln\left[(1-\alpha_0)\,e^{-(p-p_0)/\beta_L}
           + \alpha_0\left(\frac{p_0 - p_{vap}}{p - p_{vap}}\right)^{1/n}\right]

    \frac{1}{\beta(p)} = \frac{ds}{dp} = \frac{w_L}{\beta_L} + \frac{w_G}{n\,(p - p_{vap})},
    \qquad w_L = \frac{V_L}{V_L+V_G},\ w_G = \frac{V_G}{V_L+V_G}

As p → p_vap⁺ the bubbles grow without bound (vapour cavitation): s → −∞ and
β ≈ n(p − p_vap) → 0, so a chamber pressure obeying dp/dt = β/V(ΣQ − dV/dt)
can approach p_vap but never cross it, and p(s) > p_vap for every finite s.
For p ≫ p_vap with α₀ → 0, β → β_L and ρ → ρ_L e^{(p−p₀)/β_L} (pure liquid).
With p_vap = 0 and V_L ≈ 1 − α₀ this is exactly the entrained-air bulk
modulus of Simscape's Hydraulic Fluid block [1] (α = V_G/V_L) and of its
isothermal-liquid "entrained air" model [2] with constant bulk modulus.

Dissolved air (Henry's law) is LEFT OUT, on purpose:

* equilibrium release would let the whole dissolved content (for mineral oils
  of the order of 8–10 % by volume at 1 atm) come out of solution as soon as
  p drops below saturation, which greatly overstates the aeration seen in
  pumps: release and re-absorption are diffusion-limited, with time constants
  (tens of ms to seconds) far longer than the few ms a chamber spends at low
  pressure [3], [4];
* modelling the kinetics needs a second state per volume (free-air mass), the
  kernel carries only ln ρ.  The gaseous-cavitation models of the Multics /
  HYGESim family [4], [5] do carry released air with a time constant; adding it here
  is possible later without changing s(p) of the free phase.

The free-air content α₀ therefore stands for all undissolved air at p₀,
including what the suction line has already released.

Parameters a user sets (:class:`Mixture`): air fraction α₀ at p₀ (default
1e-3 = 0.1 %: a flooded suction from a settled reservoir; 0.5 % is Simscape's
default [2]; entrained air of hydraulic oils in service is typically 0.1–1 %
[3], [5]); vapour pressure p_vap (default 2000 Pa, the value of
:class:`~gerotor_twin.hydraulics.fluid.Fluid`); polytropic index n (default 1,
isothermal: bubbles of ≲ 50 µm exchange heat with the oil in ≲ 0.1 ms, well
below the ~ms compression of a chamber; 1.4 for adiabatic compression of large
bubbles); liquid bulk modulus β_L (from :class:`~gerotor_twin.hydraulics.oil.OilProperties`
at the oil temperature, :meth:`Mixture.from_oil`).

=============================  ==========================================================
name                           content
=============================  ==========================================================
:class:`Mixture`               validated parameters, ``log_density``, ``bulk_modulus``,
                               ``pressure``, ``density``, ``kernel_args()``
:func:`mixture_log_density`    s(p), closed form (numba scalar kernel)
:func:`mixture_bulk_modulus`   (β, dβ/dp), closed form (numba scalar kernel)
:func:`mixture_pressure`       p(s), safeguarded Newton (numba scalar kernel)
:func:`mixture_pressure_array` p(s) over an array
:func:`mixture_table`          (p, dp/ds) at nodes in s: a Hermite table's data
=============================  ==========================================================

Kernel argument order (all floats, SI, absolute pressures)::

    (beta_l, alpha0, n, p_vap, p0) = Mixture.kernel_args()

References
----------
.. [1] MathWorks, Simscape Fluids, *Hydraulic Fluid* block (Hydraulics
   (Isothermal) library): mixture bulk modulus
   E = E_l (1 + α(p_a/(p_a+p))^{1/n}) / (1 + α p_a^{1/n} E_l/(n (p_a+p)^{(n+1)/n})),
   https://mathworks.com/help/releases/R2021a/physmod/hydro/ref/hydraulicfluid.html
.. [2] MathWorks, Simscape, *Isothermal Liquid Properties (IL)* block and the
   isothermal liquid domain (parameters air_fraction = 0.005,
   polytropic_index = 1, p_min), "Isothermal Liquid Modeling Options",
   https://www.mathworks.com/help/simscape/ref/isothermalliquidpropertiesil.html
.. [3] H. Gholizadeh, R. Burton, G. Schoenau, "Fluid bulk modulus: a literature
   survey", Int. J. Fluid Power 12(3), 2011, pp. 5–15 (effective bulk modulus
   of oil with entrained air; dissolved vs entrained air).
.. [4] P. Casoli, A. Vacca, G. Franzoni, G. L. Berta, "Modelling of fluid
   properties in hydraulic positive displacement machines", Simulation
   Modelling Practice and Theory 14(8), 2006, pp. 1059–1072.
.. [5] M. Rundo, "Models for flow rate simulation in gear pumps: a review",
   Energies 10(9), 1261, 2017 (fluid models with entrained air and cavitation
   in lumped-parameter gear/gerotor pump models).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.errors import check_range
from gerotor_twin.units import P_ATM

__all__ = [
    "Mixture",
    "AirContent",
    "mixture_log_density",
    "mixture_bulk_modulus",
    "mixture_pressure",
    "mixture_pressure_array",
    "mixture_table",
    "S_CLIP",
    "FLOOR_LOG_GAP",
]

#: |s| above this is clipped by :func:`mixture_pressure` so that p stays finite
#: for every allowed parameter set (e^x with x ≤ ln(1e7) + 1.4·400 < 709) [-].
S_CLIP = 400.0
#: Floor of ln((p − p_vap)/(p₀ − p_vap)) in :func:`mixture_log_density`: at and
#: below p_vap it returns the finite value at p − p_vap = (p₀ − p_vap)·e^−690.
FLOOR_LOG_GAP = -690.0
_NEWTON_MAX = 100
_NEWTON_TOL = 1e-14   # on x = ln(p − p_vap): relative tolerance on p − p_vap
_F_TOL = 1e-10        # |ln V − ln V*| needed as well (guards against a stalled step)


@njit(inline="always")
def _log_volumes(x, beta_l, alpha0, n, p_vap, p0):
    """(ln V_L, ln V_G) at p = p_vap + e^x (per unit mixture volume at p0)."""
    p = p_vap + math.exp(x)
    ln_l = math.log1p(-alpha0) - (p - p0) / beta_l
    ln_g = math.log(alpha0) + (math.log(p0 - p_vap) - x) / n
    return ln_l, ln_g


@njit(inline="always")
def _log_sum(a, b):
    """ln(e^a + e^b) without overflow."""
    if a > b:
        return a + math.log1p(math.exp(b - a))
    return b + math.log1p(math.exp(a - b))


@njit(inline="always")
def _log1mexp(e):
    """ln(1 − e^e) for e < 0, accurate at both ends (Mächler's log1mexp)."""
    if e > -0.6931471805599453:
        return math.log(-math.expm1(e))
    return math.log1p(-math.exp(e))


@njit(inline="always")
def _gap_log(p, p_vap, p0):
    """x = ln(p − p_vap), floored at ln(p0 − p_vap) + FLOOR_LOG_GAP."""
    x_min = math.log(p0 - p_vap) + FLOOR_LOG_GAP
    d = p - p_vap
    if d <= 0.0:
        return x_min
    x = math.log(d)
    return x if x > x_min else x_min


@njit
def mixture_log_density(p, beta_l, alpha0, n, p_vap, p0):
    r"""s(p) = ln(ρ(p)/ρ_ref) of the oil–air–vapour mixture (closed form).

    Parameters
    ----------
    p : float
        Absolute pressure [Pa].
    beta_l : float
        Isothermal bulk modulus of the air-free liquid β_L [Pa].
    alpha0 : float
        Volume fraction of free air in the mixture at p₀, α₀ [-] (0 < α₀ < 1).
    n : float
        Polytropic index of the air [-].
    p_vap : float
        Vapour pressure, absolute [Pa] (< p₀).
    p0 : float
        Reference pressure of α₀ and ρ_ref, absolute [Pa].

    Returns
    -------
    s : float
        ln(ρ/ρ_ref) [-]; s(p₀) = 0, ds/dp = 1/β(p).

    Notes
    -----
    .. math::
        s = -\ln\left[(1-\alpha_0)e^{-(p-p_0)/\beta_L}
            + \alpha_0\left(\frac{p_0-p_{vap}}{p-p_{vap}}\right)^{1/n}\right]

    evaluated as a log-sum-exp (no overflow).  At and below p_vap (s → −∞)
    it returns the finite value at p − p_vap = (p₀ − p_vap)e^{−690}.
    """
    ln_l, ln_g = _log_volumes(_gap_log(p, p_vap, p0), beta_l, alpha0, n, p_vap, p0)
    if p > p_vap:   # the liquid term at the true p (p_vap + e^x loses digits for large p)
        ln_l = math.log1p(-alpha0) - (p - p0) / beta_l
    return -_log_sum(ln_l, ln_g)


@njit
def mixture_bulk_modulus(p, beta_l, alpha0, n, p_vap, p0):
    r"""Effective bulk modulus β(p) = dp/ds of the mixture and dβ/dp (closed form).

    Parameters
    ----------
    p : float
        Absolute pressure [Pa].
    beta_l, alpha0, n, p_vap, p0 : float
        As in :func:`mixture_log_density` [Pa, -, -, Pa, Pa].

    Returns
    -------
    beta : float
        Effective isothermal bulk modulus [Pa]; 0 at and below p_vap.
    dbeta_dp : float
        dβ/dp [-]; 0 at and below p_vap (→ n from above).

    Notes
    -----
    With Δ = p − p_vap, q = nΔ and the volume fractions w_L, w_G at p:

    .. math::
        \beta = \frac{q\,\beta_L}{w_L q + w_G \beta_L},\qquad
        \frac{d\beta}{dp} = w_L\left(\frac{\beta}{\beta_L}\right)^2
            + w_G (1+n)\left(\frac{\beta}{q}\right)^2 - 1

    (from 1/β = −d ln V/dp and dβ/dp = V''/(V c²) − 1, c = 1/β).  Limits:
    pure liquid β = β_L, dβ/dp = 0; pure gas β = nΔ, dβ/dp = n.
    """
    if not p > p_vap:
        return 0.0, 0.0
    d = p - p_vap
    ln_l = math.log1p(-alpha0) - (p - p0) / beta_l
    ln_g = math.log(alpha0) + (math.log(p0 - p_vap) - math.log(d)) / n
    t = ln_l - ln_g
    if t > 0.0:
        e = math.exp(-t)
        w_l = 1.0 / (1.0 + e)
        w_g = e / (1.0 + e)
    else:
        e = math.exp(t)
        w_g = 1.0 / (1.0 + e)
        w_l = e / (1.0 + e)
    q = n * d
    u = q / beta_l
    den = w_l * u + w_g         # > 0: w_l + w_g = 1, u > 0
    r_l = u / den               # β/β_L, with w_l·r_l ≤ 1
    r_g = 1.0 / den             # β/q,   with w_g·r_g ≤ 1
    return q * r_g, (w_l * r_l) * r_l + (w_g * r_g) * (1.0 + n) * r_g - 1.0


@njit(inline="always")
def _newton_step(x, s, ln_l, ln_g, beta_l, alpha0, n, p_vap, p0):
    """One Newton step for p(s), in the form that is exact when one phase is rigid.

    Where the bubbles set the compressibility (c_G = w_G/(nΔ) ≥ c_L = w_L/β_L)
    it solves x = φ(x) = ln(p0 − p_vap) + n(ln α0 − ln(V* − V_L(x))) (exact for
    a rigid liquid), else p = ψ(p) = p0 − β_L ln((V* − V_G(p))/(1 − α0)) (exact
    without gas); Newton on x − φ, resp. p − ψ.  Returns +inf when the update is
    undefined (V* below one term), which the caller replaces by bisection.
    """
    d = math.exp(x)
    e = ln_l + s                                                  # ln(V_L/V*)
    om = -math.expm1(e) if e < 0.0 else 0.0                       # 1 − V_L/V*
    # gas form if the bubbles set the compressibility and V* − V_L is not lost
    # to cancellation (at x_lo of a liquid-rich state V_L = V* exactly)
    if om > 1e-8 and math.exp(ln_g) * beta_l >= math.exp(ln_l) * n * d:
        r = math.exp(e) / om                                      # V_L/(V* − V_L)
        phi = math.log(p0 - p_vap) + n * (math.log(alpha0) + s - _log1mexp(e))
        dphi = -n * d / beta_l * r
        return x - (x - phi) / (1.0 - dphi)
    e = ln_g + s                                                  # ln(V_G/V*)
    om = -math.expm1(e) if e < 0.0 else 0.0                       # 1 − V_G/V*
    if om <= 0.0:
        return math.inf
    q = math.exp(e) / om                                          # V_G/(V* − V_G)
    p = p_vap + d
    psi = p0 - beta_l * (-s + _log1mexp(e) - math.log1p(-alpha0))
    dpsi = -beta_l / (n * d) * q
    d_new = p - (p - psi) / (1.0 - dpsi) - p_vap
    return math.log(d_new) if d_new > 0.0 else math.inf


@njit
def mixture_pressure(s, beta_l, alpha0, n, p_vap, p0):
    r"""Absolute pressure p(s) [Pa], the inverse of :func:`mixture_log_density`.

    Parameters
    ----------
    s : float
        ln(ρ/ρ_ref) [-]; clipped to ±:data:`S_CLIP` (NaN gives p_vap).
    beta_l, alpha0, n, p_vap, p0 : float
        As in :func:`mixture_log_density` [Pa, -, -, Pa, Pa].

    Returns
    -------
    p : float
        Absolute pressure [Pa], ≥ p_vap always.

    Notes
    -----
    Solves ln V(p) + s = 0 (V* = e^{−s}) kept inside a bracket in
    x = ln(p − p_vap), bisecting when a step leaves it.  The step
    (:func:`_newton_step`) is Newton on the fixed-point form that is exact when
    one phase is rigid: for x where the bubbles set the compressibility, for p
    where the liquid does.  With V* = e^{−s}, the liquid
    and gas terms alone give the bracket: at the pressure where one term
    equals V* the volume is ≥ V* (lower bound); where both are ≤ V*/2 it is
    ≤ V* (upper bound):

    .. math::
        x_{lo} = \max\left(\ln(p_L - p_{vap}),\ \ln(p_0 - p_{vap}) + n(\ln\alpha_0 + s)\right),\
        p_L = p_0 + \beta_L(s + \ln(1-\alpha_0))

    and the same with α₀ → 2α₀, (1 − α₀) → 2(1 − α₀) for x_hi; the iteration
    starts at x_lo.  Stops when |Δx| < 1e-14 (p − p_vap to ~1e-14 relative),
    typically in 3–6 iterations (≈ 0.2–0.4 µs compiled); at most 100.
    """
    if s != s:                    # NaN
        return p_vap
    if s > S_CLIP:
        s = S_CLIP
    elif s < -S_CLIP:
        s = -S_CLIP
    lg0 = math.log(p0 - p_vap)
    ln1a = math.log1p(-alpha0)
    x_lo = lg0 + n * (math.log(alpha0) + s)
    x_hi = lg0 + n * (math.log(2.0 * alpha0) + s)
    d_l = p0 + beta_l * (s + ln1a) - p_vap
    if d_l > 0.0:
        x_lo = max(x_lo, math.log(d_l))
    d_l2 = p0 + beta_l * (s + ln1a + math.log(2.0)) - p_vap
    if d_l2 > 0.0:
        x_hi = max(x_hi, math.log(d_l2))
    x = x_lo                      # f(x_lo) >= 0
    for _ in range(_NEWTON_MAX):
        ln_l, ln_g = _log_volumes(x, beta_l, alpha0, n, p_vap, p0)
        f = _log_sum(ln_l, ln_g) + s      # ln V(x) − ln V*, decreasing in x
        if f == 0.0:
            break
        if f > 0.0:
            x_lo = x
        else:
            x_hi = x
        x_new = _newton_step(x, s, ln_l, ln_g, beta_l, alpha0, n, p_vap, p0)
        if abs(x_new - x) <= _NEWTON_TOL * max(1.0, abs(x)) and abs(f) < _F_TOL:
            x = x_new             # converged (a step this small may land on the bracket)
            break
        if not (x_lo < x_new < x_hi):
            x_new = 0.5 * (x_lo + x_hi)
        x = x_new
    return p_vap + math.exp(x)


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def mixture_pressure_array(s, beta_l, alpha0, n, p_vap, p0):
    """p(s) [Pa] for every element of a 1-D float64 array ``s`` [-]."""
    out = np.empty(s.shape[0])
    for i in range(s.shape[0]):
        out[i] = mixture_pressure(s[i], beta_l, alpha0, n, p_vap, p0)
    return out


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def mixture_table(s_nodes, beta_l, alpha0, n, p_vap, p0):
    r"""Nodes of a cubic Hermite table of p(s): pressures and slopes dp/ds = β.

    Parameters
    ----------
    s_nodes : numpy.ndarray
        1-D float64 array of ln(ρ/ρ_ref) nodes [-].
    beta_l, alpha0, n, p_vap, p0 : float
        As in :func:`mixture_log_density` [Pa, -, -, Pa, Pa].

    Returns
    -------
    p : numpy.ndarray
        p(s) at the nodes [Pa].
    dp_ds : numpy.ndarray
        β(p(s)) at the nodes [Pa] (the exact slope of p(s)).

    Notes
    -----
    Interpolation error of a table UNIFORM in s over [s(p_lo), s(350 bar)]
    (default mixture, measured): 2048 nodes give 4e-3 Pa (1e-8 relative) for
    p_lo = 1e4 Pa, but 320 Pa for p_lo = 2100 Pa: near p_vap s spans many
    units for a few Pa, so below ~1e4 Pa call :func:`mixture_pressure` instead
    (≈ 0.3 µs) or place the nodes non-uniformly.
    """
    p = mixture_pressure_array(s_nodes, beta_l, alpha0, n, p_vap, p0)
    dp = np.empty(p.shape[0])
    for i in range(p.shape[0]):
        dp[i] = mixture_bulk_modulus(p[i], beta_l, alpha0, n, p_vap, p0)[0]
    return p, dp


# ==========================================================================
# User-facing containers
# ==========================================================================
@dataclass(frozen=True)
class AirContent:
    """The mixture parameters a user sets besides the oil (config section ``mixture``).

    Parameters
    ----------
    air_fraction : float
        Free (undissolved) air volume fraction at atmospheric pressure α₀ [-],
        in [1e-12, 0.5]. Default 1e-3 (0.1 %, see the module docstring).
    polytropic_index : float
        Polytropic index n of the air [-], in [1, 1.4]. Default 1 (isothermal).

    The vapour pressure is the fluid's (``fluid.vapour_pressure_pa``), β_L and ρ
    the oil's at its temperature.
    """

    air_fraction: float = 1e-3
    polytropic_index: float = 1.0

    def __post_init__(self) -> None:
        object.__setattr__(self, "air_fraction", check_range("mixture.air_fraction", self.air_fraction,
                                                             1e-12, 0.5))
        object.__setattr__(self, "polytropic_index", check_range("mixture.polytropic_index",
                                                                 self.polytropic_index, 1.0, 1.4))


@dataclass(frozen=True)
class Mixture:
    r"""Validated parameters of the oil–air–vapour mixture (SI, absolute pressures).

    Parameters
    ----------
    bulk_modulus_liquid_pa : float
        Isothermal bulk modulus of the air-free oil β_L [Pa]. Default 1.5e9.
    air_fraction : float
        Volume fraction of free air in the mixture at ``reference_pressure_pa``,
        α₀ [-], in [1e-12, 0.5]. Default 1e-3 (0.1 %). Use 1e-9 or less for a
        practically air-free oil (α₀ = 0 would remove the vapour floor).
    polytropic_index : float
        Polytropic index n of the air [-], in [1, 1.4]. Default 1 (isothermal).
    vapour_pressure_pa : float
        Vapour pressure, absolute [Pa], in [0, reference_pressure_pa/2].
        Default 2000.
    reference_pressure_pa : float
        Pressure p₀ at which α₀ and ρ_ref are given, absolute [Pa]. Default 101325.
    density_liquid_kg_m3 : float
        Density of the air-free oil at p₀ [kg/m³]. Default 870.
    density_gas_kg_m3 : float
        Density of the free air at p₀ [kg/m³]. Default 1.2 (≈ 20 °C).

    Raises
    ------
    InputError
        Naming ``mixture.<field>``, the value and the allowed range.

    Notes
    -----
    Equations and validity: see the module docstring.  Validity: quasi-static
    bubbles (no inertia, no surface tension, no dissolution), one temperature
    for oil and air, pressures up to a few hundred bar (constant β_L).
    """

    bulk_modulus_liquid_pa: float = 1.5e9
    air_fraction: float = 1e-3
    polytropic_index: float = 1.0
    vapour_pressure_pa: float = 2000.0
    reference_pressure_pa: float = P_ATM
    density_liquid_kg_m3: float = 870.0
    density_gas_kg_m3: float = 1.2

    def __post_init__(self) -> None:
        def put(name, lo, hi, unit=""):
            object.__setattr__(self, name, check_range(f"mixture.{name}", getattr(self, name),
                                                       lo, hi, unit=unit))

        put("bulk_modulus_liquid_pa", 1e7, 1e11, "Pa")
        put("air_fraction", 1e-12, 0.5)
        put("polytropic_index", 1.0, 1.4)
        put("reference_pressure_pa", 1e3, 1e7, "Pa")
        put("vapour_pressure_pa", 0.0, 0.5 * self.reference_pressure_pa, "Pa")
        put("density_liquid_kg_m3", 100.0, 5000.0, "kg/m^3")
        put("density_gas_kg_m3", 0.0, 100.0, "kg/m^3")

    @classmethod
    def from_oil(cls, oil, temperature_k: float, **kwargs) -> "Mixture":
        """Mixture with β_L and ρ_L of an :class:`~gerotor_twin.hydraulics.oil.OilProperties` at T [K].

        The free-air density at p₀ follows the ideal gas, ρ_g = (p₀ − p_vap)/(R T),
        R = 287.05 J/(kg·K); ``**kwargs`` set the other fields.
        """
        kwargs.setdefault("bulk_modulus_liquid_pa", oil.bulk_modulus(temperature_k))
        kwargs.setdefault("density_liquid_kg_m3", oil.density(temperature_k))
        p0 = kwargs.get("reference_pressure_pa", P_ATM)
        pv = kwargs.get("vapour_pressure_pa", 2000.0)
        kwargs.setdefault("density_gas_kg_m3", (p0 - pv) / (287.05 * temperature_k))
        return cls(**kwargs)

    def kernel_args(self) -> tuple[float, float, float, float, float]:
        """(β_L [Pa], α₀ [-], n [-], p_vap [Pa], p₀ [Pa]), the kernels' argument order."""
        return (self.bulk_modulus_liquid_pa, self.air_fraction, self.polytropic_index,
                self.vapour_pressure_pa, self.reference_pressure_pa)

    @property
    def reference_density_kg_m3(self) -> float:
        """Mixture density at p₀, ρ_ref = (1 − α₀)ρ_L + α₀ρ_g [kg/m³]."""
        a = self.air_fraction
        return (1.0 - a) * self.density_liquid_kg_m3 + a * self.density_gas_kg_m3

    def log_density(self, p):
        """s(p) = ln(ρ/ρ_ref) [-] for a float or array of absolute pressures [Pa]."""
        return _vectorise(mixture_log_density, p, self.kernel_args())

    def bulk_modulus(self, p):
        """Effective bulk modulus β(p) [Pa] for a float or array of pressures [Pa]."""
        return _vectorise(lambda *a: mixture_bulk_modulus(*a)[0], p, self.kernel_args())

    def density(self, p):
        """Mixture density ρ(p) = ρ_ref e^{s(p)} [kg/m³]."""
        return self.reference_density_kg_m3 * np.exp(self.log_density(p))

    def pressure(self, s):
        """Absolute pressure p(s) [Pa] (≥ p_vap) for a float or array of s [-]."""
        arr = np.asarray(s, dtype=np.float64)
        out = mixture_pressure_array(np.ascontiguousarray(arr.ravel()), *self.kernel_args())
        return float(out[0]) if arr.ndim == 0 else out.reshape(arr.shape)

    def air_volume_fraction(self, p):
        """Volume fraction of free air (+ vapour) w_G(p) in the mixture [-]."""
        a, n, pv, p0 = self.air_fraction, self.polytropic_index, self.vapour_pressure_pa, \
            self.reference_pressure_pa
        p = np.asarray(p, dtype=np.float64)
        with np.errstate(divide="ignore"):
            ln_g = np.log(a) + (np.log(p0 - pv) - np.log(np.maximum(p - pv, 0.0))) / n
        ln_l = np.log1p(-a) - (p - p0) / self.bulk_modulus_liquid_pa
        w = 1.0 / (1.0 + np.exp(np.clip(ln_l - ln_g, -700.0, 700.0)))
        return float(w) if w.ndim == 0 else w


def _vectorise(fn, p, args):
    arr = np.asarray(p, dtype=np.float64)
    if arr.ndim == 0:
        return float(fn(float(arr), *args))
    return np.array([fn(float(v), *args) for v in arr.ravel()]).reshape(arr.shape)

