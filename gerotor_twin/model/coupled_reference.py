r"""An independent reference for the outer gear on its teeth: pressures and gear position integrated together.

The twin and its tight reference (:mod:`.accuracy`) share one scheme: the gear's position held over an output
step, its velocity linearised in the load, the tooth contact as Moreau's time-stepping
(:mod:`.tooth_constraint`).  A finer run of that scheme cannot tell whether the scheme is right.  This
reference integrates the chamber log-densities y and the gear's position e as one ODE with an implicit
Runge–Kutta method of order 5 (Radau IIA, scipy's ``Radau`` [2]) at tight tolerances:

.. math::
    \dot y = f(y, \theta, \mathbf e, \dot{\mathbf e}),\qquad
    \dot{\mathbf e} = \mathbf M\Big(\mathbf e,\ \mathbf F(y, \theta, \mathbf e) + \sum_{k=1,2} \lambda_k\,\mathbf n_k\Big)

with the gaps and displaced volumes at the current e (no freezing), the full nonlinear mobility M of sec. 2.2
of [1] (not linearised: the film carries the load and the teeth's reactions together), and the contact of the
two lobes with the smallest gaps as a complementarity problem in the reactions λ_k ≥ 0 along the gaps' normals
n_k (Josephy–Newton, :func:`.gear_coupling.linearise_in_contact` at every right-hand side; ``full=False``: the reactions through the mobility linearised at the
free load, ė = M(e, F) + Σ λ_k G n_k, for comparison), with the rate of each gap taken as

.. math::
    r_k = \frac{\partial g_k}{\partial\theta}\,\omega + \frac{g_k}{\tau}

(the gap's own rate by the shaft's turn, plus a relaxation over τ that holds it at zero without penetration:
a lobe that closes faster than g/τ is held, the sweeping process of [3] as τ → 0).  The right-hand side is
continuous in the state, so the implicit method needs no event handling.  What it shares with the twin is the
physics (flows, loads, mobility, gap tables), not the time discretisation or the contact scheme.

References
----------
.. [1] The paper (``../shared/paper``).
.. [2] E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer 1996, sec. IV.8.
.. [3] J.J. Moreau, "Numerical aspects of the sweeping process", Comput. Methods Appl. Mech. Engrg. 177 (1999)
   329–349.
"""
from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..bearing.mobility import mobility_kernel
from ..units import bar_gauge_to_pa_abs, rpm_to_rad_s
from .contact import contact, gap_coefficients, gap_value
from .flows import rhs
from .gear_coupling import (FULL_RTOL, GC_CON, GC_ON, GC_PAIR, N_GEAR, gear_velocity, linearise_in_contact, load_step,
                            set_velocity)
from .kernel import to_pressures
from .loads import outer_gear_load
from .params import FL_DELIVERY, operating
from .tooth_constraint import constrained_velocity, contact_pair, gap_normal, two_smallest

__all__ = ["coupled_rhs", "coupled_revolution", "RELAXATION_DEG"]

#: τ of the contact's relaxation as a shaft angle [deg] (τ = this / ω): far below the output step of 1.5°.
RELAXATION_DEG = 0.005
#: Gap [m] within which two lobes share the contact force of Eq. (26) (:func:`_handover_load`): far below any
#: clearance (µm), far above the round-off of a gap held at zero (1e-15 m).
HANDOVER_M = 1e-9


@njit
def _gap_rate(tab, delta, theta, omega, ex, ey, k, c):
    """∂g_k/∂θ·ω [m/s] of lobe k at (ex, ey) [m]: a central difference of the tables over ±1e-6 rad."""
    d = 1e-6
    gap_coefficients(tab, theta + d, k, c)
    gp = gap_value(c, delta, ex, ey, 0.0)
    gap_coefficients(tab, theta - d, k, c)
    return (gp - gap_value(c, delta, ex, ey, 0.0)) / (2.0 * d) * omega


@njit
def _handover_load(pres, theta, omega, ex, ey, kc, k1, k2, g1, g2, km):
    """Load [N] of Eqs. (24)–(27) with the contact force of Eq. (26) shared by the two lobes nearest contact.

    Eq. (26) puts the driving torque on one lobe, the one with the smallest gap (``kc``).  Where two lobes are
    within :data:`HANDOVER_M` of contact (the gear wedged between two teeth, both gaps held at zero) that choice
    is round-off's, and the load jumps with it: the right-hand side is discontinuous and Radau stalls (07 at
    1650 rpm / 27.5 bar, 237° of the second revolution: a 1e-15 m move switched the lobe and changed ė by
    4 mm/s).  Here the two lobes' loads are weighted by w_k ∝ 1 − g_k/ε (g_k clipped to [0, ε], ε =
    :data:`HANDOVER_M`): equal halves at equal gaps, the nearer lobe alone once the other is ε open, so the load
    is continuous in e.  Outside ε of contact it is Eq. (26) with ``kc`` as in the twin.
    """
    w1 = 1.0 - min(max(g1, 0.0), HANDOVER_M) / HANDOVER_M
    w2 = 1.0 - min(max(g2, 0.0), HANDOVER_M) / HANDOVER_M
    if w2 <= 0.0:                                   # the second lobe ε open: one lobe carries it
        fx, fy, _fc, _unl = outer_gear_load(pres, theta, omega, ex, ey, kc if w1 <= 0.0 else k1, km)
        return fx, fy
    ax, ay, _fc, _unl = outer_gear_load(pres, theta, omega, ex, ey, k1, km)
    bx, by, _fc, _unl = outer_gear_load(pres, theta, omega, ex, ey, k2, km)
    s = w1 / (w1 + w2)
    return s * ax + (1.0 - s) * bx, s * ay + (1.0 - s) * by


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def coupled_rhs(t, z, theta0, tau, km, op, ws, out, full=True):
    """d/dt of z = (y [-], e [m]) [1/s, m/s] into ``out`` at t [s] (θ = θ₀ + ωt [rad]); τ: the relaxation [s].

    ``z``: the N+1 log-densities (the last: ∫ delivered flow dt [m³] in imposed-pressure mode, as the
    stepper) and (e_x, e_y).  Uses ``ws`` for scratch; ``ws.flows`` holds the flows at this state.
    """
    pc, tab = km.pc, km.tab
    n = pc.n
    n1 = n + 1
    y = z[:n1]
    ex, ey = z[n1], z[n1 + 1]
    theta = theta0 + op.omega * t
    _x, _y, _gam, kc = contact(tab, n, pc.tip_clearance, theta, ex, ey, ws.gaps0, ws.cmat, bool(False))
    to_pressures(y, km, ws.pres)
    k1, k2, g1, g2 = two_smallest(ws.cmat, pc.tip_clearance, ex, ey)
    fx, fy = _handover_load(ws.pres, theta, op.omega, ex, ey, kc, k1, k2, g1, g2, km)      # Eqs. (24)-(27)
    bp = (pc.housing_clearance, pc.width, 2.0 * pc.journal_radius, pc.viscosity)
    omega2 = op.omega * (n - 1) / n
    d = load_step(fx, fy)
    vx, vy = mobility_kernel(ex, ey, fx, fy, omega2, bp)
    v1x, v1y = mobility_kernel(ex, ey, fx + d, fy, omega2, bp)
    v2x, v2y = mobility_kernel(ex, ey, fx, fy + d, omega2, bp)
    c = np.empty(10)                                  # an offline reference: it may allocate
    r1 = _gap_rate(tab, pc.tip_clearance, theta, op.omega, ex, ey, k1, c)
    r2 = _gap_rate(tab, pc.tip_clearance, theta, op.omega, ex, ey, k2, c)
    n1x, n1y = gap_normal(ws.cmat[k1], ex, ey)
    n2x, n2y = gap_normal(ws.cmat[k2], ex, ey)
    contact_pair((v1x - vx) / d, (v2x - vx) / d, (v1y - vy) / d, (v2y - vy) / d, n1x, n1y, n2x, n2y,
                 r1 + g1 / tau, r2 + g2 / tau, c)
    if full:                                          # the reactions through the full mobility, as the twin's
        gc = np.zeros(N_GEAR)
        set_velocity(gc, fx, fy, (vx, vy), (v1x, v1y), (v2x, v2y), d)
        gc[GC_PAIR:GC_PAIR + 10] = c
        gc[GC_CON] = 1.0
        linearise_in_contact(ex, ey, op.omega, km, gc, FULL_RTOL)
        vx, vy = gear_velocity(fx, fy, gc)
    else:
        vx, vy, _l1, _l2 = constrained_velocity(vx, vy, c)
    ws.disp[0], ws.disp[1], ws.disp[2], ws.disp[3] = ex, ey, vx, vy      # volumes at e, squeezed by ė (volumes.py)
    ws.gear[GC_ON] = 0.0
    rhs(y, theta, ws.gaps0, km, op, ws, ws.f0, ws.jac, bool(False))
    for i in range(n1):
        out[i] = ws.f0[i]
    out[n1] = vx
    out[n1 + 1] = vy


def _system(model, op, theta0: float, tau: float, full: bool = True):
    """The coupled system's right-hand side f(t, z) with θ = θ₀ + ωt [rad], and Radau's absolute tolerances."""
    n, out = model.N, np.empty(model.N + 3)

    def f(t, zz):      # one compiled specialisation for every caller: z C-contiguous, ``full`` a bool
        coupled_rhs(t, np.ascontiguousarray(zz), theta0, tau, model.kernel, op, model._ws, out, bool(full))
        return out.copy()
    atol = np.full(n + 3, 1e-9)
    atol[n] = 1e-12
    atol[n + 1:] = 1e-11
    return f, atol


def coupled_revolution(model, rpm: float, bar: float, state, revolutions: int = 2, rtol: float = 1e-7,
                       samples_per_step: int = 8, full: bool = True):
    """One revolution of the coupled reference at (rpm, bar gauge), after ``revolutions − 1`` settling ones.

    Parameters
    ----------
    model : PumpModel
        The pump (mobility method; its numerics are not used).
    state : PumpState
        Start (e.g. the twin's periodic state at the point): its angle, log-densities and eccentricity.
    rtol : float
        Radau's relative tolerance [-]; absolute: 1e-9 on ln ρ, 1e-11 m on e, 1e-12 m³ on the delivered volume.
    samples_per_step : int
        Dense-output samples per twin output step, for the peak between samples.

    Returns
    -------
    (dict, ndarray)
        The recorded revolution at the twin's output angles, as the fields of :class:`.accuracy.Revolution`
        (θ [rad], chamber pressures [Pa], delivery flow [m³/s], η [-], mean flow [m³/s], peak [Pa]), and e [m] there.

    Notes
    -----
    Each revolution starts where the one before ended, at θ₀ + 2πk: a chamber's tables repeat with the chamber
    period 2πN/(N − 1), not with the shaft's 2π, so after one shaft revolution each chamber stands where its
    neighbour stood one revolution before (the chamber labels of :meth:`.accuracy.Revolution.at`).
    """
    from scipy.integrate import solve_ivp

    from .volumetric import EdgeLosses
    cfg, km, n = model.config, model.kernel, model.N
    omega = rpm_to_rad_s(rpm)
    p_d = bar_gauge_to_pa_abs(bar, cfg.fluid.atmospheric_pa)
    op = operating(km, omega, cfg.boundary.suction_pressure_pa, p_d)
    if model.restriction_mode:
        raise ValueError("coupled_revolution: imposed delivery pressure only (boundary.mode: imposed)")
    ws = model._ws
    period = 2.0 * math.pi / omega
    tau = math.radians(RELAXATION_DEG) / omega
    z = np.concatenate([state.log_density, state.eccentricity]).astype(float)
    z[n] = 0.0
    theta0 = float(state.theta)
    # scipy's num_jac multiplies the increment of the delivered volume z[n], on which f does not depend, by 10 at
    # every Jacobian without a bound: past ≈ 300 Jacobians it overflows to inf (the column stays zero: harmless)
    with np.errstate(over="ignore"):
        for _ in range(revolutions - 1):
            f, atol = _system(model, op, theta0, tau, full)
            z = solve_ivp(f, (0.0, period), z, method="Radau", rtol=rtol, atol=atol).y[:, -1]
            z[n] = 0.0
            theta0 += 2.0 * math.pi                                    # the next revolution starts here
    m = max(1, int(math.ceil(period / model.step_size(omega) - 1e-9)))     # the twin's output steps (advance)
    t_fine = np.linspace(0.0, period, m * samples_per_step + 1)
    f, atol = _system(model, op, theta0, tau, full)
    with np.errstate(over="ignore"):
        sol = solve_ivp(f, (0.0, period), z, method="Radau", rtol=rtol, atol=atol, dense_output=True)
    fine = sol.sol(t_fine)
    pres = np.empty(n + 1)
    p_fine = np.empty((t_fine.size, n))
    q_fine = np.empty(t_fine.size)
    for i in range(t_fine.size):
        f(t_fine[i], fine[:, i])
        to_pressures(fine[:n + 1, i], km, pres)
        p_fine[i] = pres[:n]
        q_fine[i] = ws.flows[FL_DELIVERY]
    pick = slice(samples_per_step, None, samples_per_step)          # the twin's output angles (after each step)
    qth = model.theoretical_flow(omega)
    eta = float(sol.y[n, -1] / (qth * period))
    edge = EdgeLosses.of(cfg, model.displacement)
    q = eta * qth - edge.flow(omega, p_d, op.p_s)
    rev = dict(theta=theta0 + omega * t_fine[pick], chamber_pressures=p_fine[pick], delivery_flow=q_fine[pick],
               volumetric_efficiency=q / qth, mean_delivery_flow=q, peak_pressure=float(p_fine.max()))
    return rev, fine[n + 1:, pick].T
