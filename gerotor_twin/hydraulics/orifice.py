"""Orifice flow between a chamber and a port: Eq. (21) of [1] with Cd(λ).

Eq. (21) of [1] is the turbulent orifice law with a discharge coefficient that
"depends on the Reynolds number".  Two such laws are here, both going from laminar
(Q ∝ Δp) at small Reynolds or flow number to turbulent (Q ∝ √Δp) at large: Merritt's
laminar and turbulent orifice laws in series [4] (the default), and the flow-number law
of the AMESim hydraulic library [2] (also MapleSim's Orifice [3]).  The laminar limit
removes the infinite slope dQ/dΔp of the pure turbulent law at Δp = 0, which is what
the stiff implicit integrator needs (DESIGN "Numerics": regularize the orifice near
Δp = 0 through Cd(Re)).

============================  =================================================
name                          content
============================  =================================================
:func:`laminar_turbulent_flow` (Q, dQ/dΔp), Merritt's laws in series [4] (default)
:func:`discharge_coefficient` Cd = Cd_max·tanh(2λ/λ_crit)
:func:`orifice_flow`          (Q, dQ/dΔp) of Eq. (21) of [1] with Cd(λ)
:func:`port_orifice_flow`     the configured law, as the kernel calls it
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
.. [4] H. E. Merritt, *Hydraulic Control Systems*, Wiley, 1967, sec. 3.3–3.4
   (orifice flow: turbulent Cd = π/(π+2) ≈ 0.611 for a sharp edge; at low Reynolds
   number Cd = δ√Re, δ ≈ 0.2 from Wuest's data, i.e. the laminar law
   Q = 2δ²D_h A Δp/μ; the two meet at Re_t = (Cd/δ)²).

:func:`laminar_turbulent_flow` (config ``orifice.law: merritt``, the default) puts the two
regimes of [4] in series, Δp = Q/G_lam + Q²/K_turb², so that Q follows Merritt's laminar law for
Re ≪ Re_t and his turbulent law for Re ≫ Re_t with a smooth, finite dQ/dΔp.
``orifice.law: flow_number`` is the flow-number law; the paper's commands use it, because the
clearances of tables 3–5 were calibrated with it (:func:`gerotor_twin.paper.setting.paper_setting`).
What could be checked of its sources (issue 13): MapleSim's *Orifice* [3] documents a tanh law in
the flow number with the parameters Cdmax and Critno (its rendered formula reads as tanh(λ/Critno),
without the factor 2 used here; the AMESim form 2λ/λ_crit [2] is as recalled, not re-checked), and
a public HYGESim-style gear-machine code sets λ_crit = 1000, Cq,max = 0.7.  Merritt's law is the
one with published constants (tests: ``test/test_hydraulics_orifice_merritt.py``); it became the
default once the default numerics kept the error budget with it at every point of the accuracy
grid (docs/numerics.md, docs/paper.md "Orifice law").
"""
from __future__ import annotations

import math

from gerotor_twin._jit import njit

__all__ = ["discharge_coefficient", "orifice_flow", "ORIFICE_SERIES_SWITCH", "laminar_turbulent_flow",
           "port_orifice_flow", "LAW_FLOW_NUMBER", "LAW_MERRITT", "ORIFICE_LAWS", "MERRITT_TURBULENT_CD",
           "WUEST_LAMINAR_DELTA"]

#: Orifice laws by name (config ``orifice.law``) and their kernel codes.
LAW_FLOW_NUMBER, LAW_MERRITT = 0, 1
ORIFICE_LAWS = {"flow_number": LAW_FLOW_NUMBER, "merritt": LAW_MERRITT}
#: Turbulent discharge coefficient of a sharp-edged orifice, π/(π + 2) (free-streamline theory, [4]).
MERRITT_TURBULENT_CD = math.pi / (math.pi + 2.0)
#: Laminar flow coefficient δ of a sharp-edged circular orifice (Wuest's data, quoted by [4]): Cd = δ√Re.
WUEST_LAMINAR_DELTA = 0.2

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


@njit(inline="always")
def laminar_turbulent_flow(dp, area, cd, delta, rho, mu):
    r"""Orifice flow with Merritt's laminar and turbulent laws in series [4].

    Parameters
    ----------
    dp : float
        Pressure difference Δp = p_a − p_b [Pa].
    area : float
        Orifice area A [m²]; A ≤ 0 means closed.
    cd : float
        Turbulent discharge coefficient [-] (0.611 for a sharp edge [4]; 0.7 in config/pump.yaml).
    delta : float
        Laminar flow coefficient δ [-] (0.2 for a sharp-edged circular orifice [4]).
    rho, mu : float
        Density [kg/m³] and dynamic viscosity [Pa·s] (> 0; floored like :func:`orifice_flow`).

    Returns
    -------
    q : float
        Volume flow from a to b [m³/s].
    dq_ddp : float
        dQ/dΔp [m³/(s·Pa)] (finite, = G_lam at Δp = 0).

    Notes
    -----
    With D_h = √(4A/π), G = 2δ²D_h A/μ (laminar, Q = GΔp) and K = Cd A √(2/ρ) (turbulent,
    Q = K√Δp), the series law Δp = Q/G + Q²/K² gives

    .. math::
        Q = \frac{2|\Delta p|}{1/G + s},\qquad
        \frac{dQ}{d\Delta p} = \frac{1}{1/G + 2Q/K^2} = \frac{1}{s},\qquad
        s = \sqrt{1/G^2 + 4|\Delta p|/K^2}

    (2Q/K² = s − 1/G, since (s − 1/G)(s + 1/G) = 4|Δp|/K²: one division less).

    Its discharge coefficient Q/(A√(2Δp/ρ)) tends to δ√Re (Re on the mean orifice
    velocity) for Re ≪ Re_t = (Cd/δ)² and to Cd for Re ≫ Re_t.
    """
    if not area > 0.0:
        return 0.0, 0.0
    r = rho if rho > _RHO_MIN else _RHO_MIN
    m = mu if mu > _MU_MIN else _MU_MIN
    inv_a = 1.0 / area
    inv_g = m * inv_a * math.sqrt(0.25 * math.pi * inv_a) * (0.5 / (delta * delta))   # 1/G, 1/D_h = √(π/4A)
    inv_k2 = r * inv_a * inv_a * (0.5 / (cd * cd))                                     # 1/K²
    adp = abs(dp)
    s = math.sqrt(inv_g * inv_g + 4.0 * adp * inv_k2)
    q = 2.0 * adp / (inv_g + s)
    return (q if dp >= 0.0 else -q), 1.0 / s


@njit(forceinline=True)     # five sites in the stepper: compiled once, inlined by LLVM
def port_orifice_flow(dp, area, law, cd, lambda_crit, delta, rho, mu):
    """Eq. (21) of [1] with the configured law: ``LAW_MERRITT`` or ``LAW_FLOW_NUMBER``; (Q, dQ/dΔp)."""
    if law == LAW_MERRITT:
        return laminar_turbulent_flow(dp, area, cd, delta, rho, mu)
    return orifice_flow(dp, area, cd, lambda_crit, rho, mu)
