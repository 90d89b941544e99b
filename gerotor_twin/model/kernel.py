r"""Compiled stepper of the pump model: ROS2 sub-steps, outer-gear Heun step, output steps.

The right-hand side lives in :mod:`.flows`, the overlap check in :mod:`.contact`,
the outer-gear load in :mod:`.loads`, the data model in :mod:`.params`.

Integrator: Verwer's two-stage Rosenbrock method ROS2 (γ = 1 + 1/√2),
L-stable and second order for any approximation W of the Jacobian [2], with
adaptive sub-steps inside a fixed output step in shaft angle.  The right-hand
side depends on time through the shaft angle, so the stages carry ∂f/∂t [3]:

.. math::
    (I - γhJ)k_1 = f(t_n, y_n) + γh f_t,\qquad
    (I - γhJ)k_2 = f(t_n + h, y_n + hk_1) - 2k_1 - γh f_t,\qquad
    y_{n+1} = y_n + \tfrac32 h k_1 + \tfrac12 h k_2

Without f_t a stiff chamber on a moving quasi-equilibrium (an opening or
closing port) lags it by ≈ 0.71 of its movement per sub-step (docs/numerics.md).
A port that closes during the sub-step would, linearised, keep closing through
zero area: its share of f_t is scaled by min(1, t_c/h), t_c its time to close
(:func:`.flows.closing_ports`).  A chamber whose delivery port closes within eight output
steps (or opened within the last one) has its error tolerance multiplied by
``numerics.closing_tolerance``: the pressure spike of the throttled, compressed
chamber forms there (and that of a chamber refilled from the delivery kidney), and
the embedded error estimate under-reads it (docs/numerics.md).  The error of a
sub-step is the difference to the embedded first-order solution, measured on
the pressure relative to Δp_ref, the larger of p_delivery − p_suction and the range of
the chamber pressures over about the last revolution (highest − lowest sample, updated
every output step: :func:`update_range`, carried in :attr:`.records.PumpState.pressure_range`),
at least 1 bar (or on ln ρ,
``numerics.error_measure``).  The range is the scale of the waveform the budget is
stated on: at a low delivery pressure a trapped chamber's spike makes it many times
p_delivery − p_suction, and an error measured against the small difference spends
sub-steps on accuracy nobody can see.  The first stage of a sub-step reuses the
right-hand side and Jacobian evaluated at the end of the previous output step
(and after a rejected sub-step).  The outer gear moves inside the stages: its
velocity (mobility method compiled in; Method 1 and FDM set up from Python),
linearised in the load over the output step, squeezes the chambers, and its
Jacobian is part of W (:mod:`.gear_coupling`); the gear is placed at the end of
the step where ∫ė dt takes it.  With ``numerics.gear_coupling: partitioned`` it
is moved after each output step by Heun's method on the bearing model, with the
load from the new pressures (the squeeze of that move is spread over the next
step: :mod:`.volumes`).

Nothing here allocates: every scratch array lives in the model's
:class:`~.params.Workspace`.

References
----------
.. [1] The paper (``../shared/paper``).
.. [2] J.G. Verwer, E.J. Spee, J.G. Blom, W. Hundsdorfer, "A second-order
   Rosenbrock method applied to photochemical dispersion problems",
   SIAM J. Sci. Comput. 20 (1999) 1456–1480.
.. [3] E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*,
   2nd ed., Springer 1996, sec. IV.7 (Rosenbrock methods, non-autonomous form).
.. [4] Ibid., sec. IV.7, "Dense output" (continuous extensions of Rosenbrock methods).
"""
from __future__ import annotations

import math

from .._jit import njit
from ..bearing.mobility import mobility_kernel
from ..hydraulics.state_equation import pressure_of
from .contact import contact
from .flows import closing_ports, closing_share, rhs
from .gear_coupling import (GC_CON, GC_CX, GC_CY, GC_DEX, GC_DEY, GC_GXX, GC_GXY, GC_GYX, GC_GYY, GC_ON, GC_PAIR,
                            GC_PEND, close_pending, gear_move, keep_first_stage, linearise_mobility, linearise_short,
                            linearise_with, substep_rates)
from .loads import outer_gear_load
from .params import (CT_BOUND, CT_CLOSING, CT_CMAT_END, CT_FRESH, CT_GEO_OK, CT_PENDING, CT_RANGE, CT_STATUS, CT_SUBSTEP,  # noqa: F401
                     FL_DELIVERY, FL_RESTRICTION, FRESH_IN_F0, FRESH_IN_F1, FRESH_NONE)
from .step_control import (B1_END, B2_END, GAMMA, defect_error, defect_threshold, embedded_error, error_norm,
                           error_weights, port_filtered, step_factor, update_range)
from .tooth_constraint import pull_back_along
from .volumes import move_volumes

# ------------------------------------------------------------------ outputs
# per-step record columns besides the chamber pressures and gaps (the gaps have their own record)
R_T, R_THETA, R_QDEL, R_QSUC, R_QSD, R_QDR, R_QREST, R_PD, R_EX, R_EY, R_FX, R_FY, R_GAMMA, R_KC = range(14)
N_REC = 14

# counters
C_STEPS, C_CAVITATION, C_CONTACT_UNLOADED, C_HOUSING_CONTACT, C_GEAR_CONTACT, C_SUBSTEPS, C_REJECTED, \
    C_FAILED, C_ABANDONED = range(9)
N_COUNTERS = 9

#: :func:`pressure_step`'s status: the output step done, or abandoned (a non-finite sub-step, or the attempts spent:
#: ``numerics.max_substep_attempts`` in ``Workspace.ctrl[CT_BOUND]``, the bound on one call's work per output step).
STEP_DONE, STEP_NONFINITE, STEP_WORK_BOUND = 0, 1, 2

# how the outer gear moves in integrate()
MOVE_FIXED, MOVE_MOBILITY, MOVE_EXTERNAL = 0, 1, 2

_DENSE_W = 1.0 / (1.0 - 2.0 * GAMMA)     # ROS2's continuous extension (_track_peak)
#: output steps ahead in which a closing port is treated as closing (its ∂f/∂t share, its tolerance)
CLOSING_HORIZON = 8.0


# ------------------------------------------------------------ linear algebra
@njit(inline="always")
def lu_factor(a, piv):
    """In-place LU with partial pivoting of the small dense matrix ``a`` (Doolittle); the diagonal keeps 1/u_kk,
    so that :func:`lu_solve` multiplies where it would divide (a division's latency, ≈ 13 cycles, sits on the back
    substitution's critical path, twice per sub-step)."""
    n = a.shape[0]
    for k in range(n):
        m = k
        for i in range(k + 1, n):
            if abs(a[i, k]) > abs(a[m, k]):
                m = i
        piv[k] = m
        if m != k:
            for j in range(n):
                a[k, j], a[m, j] = a[m, j], a[k, j]
        inv = 1.0 / a[k, k]
        a[k, k] = inv
        for i in range(k + 1, n):
            a[i, k] *= inv
            lik = a[i, k]
            if lik != 0.0:
                for j in range(k + 1, n):
                    a[i, j] -= lik * a[k, j]


@njit(inline="always")
def lu_solve(a, piv, b, x):
    """Solve (LU) x = b with the factors of :func:`lu_factor` (its diagonal 1/u_kk; x may alias b)."""
    n = a.shape[0]
    for i in range(n):
        x[i] = b[i]
    for k in range(n):
        m = piv[k]
        if m != k:
            x[k], x[m] = x[m], x[k]
    for j in range(n):              # forward, by columns: each x_i −= l_ij x_j in the order j = 0, 1, … (the row
        xj = x[j]                   # sum's order, to the bit), the rows' updates independent of one another
        for i in range(j + 1, n):
            x[i] -= a[i, j] * xj
    for i in range(n - 1, -1, -1):
        s = x[i]
        for j in range(i + 1, n):
            s -= a[i, j] * x[j]
        x[i] = s * a[i, i]


# ------------------------------------------------------------------ stepping
@njit(inline="always")
def _track_peak(y, h, n, ws):
    r"""Raise ``ws.peak`` to the max of each chamber's ln ρ over the accepted sub-step of h [s] that ended at y.

    ROS2's continuous extension [4] (second order, like the step; it does not overshoot a stiff
    chamber's relaxation, where a Hermite cubic through the end rates does) is a parabola in the
    stages ``ws.k1``, ``ws.k2`` of the sub-step:

    .. math::
        y(t_n + sh) = y_n + h\left[b_1(s) k_1 + b_2(s) k_2\right],\qquad
        b_2(s) = \frac{s^2/2 - \gamma s}{1 - 2\gamma},\quad b_1(s) = s + b_2(s)

    (:math:`b_1(1) = 3/2`, :math:`b_2(1) = 1/2`: the step itself); its maximum inside the sub-step,
    if any, and the end y are the candidates.  The sub-steps resolve a pressure spike that the
    output grid samples only at its angles.  Limit: for a stiff chamber that follows a moving
    quasi-equilibrium the extension is convex under a concave top, so such a top is seen only
    through the sub-step ends (docs/numerics.md, "Accuracy of the defaults").
    """
    for i in range(n):
        if y[i] > ws.peak[i]:
            ws.peak[i] = y[i]
        if ws.k1[i] + ws.k2[i] > 0.0:                          # concave: w < 0
            u = h * ws.k1[i]
            w = h * (ws.k1[i] + ws.k2[i]) * _DENSE_W            # y(sh) = y_n + s(u − γw) + s²w/2
            s = GAMMA - u / w
            if 0.0 < s < 1.0:
                m = y[i] - 1.5 * u - 0.5 * h * ws.k2[i] + s * (u - GAMMA * w) + 0.5 * s * s * w
                if m > ws.peak[i]:
                    ws.peak[i] = m


@njit(forceinline=True)     # inlined by LLVM at its three sites, compiled once by numba (docs/performance.md)
def _first_stage(y, th, km, op, ws, integrals, big_h):
    """RHS and Jacobian at (y, θ, ``ws.gaps0``) into ``ws.f0``/``ws.jac``; flow integrals closed.

    The flows here are those at the end of the last accepted sub-step: its trapezoid
    (``ws.flows_prev`` at its start, these at its end) is added to ``integrals`` now,
    so ∫ flow dt uses the flows of the accepted states, at no extra RHS; and its
    chamber peaks are tracked (:func:`_track_peak`).  Where the defect check evaluated the RHS and Jacobian at this
    state already (``ws.ctrl[CT_FRESH]`` = ``FRESH_IN_F1``: a sub-step it accepted inside the output step, so the
    gaps, the gear's coupling and the displaced volumes are those it saw) they are taken from ``ws.f1`` and
    ``ws.jac_end``.
    """
    if ws.ctrl[CT_FRESH] == FRESH_IN_F1:
        n1 = ws.f0.shape[0]
        for i in range(n1):
            ws.f0[i] = ws.f1[i]
            for k in range(n1 + 1):                 # ∂f/∂y and ∂f/∂t: what flows.rhs writes
                ws.jac[i, k] = ws.jac_end[i, k]
    else:
        rhs(y, th, ws.gaps0, km, op, ws, ws.f0, ws.jac, bool(True))   # bool(): not a literal (flows.rhs, Notes)
    if ws.gear[GC_ON] != 0.0:
        close_pending(ws.gear)                      # ∫ė dt of the last accepted sub-step (gear_coupling)
        keep_first_stage(ws.gear)
    ws.ctrl[CT_CLOSING] = closing_ports(km.pc, op, ws.p, ws.rho, ws.geo, ws.jac, CLOSING_HORIZON * big_h)
    error_weights(km, op, ws, CLOSING_HORIZON * big_h)
    defect_threshold(km, op, ws, big_h)
    h = ws.ctrl[CT_PENDING]
    if h > 0.0:
        _track_peak(y, h, km.pc.n, ws)
    for i in range(ws.flows.shape[0]):
        if h > 0.0 and i != FL_DELIVERY:          # the delivered volume: integrate's, from the stages
            integrals[i] += 0.5 * h * (ws.flows_prev[i] + ws.flows[i])
        ws.flows_prev[i] = ws.flows[i]
    ws.ctrl[CT_PENDING] = 0.0
    ws.ctrl[CT_FRESH] = FRESH_IN_F0


@njit(inline="always")
def ros2_step(y, th2, h, km, op, ws):
    """One ROS2 sub-step of size h [s] from (y, θ) to θ₂ = ``th2`` = θ + ωh [rad]: ``ws.ynew`` and the embedded
    error ``ws.err``.

    ``ws.f0``/``ws.jac`` must hold the RHS, ∂f/∂y and (from column N+1 on, :func:`.flows.closing_ports`)
    ∂f/∂t at (y, θ, ``ws.gaps0``) (:func:`pressure_step` evaluates the first stage before it sizes the
    sub-step); the second stage is at θ₂ with ``ws.gaps1`` (θ₂ passed, not summed here: the next first stage is at
    the same angle to the bit, and reads the tables' values there from ``ws.geo``, :func:`.flows.chamber_geometry`).
    """
    n1 = y.shape[0]
    for i in range(n1):
        for k in range(n1):
            ws.lu[i, k] = -GAMMA * h * ws.jac[i, k]
        ws.lu[i, i] += 1.0
    lu_factor(ws.lu, ws.piv)
    gh = GAMMA * h
    if ws.ctrl[CT_CLOSING] > 0.0:                          # ∂f/∂t for this h (ws.err is free until the end)
        closing_share(km.pc.n, h, ws.jac, ws.err)
    else:
        for i in range(n1):
            ws.err[i] = ws.jac[i, n1]
    for i in range(n1):
        ws.k1[i] = ws.f0[i] + gh * ws.err[i]               # non-autonomous ROS2: + γh ∂f/∂t
    lu_solve(ws.lu, ws.piv, ws.k1, ws.k1)
    for i in range(n1):
        ws.y1[i] = y[i] + h * ws.k1[i]
    rhs(ws.y1, th2, ws.gaps1, km, op, ws, ws.f1, ws.jac, bool(False))
    for i in range(n1):
        ws.f1[i] -= 2.0 * ws.k1[i] + gh * ws.err[i]
    lu_solve(ws.lu, ws.piv, ws.f1, ws.k2)
    for i in range(n1):
        ws.ynew[i] = y[i] + 1.5 * h * ws.k1[i] + 0.5 * h * ws.k2[i]
    embedded_error(h, ws.k1, ws.k2, ws.err)
    return error_norm(ws.err, ws.wt)


@njit          # called, not inlined: it runs on the few checked sub-steps, and a fourth inlined copy of the
def _defect_norm(th2, h, km, op, ws):    # right-hand side in the stepper cost 1.5–3.5 s of the first compile
    """Error norm of the sub-step of h [s] that ended at (``ws.ynew``, θ₂ = ``th2``) by its defect there
    (:func:`.step_control.defect_error`): the right-hand side and Jacobian at the new state into ``ws.f1`` and
    ``ws.jac_end``, so that a rejected sub-step is tried again from the first stage as it was (``ws.f0``,
    ``ws.jac``), and one accepted inside the output step hands them to the next first stage (:func:`pressure_step`,
    :func:`_first_stage`)."""
    rhs(ws.ynew, th2, ws.gaps1, km, op, ws, ws.f1, ws.jac_end, bool(True))
    defect_error(h, ws.f1, ws.k1, ws.k2, ws.jac_end, ws.err)
    return error_norm(ws.err, ws.wt)


@njit(inline="always")
def _teeth_rates(ex, ey, th, th2, h, remaining, at_end, km, ws):
    """With the tooth constraint on, the teeth's rates of the sub-step of h [s] from θ = ``th`` to ``th2`` [rad] with
    ``remaining`` [s] of the output step left (:func:`.gear_coupling.substep_rates`; (ex, ey) the step's start [m]);
    ``at_end``: it ends the output step and ``ws.cmat`` holds the gap expansions there (inside :func:`pressure_step`).
    True where the first stage in hand no longer holds under them."""
    if ws.gear[GC_ON] == 0.0 or ws.gear[GC_CON] == 0.0:
        return False
    return substep_rates(ws.gear, ex, ey, th, th2, h, remaining, km.tab, km.pc.tip_clearance, ws.cmat, at_end)


@njit(inline="always")
def _proposed_substep(big_h, ws):
    """The sub-step [s] carried from the last output step (``ws.ctrl[CT_SUBSTEP]``), at most ``big_h``; ``big_h``
    if none."""
    return big_h if ws.ctrl[CT_SUBSTEP] <= 0.0 else min(big_h, ws.ctrl[CT_SUBSTEP])


@njit(inline="always")
def _first_substep_rates(ex, ey, theta, big_h, km, op, ws):
    """The teeth's rates of the first sub-step :func:`pressure_step` will try in the output step of ``big_h`` [s] from
    θ [rad] (the sub-step carried in ``ws.ctrl[CT_SUBSTEP]``), set before the step's first stage is evaluated, so that
    it holds there."""
    h = min(max(_proposed_substep(big_h, ws), big_h * 1e-5), big_h)
    if h == big_h:                  # one sub-step from the step's start: the set-up's own rates
        return
    th2 = theta + op.omega * big_h if h >= big_h * (1.0 - 1e-12) else theta + op.omega * h
    _teeth_rates(ex, ey, theta, th2, h, big_h, bool(False), km, ws)   # ws.cmat: the step's start; bool(): not a literal


@njit(inline="always")
def pressure_step(y, theta, big_h, ex, ey, km, op, ws, counters, integrals):
    """Advance the pressures over one output step ``big_h`` [s] with adaptive ROS2 sub-steps.

    The gear displacement (ex, ey) is frozen over the step; the gaps are
    interpolated linearly between their values at the two ends of the step.  On entry ``ws.gaps0`` holds the gaps at θ.  ``ws.ctrl[CT_SUBSTEP]``
    carries the proposed sub-step between calls.

    Returns ``STEP_DONE``, or why the step was abandoned part-way (``y`` then holds the last accepted
    sub-step): ``STEP_NONFINITE``, a sub-step at the smallest size gave a non-finite state;
    ``STEP_WORK_BOUND``, ``ws.ctrl[CT_BOUND]`` (``numerics.max_substep_attempts``) sub-step attempts did not
    finish it.  The caller stops there.
    """
    pc = km.pc
    n1 = y.shape[0]
    h = _proposed_substep(big_h, ws)
    h_min = big_h * 1e-5
    done = 0.0
    # gaps at the end of the output step; inside it they are interpolated linearly in time (the expansions there
    # are in ws.cmat already if the tooth constraint was set up for this step)
    contact(km.tab, pc.n, pc.tip_clearance, theta + op.omega * big_h, ex, ey, ws.gaps_end, ws.cmat,
            bool(ws.ctrl[CT_CMAT_END] != 0.0))
    ws.ctrl[CT_CMAT_END] = 0.0
    for k in range(pc.n):
        ws.gaps_start[k] = ws.gaps0[k]
    attempts = 0
    th = theta                                      # the angle of the accepted state [rad]
    while done < big_h * (1.0 - 1e-12):
        attempts += 1
        if attempts > ws.ctrl[CT_BOUND]:
            return STEP_WORK_BOUND
        h = min(max(min(h, big_h - done), h_min), big_h - done)
        last = done + h >= big_h * (1.0 - 1e-12)
        th2 = theta + op.omega * big_h if last else th + op.omega * h   # the step's end: integrate's angle
        if ws.ctrl[CT_FRESH] != FRESH_IN_F0:            # a new state (a retry keeps its rates and first stage):
            if _teeth_rates(ex, ey, th, th2, h, big_h - done, last, km, ws) and ws.ctrl[CT_FRESH] == FRESH_IN_F1:
                ws.ctrl[CT_FRESH] = FRESH_NONE          # the defect check's reactions change with the teeth's rates
            _first_stage(y, th, km, op, ws, integrals, big_h)       # first stage at (y, θ)
        w = (done + h) / big_h
        for k in range(pc.n):
            ws.gaps1[k] = ws.gaps_start[k] + w * (ws.gaps_end[k] - ws.gaps_start[k])
        check = port_filtered(ws, h)
        en = ros2_step(y, th2, h, km, op, ws)
        checked = False
        if en <= 1.0 or h <= h_min:
            finite = True
            for i in range(n1):
                if not math.isfinite(ws.ynew[i]):
                    finite = False
            if not finite:
                return STEP_NONFINITE
            if check and h > h_min:
                en = _defect_norm(th2, h, km, op, ws)  # the embedded estimate is blind there (step_control)
                checked = True
        if en <= 1.0 or h <= h_min:
            if en > 1.0:
                counters[C_FAILED] += 1               # accepted at the smallest sub-step above the tolerance
            for i in range(n1):
                y[i] = ws.ynew[i]
            ws.ctrl[CT_PENDING] = h               # its ∫ flow dt is closed by the next first stage
            ws.gear[GC_PEND] = h                  # and its ∫ė dt
            for k in range(pc.n):
                ws.gaps0[k] = ws.gaps1[k]
            # the defect check's RHS at this state serves the next first stage, unless the output step ends here
            # (the gear's move and the overlap check change the gaps and the volumes before it)
            ws.ctrl[CT_FRESH] = FRESH_IN_F1 if checked and not last else FRESH_NONE
            if checked and ws.gear[GC_ON] != 0.0:
                keep_first_stage(ws.gear)             # the defect check's right-hand side: the next first stage's
            done += h
            th = th2
            counters[C_SUBSTEPS] += 1
        else:
            counters[C_REJECTED] += 1      # stage 1 stays valid: same (y, θ), the defect check's in ws.jac_end
        h = max(h * step_factor(en), h_min)
    ws.ctrl[CT_SUBSTEP] = h
    return STEP_DONE


@njit(inline="always")
def to_pressures(y, km, out):
    """Pressures [Pa] of the log-density state; returns how many volumes are cavitating."""
    cav = 0
    for i in range(y.shape[0]):
        out[i] = pressure_of(y[i], km.eos)
        if out[i] < km.eos.p_lo:
            cav += 1
    return cav


@njit
def peak_pressures(rec_peak, rec_p, p0, eos):
    """The ln ρ peaks of :func:`integrate` as pressures [Pa], in place: each row's highest chamber pressure
    over its closed step, at least those at its two ends (``p0``: the chambers' at the first step's start).

    Takes the state equation ``eos``, not the whole :class:`~.params.KernelModel`: a call from Python
    unboxes its arguments, ≈ 7 µs for the model's tuples.
    """
    for n in range(rec_peak.shape[0]):
        for i in range(rec_peak.shape[1]):
            s = rec_peak[n, i]
            start = p0[i] if n == 0 else rec_p[n - 1, i]
            ends = max(start, rec_p[n, i])
            rec_peak[n, i] = max(pressure_of(s, eos), ends) if s > -math.inf else ends


@njit(inline="always")
def heun_step(velocity, bparams, ex, ey, h, theta, omega, kc, km, ws, counters):
    """One Heun step of the outer-gear centre over h [s] under the load of the pressures ``ws.pres``.

    ``velocity(ex, ey, fx, fy, omega2, bparams) -> (dex, dey)`` is the bearing's
    kernel (mobility, Method 1, FDM); the predictor is projected by the overlap
    check; |e| is capped at ε_max·c (counted as housing contact).
    Returns (ex, ey, fx, fy) [m, N], the load at the start.
    """
    pc = km.pc
    omega2 = omega * (pc.n - 1) / pc.n
    fx, fy, _fc, unl = outer_gear_load(ws.pres, theta, omega, ex, ey, kc, km)
    counters[C_CONTACT_UNLOADED] += unl
    d1x, d1y = velocity(ex, ey, fx, fy, omega2, bparams)
    px, py, _g, kc2 = contact(km.tab, pc.n, pc.tip_clearance, theta, ex + h * d1x, ey + h * d1y, ws.gaps1,
                              ws.cmat, bool(True))      # ws.cmat holds θ's coefficients (pressure_step)
    fx2, fy2, _fc2, _unl2 = outer_gear_load(ws.pres, theta, omega, px, py, kc2, km)
    d2x, d2y = velocity(px, py, fx2, fy2, omega2, bparams)
    ex, ey = housing_cap(ex + 0.5 * h * (d1x + d2x), ey + 0.5 * h * (d1y + d2y), pc, counters)
    return ex, ey, fx, fy


@njit(inline="always")
def housing_cap(ex, ey, pc, counters):
    """(ex, ey) [m] with |e| capped at ε_max·c (counted as housing contact)."""
    en = math.hypot(ex, ey)
    cap = pc.eps_max * pc.housing_clearance
    if en > cap:
        ex *= cap / en
        ey *= cap / en
        counters[C_HOUSING_CONTACT] += 1
    return ex, ey


@njit(inline="always")
def _delivery_flow(pc, ws):
    r"""The delivery flow at the end of an output step [m³/s], from its last ROS2 sub-step's stages ``ws.k1``,
    ``ws.k2`` (and, in restriction mode, ``ws.flows`` at the end state):

    .. math:: Q = s\,\big(b_1'(1)\,k_{1,N} + b_2'(1)\,k_{2,N}\big) + Q_r

    the rate at the sub-step's end of ROS2's continuous extension (``B1_END``, ``B2_END``) of component N: with an
    imposed delivery pressure the delivered-volume quadrature (s = 1, Q_r = 0), in restriction mode the delivery
    line's ln ρ (s its volume, Q_r the restriction's flow). It is the flow whose integral is the delivered volume.
    The right-hand side at the end state is not: a chamber open to the delivery port relaxes within microseconds,
    and its port flow G·(p_j − p_d) multiplies the state's error in p_j, however small, by the port's
    conductance G (docs/numerics.md, "The delivery flow at the output points").
    """
    rate = B1_END * ws.k1[pc.n] + B2_END * ws.k2[pc.n]
    if pc.restriction:
        return pc.line_volume * rate + ws.flows[FL_RESTRICTION]
    return rate


@njit(inline="always")
def _record(rec, rec_p, rec_peak, rec_gap, n, t, theta, ex, ey, fx, fy, gam, kc, ws, q_delivery):
    fl = ws.flows
    rec[n, R_T] = t
    rec[n, R_THETA] = theta
    rec[n, R_QDEL] = q_delivery
    for i in range(1, 5):                      # FL_SUCTION .. FL_RESTRICTION
        rec[n, R_QDEL + i] = fl[i]
    rec[n, R_PD] = ws.pres[ws.pres.shape[0] - 1]
    rec[n, R_EX] = ex
    rec[n, R_EY] = ey
    rec[n, R_FX] = fx
    rec[n, R_FY] = fy
    rec[n, R_GAMMA] = gam
    rec[n, R_KC] = kc
    for i in range(rec_p.shape[1]):
        rec_p[n, i] = ws.pres[i]
        rec_peak[n, i] = ws.peak[i]
        ws.peak[i] = -math.inf
        rec_gap[n, i] = ws.gaps0[i]


@njit
def integrate(y, e, theta, t, n_steps, h, km, op, ws, rec, rec_p, rec_peak, rec_gap, counters, integrals, move,
              constraint=None):
    """Advance ``n_steps`` output steps of h [s]; returns the new (θ, t), updates y, e in place.

    Writes one record per step into ``rec`` (N_REC columns), ``rec_p`` (chamber
    pressures), ``rec_peak`` (each chamber's highest pressure over the step, from
    the sub-steps: :func:`_track_peak`) and ``rec_gap`` (gap heights); ``integrals`` accumulates
    ∫ flow dt [m³] per ``FL_*`` index: the delivered volume with the Rosenbrock stages themselves, consistent
    with the chambers' mass balance (imposed delivery pressure: their quadrature; restriction mode: the line's
    volume times the change of its ln ρ, plus what left through the restriction); the others by the trapezoid over
    every accepted ROS2 sub-step.
    ``move``: MOVE_FIXED (the centre stays where it is), MOVE_MOBILITY (Heun
    steps of the mobility method, sec. 2.2 of [1]) or MOVE_EXTERNAL (held here,
    moved by the caller: :func:`integrate_external`).
    ``constraint``: None, or ``ws.gear`` with ``numerics.gear_coupling: constrained`` (the tooth contact as a
    constraint inside the step: :func:`.gear_coupling.set_constraint` after each linearisation, the pull-back
    along G n after each step).  Its type, not a flag, selects the path: numba prunes the ``is not None``
    branches, so the other schemes compile without that code (compiled in behind a run-time flag it cost them
    2–12 % of speed with the same sub-steps, docs/performance.md) and ``constrained`` is a specialisation of
    its own, compiled on first use.
    """
    pc = km.pc
    # the gear inside the stages (numerics.gear_coupling: model/gear_coupling.py); MOVE_EXTERNAL: set up by
    # the caller (integrate_external), one output step per call
    coupled = move != MOVE_FIXED and gear_in_stages(km)
    ex, ey, gam, kc = contact(km.tab, pc.n, pc.tip_clearance, theta, e[0], e[1], ws.gaps0, ws.cmat, bool(False))
    ws.ctrl[CT_CMAT_END] = 0.0                     # ws.cmat holds θ's expansions
    ws.ctrl[CT_GEO_OK] = 0.0                       # ws.geo: no table values yet (the tables may be new)
    move_volumes(km.tab, ws.disp, ex, ey, 0.0)
    if not coupled:
        ws.gear[GC_ON] = 0.0
    elif move == MOVE_MOBILITY:
        to_pressures(y, km, ws.pres)
        if linearise_mobility(ex, ey, theta, op.omega, h, kc, km, ws.pres, ws.gear, ws.gear_rows, ws.cmat,
                              constraint is not None):
            ws.ctrl[CT_CMAT_END] = 1.0             # and the step's end: pressure_step's tip gaps read them
    ws.ctrl[CT_PENDING] = 0.0
    ws.ctrl[CT_FRESH] = FRESH_NONE                 # a call starts with its own first stage
    if coupled:
        _first_substep_rates(ex, ey, theta, h, km, op, ws)
    _first_stage(y, theta, km, op, ws, integrals, h)
    ws.peak[:] = -math.inf
    fade = math.exp(-abs(op.omega) * h / (2.0 * math.pi))     # of the error scale's range, per output step
    for n in range(n_steps):
        if not pc.restriction:
            y[pc.n] = 0.0                          # ∫ Q_delivered dt over this step (flows.assemble)
        line0 = y[pc.n]                            # restriction mode: the line's ln ρ and what left it so far
        restricted0 = integrals[FL_RESTRICTION]
        status = pressure_step(y, theta, h, ex, ey, km, op, ws, counters, integrals)
        if status != STEP_DONE:
            ws.ctrl[CT_STATUS] = status            # the caller reports it (PumpModel.advance: SolverFailure)
            counters[C_ABANDONED] += 1
            break
        if not pc.restriction:
            integrals[FL_DELIVERY] += y[pc.n]
            y[pc.n] = op.s_d
        counters[C_CAVITATION] += to_pressures(y, km, ws.pres)
        update_range(ws.ctrl, ws.pres, pc.n, fade)   # the error scale of the next step
        theta += op.omega * h
        t += h
        fx = 0.0
        fy = 0.0
        if coupled:
            if ws.gear[GC_CX] == 0.0 and ws.gear[GC_CY] == 0.0:
                counters[C_CONTACT_UNLOADED] += 1          # the contact would pull at the step start
            px, py, fx, fy = gear_move(ex, ey, theta, km, ws.pres, ws.gear, ws.gear_rows)
            ws.disp[0] = ex + ws.gear[GC_DEX]      # where the stages' squeeze has taken the volumes: only the
            ws.disp[1] = ey + ws.gear[GC_DEY]      # rest of the move is squeezed over the next step (move_volumes)
            ex, ey = housing_cap(px, py, pc, counters)
        elif move == MOVE_MOBILITY:
            bp = (pc.housing_clearance, pc.width, 2.0 * pc.journal_radius, pc.viscosity)
            ex, ey, fx, fy = heun_step(mobility_kernel, bp, ex, ey, h, theta, op.omega, kc, km, ws, counters)
        elif move == MOVE_FIXED:
            fx, fy, _fc, _unl = outer_gear_load(ws.pres, theta, op.omega, ex, ey, kc, km)
        ex0, ey0 = ex, ey
        if constraint is not None and coupled:        # back onto the teeth along G n, as inside the step
            ex, ey, _ok = pull_back_along(ws.cmat, pc.tip_clearance, ex, ey, ws.gear[GC_GXX], ws.gear[GC_GXY],
                                          ws.gear[GC_GYX], ws.gear[GC_GYY], ws.gear[GC_PAIR:GC_PAIR + 10])
        ex, ey, gam, kc = contact(km.tab, pc.n, pc.tip_clearance, theta, ex, ey, ws.gaps0, ws.cmat, bool(True))
        move_volumes(km.tab, ws.disp, ex, ey, h)
        if ex != ex0 or ey != ey0:
            counters[C_GEAR_CONTACT] += 1
        if coupled and move == MOVE_MOBILITY:
            if linearise_mobility(ex, ey, theta, op.omega, h, kc, km, ws.pres, ws.gear, ws.gear_rows, ws.cmat,
                                  constraint is not None):
                ws.ctrl[CT_CMAT_END] = 1.0
            _first_substep_rates(ex, ey, theta, h, km, op, ws)
        _first_stage(y, theta, km, op, ws, integrals, h)   # end-of-step flows (recorded, but the delivery's) = next first stage
        if pc.restriction:                         # delivered = stored in the line + gone through the restriction
            integrals[FL_DELIVERY] += pc.line_volume * (y[pc.n] - line0) + integrals[FL_RESTRICTION] - restricted0
        counters[C_STEPS] += 1
        _record(rec, rec_p, rec_peak, rec_gap, n, t, theta, ex, ey, fx, fy, gam, kc, ws, _delivery_flow(pc, ws))
    e[0] = ex
    e[1] = ey
    return theta, t


@njit(inline="always")
def gear_in_stages(km):
    """True if a moving gear's squeeze goes into the ROS2 stages (numerics.gear_coupling, displaced volumes)."""
    return km.tab.volumes_follow_gear and km.pc.gear_in_stages


def integrate_external(bearing, y, e, theta, t, n_steps, h, km, op, ws, rec, rec_p, rec_peak, rec_gap, counters,
                       integrals):
    """Output steps with a bearing model other than the mobility method (Method 1, FDM): a Python loop.

    Each output step is one compiled :func:`integrate` step.  With the gear in the stages
    (:mod:`.gear_coupling`) it is set up here before the step with ``bearing.kernel`` (three
    calls) and moved by the step itself; else the step holds the gear and the same
    :func:`heun_step` moves it afterwards (compiled for the kernel in each process: numba
    caches no function that takes a function).
    """
    if gear_in_stages(km):
        return _integrate_external_in_stages(bearing, y, e, theta, t, n_steps, h, km, op, ws, rec, rec_p, rec_peak,
                                             rec_gap, counters, integrals)
    abandoned = counters[C_ABANDONED]
    for i in range(n_steps):
        theta, t = integrate(y, e, theta, t, 1, h, km, op, ws, rec[i:i + 1], rec_p[i:i + 1], rec_peak[i:i + 1],
                             rec_gap[i:i + 1], counters, integrals, MOVE_EXTERNAL)
        if counters[C_ABANDONED] != abandoned:
            break
        kc = int(rec[i, R_KC])
        ex, ey, fx, fy = heun_step(bearing.kernel, bearing.params, e[0], e[1], h, theta, op.omega, kc, km, ws,
                                   counters)
        ex, ey, gam, kc = contact(km.tab, km.pc.n, km.pc.tip_clearance, theta, ex, ey, ws.gaps0, ws.cmat)
        move_volumes(km.tab, ws.disp, ex, ey, h)
        ws.ctrl[CT_FRESH] = FRESH_NONE       # the gaps moved: the next first stage is recomputed
        e[0], e[1] = ex, ey
        rec[i, R_EX], rec[i, R_EY], rec[i, R_FX], rec[i, R_FY] = ex, ey, fx, fy
        rec[i, R_GAMMA], rec[i, R_KC] = gam, kc
        rec_gap[i] = ws.gaps0
    return theta, t


def _integrate_external_in_stages(bearing, y, e, theta, t, n_steps, h, km, op, ws, rec, rec_p, rec_peak, rec_gap,
                                  counters, integrals):
    """:func:`integrate_external` with the gear in the stages: linearise with ``bearing``, then one step (Method 1:
    the same, compiled, :func:`integrate_short`)."""
    if bearing.name == "short":
        return integrate_short(bearing.params, y, e, theta, t, n_steps, h, km, op, ws, rec, rec_p, rec_peak, rec_gap,
                               counters, integrals, MOVE_EXTERNAL, ws.gear if km.pc.gear_constrained else None)
    abandoned = counters[C_ABANDONED]
    for i in range(n_steps):
        ex, ey, _gam, kc = contact(km.tab, km.pc.n, km.pc.tip_clearance, theta, e[0], e[1], ws.gaps0, ws.cmat)
        to_pressures(y, km, ws.pres)
        linearise_with(bearing, ex, ey, theta, op.omega, h, kc, km, ws.pres, ws.gear, ws.gear_rows, ws.cmat)
        theta, t = integrate(y, e, theta, t, 1, h, km, op, ws, rec[i:i + 1], rec_p[i:i + 1], rec_peak[i:i + 1],
                             rec_gap[i:i + 1], counters, integrals, MOVE_EXTERNAL,
                             ws.gear if km.pc.gear_constrained else None)
        if counters[C_ABANDONED] != abandoned:
            break
    return theta, t


@njit
def integrate_short(params, y, e, theta, t, n_steps, h, km, op, ws, rec, rec_p, rec_peak, rec_gap, counters, integrals,
                    move, constraint=None):
    """:func:`_integrate_external_in_stages` with Method 1's kernel compiled in (``params``: its parameters,
    :class:`~gerotor_twin.bearing.short_bearing.ShortBearing`): the same calls in the same order, so the same
    results bit for bit, without the return to Python and the dispatch of :func:`integrate` at every output step
    (docs/performance.md, "Cost of the four outer-gear models").  ``constraint`` as for :func:`integrate` (its type
    selects the specialisation).  ``move``: ``MOVE_EXTERNAL``, and the one step per call ``min(1, n_steps)``,
    reach :func:`integrate` as run-time integers: a constant written here would be typed as its literal value and
    compile a specialisation of :func:`integrate` of its own (≈ 5 s).  The FDM bearing's kernel allocates its
    fields and stays in the Python loop."""
    abandoned = counters[C_ABANDONED]
    one = min(1, n_steps)
    for i in range(n_steps):
        ex, ey, _gam, kc = contact(km.tab, km.pc.n, km.pc.tip_clearance, theta, e[0], e[1], ws.gaps0, ws.cmat,
                                   bool(False))
        to_pressures(y, km, ws.pres)
        linearise_short(params, ex, ey, theta, op.omega, h, kc, km, ws.pres, ws.gear, ws.gear_rows, ws.cmat,
                        constraint is not None)
        theta, t = integrate(y, e, theta, t, one, h, km, op, ws, rec[i:i + 1], rec_p[i:i + 1], rec_peak[i:i + 1],
                             rec_gap[i:i + 1], counters, integrals, move, constraint)
        if counters[C_ABANDONED] != abandoned:
            break
    return theta, t
