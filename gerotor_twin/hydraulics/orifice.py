"""Orifice flow between a chamber and a port: Eq. (21) of [1] with Cd(λ).

Eq. (21) of [1] is the turbulent orifice law with a discharge coefficient that
"depends on the Reynolds number".  Here Cd follows the flow-number law of the
AMESim hydraulic library [2] (also MapleSim's Orifice [3]), which goes from
laminar (Q ∝ Δp) at small flow number to turbulent (Q ∝ √Δp) at large flow
number.  Its laminar limit removes the infinite slope dQ/dΔp of the pure
turbulent law at Δp = 0, which is what the stiff implicit integrator needs
(DESIGN "Numerics": regularize the orifice near Δp = 0 through Cd(Re)).

============================  =================================================
name                          content
============================  =================================================
:func:`discharge_coefficient` Cd = Cd_max·tanh(2λ/λ_crit)
:func:`orifice_flow`          (Q, dQ/dΔp) of Eq. (21) of [1] with Cd(λ)
============================  =================================================

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", section 3, Eq. (21)
   (``/work/shared/paper/gerotor-micromotion-paper.md``).
.. [2] Siemens Simcenter Amesim (formerly LMS Imagine.Lab AMESim), Hydraulic
   library: flow coefficient as a function of the flow number,
   C_q = C_q,max·tanh(2λ/λ_crit), λ = D_h·√(2|Δp|/ρ)/ν; the law used in the
   AMESim-based pump and valve models of M. Borghi, M. Milani and co-workers.
.. [3] Maplesoft, MapleSim Hydraulics Library, *Orifice* (parameters
   ``Cdmax`` and ``Critno``, the critical flow number), online help.
.. [4] H. E. Merritt, *Hydraulic Control Systems*, Wiley, 1967, ch. 3
   (orifice flow, laminar and turbulent regimes).
"""
from __future__ import annotations

import math

from gerotor_twin._jit import njit

__all__ = ["discharge_coefficient", "orifice_flow", "ORIFICE_SERIES_SWITCH"]

#: Below this value of z = 2λ/λ_crit the derivative uses the Taylor series of
#: tanh(z)/z + sech²(z) instead of the direct formula (0/0 at z = 0).  The
#: series truncated after z⁶ has a relative error below 1e-22 there, so the
#: switch is continuous to round-off.
ORIFICE_SERIES_SWITCH = 1e-3

# Floors for ρ, μ, λ_crit: the caller guarantees positive values; the floors
# only keep the kernel finite (no NaN/inf) if it does not.
_RHO_MIN = 1e-6          # [kg/m³]
_MU_MIN = 1e-12          # [Pa·s]
_LAMBDA_CRIT_MIN = 1e-6  # [-]


@njit
def discharge_coefficient(flow_number, cd_max, lambda_crit):
    r"""Discharge coefficient as a function of the flow number.

    Parameters
    ----------
    flow_number : float
        Flow number λ = D_h √(2|Δp|/ρ) / ν [-] (≥ 0; its absolute value is used).
    cd_max : float
        Turbulent (large-λ) discharge coefficient Cd_max [-]; typically 0.6–0.7
        for sharp-edged orifices [4].
    lambda_crit : float
        Critical flow number λ_crit of the laminar→turbulent transition [-];
        λ_crit ≈ 1000 is the usual AMESim value [2]. Non-positive values mean
        "always turbulent" (Cd = Cd_max).

    Returns
    -------
    cd : float
        Discharge coefficient [-].

    Notes
    -----
    Flow-number law of [2], [3]:

    .. math::
        C_d(\lambda) = C_{d,max} \tanh\left(\frac{2\lambda}{\lambda_{crit}}\right)

    C_d ≈ 2 C_{d,max} λ/λ_crit for λ ≪ λ_crit (laminar: Q ∝ Δp),
    C_d(λ_crit) = tanh(2) C_{d,max} ≈ 0.964 C_{d,max}, and C_d → C_{d,max} for
    λ ≫ λ_crit (turbulent).  The flow number is a Reynolds number built on the
    hydraulic diameter and the ideal jet velocity √(2|Δp|/ρ).

    Examples
    --------
    >>> round(discharge_coefficient(1000.0, 0.7, 1000.0), 6)
    0.674827
    """
    if not lambda_crit > 0.0:
        return cd_max
    return cd_max * math.tanh(2.0 * abs(flow_number) / lambda_crit)


@njit(inline="always")
def orifice_flow(dp, area, cd_max, lambda_crit, rho, mu):
    r"""Flow through an orifice, Eq. (21) of [1], with Cd(λ) and its derivative.

    Parameters
    ----------
    dp : float
        Pressure difference Δp = p_a − p_b [Pa].
    area : float
        Orifice (open port) area A [m²]; A ≤ 0 means closed.
    cd_max : float
        Turbulent discharge coefficient Cd_max [-].
    lambda_crit : float
        Critical flow number λ_crit [-] (≈ 1000 [2]); must be > 0.
    rho : float
        Fluid density ρ [kg/m³]; must be > 0.
    mu : float
        Dynamic viscosity μ [Pa·s]; must be > 0.

    Returns
    -------
    q : float
        Volume flow Q from side a to side b [m³/s] (positive when Δp > 0).
    dq_ddp : float
        Analytic derivative dQ/dΔp [m³/(s·Pa)] (≥ 0, finite at Δp = 0).

    Notes
    -----
    Eq. (21) of [1] with the flow-number discharge coefficient of [2]:

    .. math::
        Q = \mathrm{sign}(\Delta p)\, C_d(\lambda)\, A \sqrt{\frac{2|\Delta p|}{\rho}},
        \quad \lambda = \frac{D_h}{\nu}\sqrt{\frac{2|\Delta p|}{\rho}},
        \quad D_h = \sqrt{\frac{4A}{\pi}},\quad \nu = \frac{\mu}{\rho}

    With v = √(2|Δp|/ρ), a = 2 D_h/(ν λ_crit) and z = a v (= 2λ/λ_crit),
    Q = sign(Δp) C_{d,max} A v tanh(z) and

    .. math::
        \frac{dQ}{d\Delta p} = \frac{a\, C_{d,max} A}{\rho}
        \left(\frac{\tanh z}{z} + \mathrm{sech}^2 z\right)

    which tends to the laminar value 2 a C_{d,max} A/ρ as Δp → 0 (there
    Q ≈ 2 a C_{d,max} A Δp/ρ) and to the turbulent C_{d,max} A/(ρ v) for
    z ≫ 1.  For z < :data:`ORIFICE_SERIES_SWITCH` the bracket is evaluated
    with its Taylor series 2 − 4z²/3 + 4z⁴/5 − 136z⁶/315 (no 0/0).

    Validity: incompressible, quasi-steady orifice; A ≤ 0 returns (0, 0).
    The caller guarantees ρ, μ, λ_crit > 0 (floored at 1e-6 kg/m³, 1e-12 Pa·s
    and 1e-6 otherwise, only so that the result stays finite).  Q is odd and dQ/dΔp even in Δp.
    """
    if not area > 0.0:
        return 0.0, 0.0
    r = rho if rho > _RHO_MIN else _RHO_MIN
    m = mu if mu > _MU_MIN else _MU_MIN
    lc = lambda_crit if lambda_crit > _LAMBDA_CRIT_MIN else _LAMBDA_CRIT_MIN
    adp = abs(dp)
    d_h = math.sqrt(4.0 * area / math.pi)
    a = 2.0 * d_h * r / (m * lc)          # = 2 D_h / (ν λ_crit)  [s/m]
    v = math.sqrt(2.0 * adp / r)           # ideal jet velocity [m/s]
    z = a * v                              # = 2 λ / λ_crit [-]
    em = math.expm1(-2.0 * z)              # z ≥ 0: no overflow; one call gives tanh and sech²
    e = 1.0 + em
    t = -em / (2.0 + em)                   # tanh z = (1 − e)/(1 + e), no cancellation
    if z < ORIFICE_SERIES_SWITCH:
        z2 = z * z
        bracket = 2.0 + z2 * (-4.0 / 3.0 + z2 * (4.0 / 5.0 - z2 * (136.0 / 315.0)))
    else:
        sech2 = 4.0 * e / ((1.0 + e) * (1.0 + e))
        bracket = t / z + sech2
    q = cd_max * area * v * t
    if dp < 0.0:
        q = -q
    return q, a * cd_max * area / r * bracket
