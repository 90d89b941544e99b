r"""Sub-step control of the ROS2 stepper (:mod:`.kernel`): the error estimate, the error scale, the error weights, the
error norm and the step-size factor, each a few named lines.

A sub-step of size h is accepted when its error norm is at most 1,

.. math::
    \lVert e \rVert = \max_i |e_i|\, w_i,\qquad e = \tfrac12 h (k_1 + k_2)

(the difference between ROS2 and its embedded first-order solution y + h k₁ [2]), with per-volume weights
w_i (:func:`error_weights`) on the pressure scale Δp_ref (:func:`error_scale`, :func:`update_range`).  The
next sub-step is h times

.. math::
    \mathrm{fac} = \min\!\big(f_{max}, \max(f_{min},\ 0.9\,\lVert e \rVert^{-1/(\hat q + 1)})\big),\qquad \hat q = 1

the standard controller of [1] (II.4, eq. (4.13); IV.8 for Rosenbrock methods): the embedded solution's
local error is O(h^{q̂+1}).  Why the scale and the weights are what they are: docs/numerics.md ("The sub-step
error scale", "Closing ports").

Across a closing port that holds its chamber stiff (:func:`port_filtered`) the embedded estimate is blind: both
of its solutions are filtered by W = I − γhJ at the sub-step's start, where the port is still open, while the
chamber's quasi-equilibrium runs away as the area goes to zero.  There an accepted sub-step is checked once more
by its defect at the new state (:func:`defect_error`, [3]), filtered by each volume's stiffness *there*.

References
----------
.. [1] E. Hairer, S.P. Nørsett, G. Wanner, *Solving Ordinary Differential Equations I*, 2nd ed., Springer
   1993, sec. II.4 (automatic step size control); E. Hairer, G. Wanner, *Solving Ordinary Differential
   Equations II*, 2nd ed., Springer 1996, sec. IV.8.
.. [2] J.G. Verwer, E.J. Spee, J.G. Blom, W. Hundsdorfer, "A second-order Rosenbrock method applied to
   photochemical dispersion problems", SIAM J. Sci. Comput. 20 (1999) 1456–1480.
.. [3] W.H. Enright, "A new error-control for initial value solvers", Appl. Math. Comput. 31 (1989) 288–301
   (the defect of a continuous extension as the error control); [1] II, sec. IV.7 for ROS2's extension.
"""
from __future__ import annotations

import math

from .._jit import njit
from ..hydraulics.orifice import port_orifice_flow
from .flows import G_AD, G_AS, G_DAD, G_DAS, G_V, time_to_close
from .params import CT_DEFECT_H, CT_RANGE, ERROR_PRESSURE

__all__ = ["SAFETY", "FACTOR_MIN", "FACTOR_MAX", "OPENED_WINDOW", "error_scale", "update_range", "port_event",
           "error_weights", "embedded_error", "error_norm", "step_factor", "defect_threshold", "port_filtered",
           "defect_error", "GAMMA", "B1_END", "B2_END"]

SAFETY = 0.9        #: on the factor that would put the next error norm at exactly 1 [1, eq. (4.13)]
FACTOR_MIN = 0.2    #: smallest factor per sub-step; also after a non-finite error norm [-]
FACTOR_MAX = 4.0    #: largest factor per sub-step [-]
_TINY_NORM = 1e-8   #: below this the error norm says nothing about the step: grow by FACTOR_MAX
OPENED_WINDOW = 0.125  #: a delivery port counts as just opened within this share of the closing horizon [-] (one
                       #: output step of the stepper's eight, ``kernel.CLOSING_HORIZON``)
GAMMA = 1.0 + 1.0 / math.sqrt(2.0)             #: ROS2's γ [2]
#: ROS2's continuous extension y(t + sh) = y + h(b₁(s)k₁ + b₂(s)k₂), b₂(s) = (s²/2 − γs)/(1 − 2γ), b₁ = s + b₂
#: ([1] II, IV.7; ``kernel._track_peak``), differentiated at s = 1: its rate at the sub-step's end is
#: B1_END·k₁ + B2_END·k₂
B2_END = (1.0 - GAMMA) / (1.0 - 2.0 * GAMMA)
B1_END = 1.0 + B2_END


@njit(inline="always")
def error_scale(op, ws):
    """Δp_ref [Pa], the pressure scale of the sub-step error: the larger of ``op.dp_ref`` (p_d − p_s, at least
    1 bar) and the chamber pressures' recent range ``ws.ctrl[CT_RANGE]`` (:func:`update_range`)."""
    return max(op.dp_ref, ws.ctrl[CT_RANGE])


@njit
def update_range(ctrl, pres, n, fade):
    r"""The chamber pressures' recent range after an output step, into ``ctrl[CT_RANGE]`` [Pa].

    .. math:: R_k = \max\left(R_{k-1} f,\; \max_i p_i - \min_i p_i\right),
              \qquad f = e^{-\omega h / 2\pi}

    over the n chambers: p_i their pressures at the step's end (``pres``, the output samples); f fades the
    range by 1/e per revolution.  At every instant some chamber is near suction pressure and, once a
    revolution, one at its spike, so R is about the waveform's range over the last revolution: the scale the
    error budget is stated on (docs/numerics.md).  The samples miss up to ≈ 3 % of a spike's top between them;
    counting the peaks between samples was measured and is not used (docs/numerics.md, "The sub-step error
    scale").  Updated per output step, not per call, so a run split into calls at step boundaries is the run
    in one call.
    """
    hi = -math.inf
    lo = math.inf
    for i in range(n):
        hi = max(hi, pres[i])
        lo = min(lo, pres[i])
    ctrl[CT_RANGE] = max(ctrl[CT_RANGE] * fade, hi - lo)


@njit(inline="always")
def port_event(area, slope, omega, horizon):
    """True if a chamber's delivery port, open area [m²] changing at ``slope`` [m²/rad], closes within
    ``horizon`` [s] at ω = ``omega`` [rad/s], or opened within :data:`OPENED_WINDOW` of it (its age: the time to
    close backwards in time): the events the embedded error estimate under-reads (:func:`error_weights`)."""
    return (time_to_close(area, slope, omega, horizon) > 0.0
            or time_to_close(area, -slope, omega, OPENED_WINDOW * horizon) > 0.0)


@njit(inline="always")
def error_weights(km, op, ws, horizon):
    """Per-volume weights ``ws.wt`` [-] of :func:`error_norm`, at the first stage of a sub-step.

    Pressure measure: w_i = β_i / (tol·Δp_ref) (:func:`error_scale`), at least 1/``log_density_tolerance``.  A
    chamber whose delivery port closes within ``horizon`` [s] or has just opened (:func:`port_event`, from the
    first stage's port areas and slopes in ``ws.geo``) is held to ``closing_tolerance``·tol and weighed with
    max(β_i, β(p_d)): an error δ in its ln ρ, made while it is still near suction pressure where β_i is small,
    becomes a pressure error β(p_d)·δ once the delivery kidney has filled it (a just-opened chamber at 1 bar:
    β_i ≈ 0.1 GPa against 1.5 GPa).  A chamber whose suction port closes within ``horizon`` is weighed with
    max(β_i, β(p_d)) for the same reason (it is sealed next and then filled to delivery pressure: the mass it
    holds when it is sealed sets when its pressure rises), at tol.  Log-density measure: w_i = 1/tol.  The
    delivered-volume quadrature (imposed delivery pressure) has weight 0.
    """
    pc = km.pc
    for i in range(pc.n + 1):
        if i == pc.n and not pc.restriction:
            ws.wt[i] = 0.0                                          # the delivered-volume quadrature
        elif pc.error_measure == ERROR_PRESSURE:                   # dp = β dy, relative to Δp; mass where β is small
            tol = pc.tolerance
            beta = ws.beta[i]
            if i < pc.n and port_event(ws.geo[i, G_AD], ws.geo[i, G_DAD], op.omega, horizon):
                tol *= pc.closing_tolerance                        # the spikes (docs/numerics.md)
                beta = max(beta, op.beta_d)                        # its error, once at delivery pressure
            elif i < pc.n and time_to_close(ws.geo[i, G_AS], ws.geo[i, G_DAS], op.omega, horizon) > 0.0:
                beta = max(beta, op.beta_d)                        # sealed next, then filled to p_d
            ws.wt[i] = max(beta / (tol * error_scale(op, ws)), 1.0 / pc.log_density_tolerance)
        else:
            ws.wt[i] = 1.0 / pc.tolerance


@njit(inline="always")
def embedded_error(h, k1, k2, err):
    r"""The local error estimate of a ROS2 sub-step of h [s] with stages ``k1``, ``k2`` [1/s] into ``err`` [-]:

    .. math:: e = y_{n+1} - \hat y_{n+1} = \tfrac12 h (k_1 + k_2),\qquad
              y_{n+1} = y_n + \tfrac32 h k_1 + \tfrac12 h k_2,\quad \hat y_{n+1} = y_n + h k_1

    ROS2 against its embedded first-order solution [2]; it estimates the first-order solution's error
    (O(h²)), hence the exponent 1/(q̂ + 1) = 1/2 of :func:`step_factor`, and the second-order solution is
    propagated (local extrapolation).
    """
    for i in range(err.shape[0]):
        err[i] = 0.5 * h * (k1[i] + k2[i])


@njit(inline="always")
def error_norm(err, wt):
    """‖err‖ = max_i |err_i| w_i [-]; NaN if any term is NaN (a non-finite estimate is never accepted)."""
    en = 0.0
    for i in range(err.shape[0]):
        v = abs(err[i]) * wt[i]
        if not (v <= en):          # also catches NaN
            en = v
    return en


@njit(inline="always")
def step_factor(en):
    """The factor [-] on the sub-step just tried (accepted or not) for the next one, from its error norm ``en``:
    SAFETY·en^(−1/2) within [FACTOR_MIN, FACTOR_MAX] [1]; FACTOR_MIN if ``en`` is not finite (an overflow in the
    stages: shrink), FACTOR_MAX if it is below 1e-8."""
    if not math.isfinite(en):
        return FACTOR_MIN
    if en < _TINY_NORM:
        return FACTOR_MAX
    return min(FACTOR_MAX, max(FACTOR_MIN, SAFETY / math.sqrt(en)))


@njit(inline="always")
def _filter_threshold(pc, omega, dp, area, slope, beta, volume, big_h):
    r"""The smallest sub-step [s] over which one port needs the defect check, or ∞: a port of open ``area`` [m²]
    falling at ``slope`` [m²/rad] closes in t_c (:func:`.flows.time_to_close`), so its area halves within a
    sub-step of h > t_c/2; its conductance holds its chamber (bulk modulus ``beta`` [Pa], ``volume`` [m³]) stiff on
    the scale of h where γh·|∂Q/∂Δp|·β/V > 1, ``dp`` [Pa] the difference across it.  ∞ where t_c ≥ 2·``big_h``:
    no sub-step is longer than the output step ``big_h`` [s] (and the orifice law is not evaluated)."""
    tc = time_to_close(area, slope, omega, 2.0 * big_h)
    if tc <= 0.0:
        return math.inf
    _q, dq = port_orifice_flow(dp, area, pc.orifice_law, pc.cd_max, pc.lambda_crit, pc.laminar_delta, pc.density,
                               pc.viscosity)                                # Eq. (21)
    rate = abs(dq) * beta / volume
    return max(0.5 * tc, 1.0 / (GAMMA * rate)) if rate > 0.0 else math.inf


@njit(inline="always")
def defect_threshold(km, op, ws, big_h):
    r"""At the first stage of a sub-step: into ``ws.ctrl[CT_DEFECT_H]`` the sub-step [s] above which the step needs
    the defect check (:func:`port_filtered`): the smallest over the chambers' suction and delivery ports of
    :func:`_filter_threshold`, from the first stage's pressures, bulk moduli and port geometry in ``ws``; ``big_h``
    [s]: the output step, the longest sub-step.  ∞ with the log-density measure (the references): its
    tolerance resolves the closing ports by itself.

    The embedded estimate filters both of its solutions by W = I − γhJ of the start, where that port's
    conductance dominates the chamber's row; as the area falls the chamber's quasi-equilibrium moves like
    1/A², which the filtered stages do not see (docs/numerics.md, "The defect check across a closing port").
    """
    pc = km.pc
    n = pc.n
    h_check = math.inf
    for j in range(n if pc.error_measure == ERROR_PRESSURE else 0):
        v = ws.geo[j, G_V]
        h_check = min(h_check,
                      _filter_threshold(pc, op.omega, op.p_s - ws.p[j], ws.geo[j, G_AS], ws.geo[j, G_DAS],
                                        ws.beta[j], v, big_h),
                      _filter_threshold(pc, op.omega, ws.p[n] - ws.p[j], ws.geo[j, G_AD], ws.geo[j, G_DAD],
                                        ws.beta[j], v, big_h))
    ws.ctrl[CT_DEFECT_H] = h_check


@njit(inline="always")
def port_filtered(ws, h):
    """True if the sub-step of h [s] about to be taken needs the defect check (:func:`defect_error`): a port's area
    halves within it while the port holds its chamber stiff on its scale (:func:`defect_threshold`)."""
    return h > ws.ctrl[CT_DEFECT_H]


@njit(inline="always")
def defect_error(h, f_end, k1, k2, jac, err):
    r"""The error of a ROS2 sub-step of h [s] from its defect at the new state, into ``err`` [-]:

    .. math::
        e_i = \frac{h\,\big(f_i(y_{n+1}, t + h) - b_1'(1)\,k_{1,i} - b_2'(1)\,k_{2,i}\big)}
                   {1 + \gamma h \max(0, -J_{ii}(y_{n+1}, t + h))}

    ``f_end``: the right-hand side at the new state [1/s]; ``jac``: its Jacobian there (diagonal only used);
    ``k1``, ``k2``: the sub-step's stages [1/s].  The numerator is the defect of the continuous extension
    (B1_END, B2_END: its rate at the end against the equation's) over the sub-step [3]; the denominator
    filters it as the stepper would, one volume at a time, with the stiffness at the new state: a volume that
    relaxes fast carries its defect as d/(γ|J_ii|), a slow one as h·d.  For a smooth solution the defect is
    O(h²), so e is O(h³), below the embedded estimate; across a closing port it reads the lag that the start's
    filter hid.
    """
    for i in range(err.shape[0]):
        d = f_end[i] - B1_END * k1[i] - B2_END * k2[i]
        err[i] = h * d / (1.0 + GAMMA * h * max(0.0, -jac[i, i]))

