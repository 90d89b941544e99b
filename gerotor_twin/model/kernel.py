"""Compiled hot loop of the pump model: right-hand side, Jacobian, stepper.

State vector y (length N+1): the N chamber pressures and the delivery-volume
pressure (a state in ``restriction`` mode; held at the imposed value in
``imposed`` mode).  All pressures absolute [Pa].

Continuity (eq. 20 of [1], corrected: dp/dθ = β/(Vω)(ΣQ − ω dV/dθ); the
printed 1/ω_int factor is not dimensionally right), written in time and in
mass-conservative form:

.. math::
    \\frac{dp_j}{dt} = \\frac{\\beta(p_j)}{V_j}
       \\Big(\\sum_i \\frac{\\rho(p_{up,i})}{\\rho(p_j)} Q_i - \\omega\\frac{dV_j}{d\\theta}\\Big)

where Q_i are the volume flows into chamber j (at upstream conditions) and
ρ(p) is the barotropic density consistent with β(p) (dρ/dp = ρ/β).  The
density ratio (1 ± Δp/β, at most 0.2 % here) makes the mass balance close
exactly over a cycle; with ρ = const the book-keeping error would be of the
same order as the compressibility itself.

Integrator: Verwer's two-stage Rosenbrock method ROS2 (γ = 1 + 1/√2),
L-stable and second order for any approximation W of the Jacobian [2], with
a fixed step in shaft angle.  The outer-gear micro-motion is advanced after
each pressure step by Heun's method on the bearing model (partitioned
scheme: the bearing time constants, ≳ 0.3 ms, are long against the step).

References
----------
.. [1] The paper (``../shared/paper``).
.. [2] J.G. Verwer, E.J. Spee, J.G. Blom, W. Hundsdorfer, "A second-order
   Rosenbrock method applied to photochemical dispersion problems",
   SIAM J. Sci. Comput. 20 (1999) 1456–1480.
"""
from __future__ import annotations

import math

import numpy as np

from .._jit import njit
from ..bearing.mobility import mobility_velocity
from ..geometry.tables import (AD, ARM, AS, DV, FX, FY, GG, GX, GY, HGG, HXG, HXX, HXY, HYG, HYY, KREL,
                               TQ, V, VR, interp)
from ..hydraulics.fluid import (FP_ATMOSPHERIC, FP_BULK_MODULUS, FP_CAVITATION_RATIO, FP_DENSITY,
                                FP_SWITCH_BAND, FP_VAPOUR, FP_VISCOSITY, bulk_modulus, log_density)
from ..hydraulics.gaps import tooth_tip_flow
from ..hydraulics.orifice import orifice_flow

# ---------------------------------------------------------------- parameters
P_N, P_WIDTH, P_DELTA, P_DH, P_CD, P_LAMBDA, P_GLAT, P_GSD, P_GDR, P_C, P_RJ, P_MODE, P_VLINE, \
    P_AREST, P_PTANK, P_EPSMAX = range(7, 23)
N_PARAMS = 23

# ------------------------------------------------------------------ outputs
# per-step record columns besides the chamber pressures and gaps
R_T, R_THETA, R_QDEL, R_QSUC, R_QSD, R_QDR, R_QREST, R_PD, R_EX, R_EY, R_FX, R_FY, R_GAMMA, R_KC, \
    R_MIN_GAP = range(15)
N_REC = 15

# counters
C_STEPS, C_CAVITATION, C_CONTACT_UNLOADED, C_HOUSING_CONTACT, C_GEAR_CONTACT = range(5)
N_COUNTERS = 5

BEARING_FIXED, BEARING_MOBILITY, BEARING_EXTERNAL = 0, 1, 2

GAMMA = 1.0 + 1.0 / math.sqrt(2.0)


@njit
def _gap_coeffs(tab, period, shift, k, theta, out):
    t = theta + k * shift
    for i, col in enumerate((GX, GY, GG, HXX, HXY, HYY, HXG, HYG, HGG)):
        out[i] = interp(tab, col, t, period)


@njit
def _gap_value(c, delta, ex, ey, g):
    return (delta + c[0] * ex + c[1] * ey + c[2] * g
            + 0.5 * (c[3] * ex * ex + 2.0 * c[4] * ex * ey + c[5] * ey * ey
                     + 2.0 * c[6] * ex * g + 2.0 * c[7] * ey * g + c[8] * g * g))


@njit
def _smallest_positive_root(a, b, c):
    """Smallest root > 0 of a x² + b x + c, or +inf."""
    best = np.inf
    if abs(a) < 1e-300 or abs(a * c) < 1e-12 * b * b:
        if b != 0.0:
            x = -c / b
            if x > 0.0:
                best = x
        return best
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return best
    sq = math.sqrt(disc)
    # numerically stable pair
    q = -0.5 * (b + math.copysign(sq, b))
    for x in (q / a, c / q if q != 0.0 else np.inf):
        if 0.0 < x < best:
            best = x
    return best


@njit
def contact(tab, period, shift, N, delta, theta, ex, ey, h_out, coef):
    """Overlap check of sec. 3.7 of [1] on the tabulated gap expansion.

    Returns the displacement actually taken (pulled back along **e** if the
    gears would overlap), the inner-gear rotation γ (turned forward until one
    contact if they would not touch), the index of the contact lobe, and
    fills ``h_out`` with the N gap heights [m].
    """
    cmat = np.empty((N, 9))
    for k in range(N):
        _gap_coeffs(tab, period, shift, k, theta, coef)
        for i in range(9):
            cmat[k, i] = coef[i]
        h_out[k] = _gap_value(coef, delta, ex, ey, 0.0)
    hmin = np.min(h_out)
    gamma = 0.0
    if hmin >= 0.0:
        # rotate the inner gear forward until the first lobe touches
        best = np.inf
        for k in range(N):
            c = cmat[k]
            b = c[2] + c[6] * ex + c[7] * ey
            if b < 0.0:
                x = _smallest_positive_root(0.5 * c[8], b, h_out[k])
                if x < best:
                    best = x
        if best < np.inf:
            gamma = best
    else:
        en = math.hypot(ex, ey)
        ux, uy = ex / en, ey / en
        s = 0.0
        for k in range(N):
            if h_out[k] < 0.0:
                c = cmat[k]
                gx = c[0] + c[3] * ex + c[4] * ey
                gy = c[1] + c[4] * ex + c[5] * ey
                b = -(gx * ux + gy * uy)
                a = 0.5 * (c[3] * ux * ux + 2.0 * c[4] * ux * uy + c[5] * uy * uy)
                x = _smallest_positive_root(a, b, h_out[k])
                if x == np.inf:
                    x = en
                if x > s:
                    s = x
        s = min(s, en)
        ex -= s * ux
        ey -= s * uy
    kc = 0
    for k in range(N):
        h_out[k] = _gap_value(cmat[k], delta, ex, ey, gamma)
        if h_out[k] < h_out[kc]:
            kc = k
    return ex, ey, gamma, kc


@njit
def rhs(y, theta, omega, ps, pd_in, h_gap, tab, period, shift, prm, f, jac, want_jac, flows):
    """Right-hand side dy/dt [Pa/s] (and its Jacobian) at shaft angle θ.

    ``flows`` receives (q_delivery_out, q_suction_in, q_sd, q_drain, q_restriction) [m³/s].
    """
    N = int(prm[P_N])
    beta_s, ratio, p_atm = prm[FP_BULK_MODULUS], prm[FP_CAVITATION_RATIO], prm[FP_ATMOSPHERIC]
    band, p_vap = prm[FP_SWITCH_BAND], prm[FP_VAPOUR]
    rho, mu = prm[FP_DENSITY], prm[FP_VISCOSITY]
    cd, lam = prm[P_CD], prm[P_LAMBDA]
    b, dh, glat = prm[P_WIDTH], prm[P_DH], prm[P_GLAT]
    restriction = prm[P_MODE] > 0.5
    pd = y[N] if restriction else pd_in
    n1 = N + 1
    s = np.empty(n1)
    for i in range(N):
        s[i] = log_density(y[i], beta_s, ratio, p_atm, band, p_vap)
    s[N] = log_density(pd, beta_s, ratio, p_atm, band, p_vap)
    s_ps = log_density(ps, beta_s, ratio, p_atm, band, p_vap)
    acc = np.zeros(n1)        # Σ (ρ_up/ρ_i) Q_i into each volume [m³/s]
    if want_jac:
        for i in range(n1):
            for k in range(n1):
                jac[i, k] = 0.0
    q_del = 0.0
    q_suc = 0.0
    for j in range(N):
        tj = theta + j * shift
        pj = y[j]
        # suction port -> chamber j, eq. (21)
        q, dq = orifice_flow(ps - pj, interp(tab, AS, tj, period), cd, lam, rho, mu)
        fac = math.exp(s_ps - s[j]) if q > 0.0 else 1.0
        acc[j] += fac * q
        q_suc += q
        if want_jac:
            jac[j, j] -= fac * dq
        # delivery port -> chamber j
        q, dq = orifice_flow(pd - pj, interp(tab, AD, tj, period), cd, lam, rho, mu)
        if q > 0.0:
            acc[j] += math.exp(s[N] - s[j]) * q
            acc[N] -= q
            q_del -= q
        else:
            acc[j] += q
            fd = math.exp(s[j] - s[N])
            acc[N] -= fd * q
            q_del -= fd * q
        if want_jac:
            jac[j, j] -= dq
            jac[N, j] += dq
            jac[j, N] += dq
            jac[N, N] -= dq
        # tooth-tip gap at lobe j: chamber j-1 -> chamber j, eq. (22)
        jm = (j - 1) % N
        hk = h_gap[j]
        q = 0.0
        dq = 0.0
        if hk > 0.0:
            krel = interp(tab, KREL, tj, period)
            le = 2.0 * math.sqrt(2.0 * hk * dh / krel)
            q, dq = tooth_tip_flow(y[jm] - pj, hk, le, omega * interp(tab, VR, tj, period), b, mu)
        # lateral leakage across the lobe land, sec. 3.2
        q += glat * (y[jm] - pj)
        dq += glat
        if q > 0.0:
            acc[j] += math.exp(s[jm] - s[j]) * q
            acc[jm] -= q
        else:
            acc[j] += q
            acc[jm] -= math.exp(s[j] - s[jm]) * q
        if want_jac:
            jac[j, jm] += dq
            jac[j, j] -= dq
            jac[jm, jm] -= dq
            jac[jm, j] += dq
    # suction-delivery (sec. 3.3) and drain (sec. 3.4) leakages leave the delivery volume
    q_sd = prm[P_GSD] * (pd - ps)
    q_dr = prm[P_GDR] * (pd - ps)
    q_rest = 0.0
    acc[N] -= q_sd + q_dr
    if restriction:
        q_rest, dqr = orifice_flow(pd - prm[P_PTANK], prm[P_AREST], cd, lam, rho, mu)
        acc[N] -= q_rest
    # assemble
    for j in range(N):
        tj = theta + j * shift
        vol = interp(tab, V, tj, period)
        beta, dbeta = bulk_modulus(y[j], beta_s, ratio, p_atm, band, p_vap)
        net = acc[j] - omega * interp(tab, DV, tj, period)
        f[j] = beta / vol * net
        if want_jac:
            for k in range(n1):
                jac[j, k] *= beta / vol
            jac[j, j] += dbeta / vol * net
    if restriction:
        beta, dbeta = bulk_modulus(pd, beta_s, ratio, p_atm, band, p_vap)
        vl = prm[P_VLINE]
        f[N] = beta / vl * acc[N]
        if want_jac:
            jac[N, N] -= prm[P_GSD] + prm[P_GDR] + dqr
            for k in range(n1):
                jac[N, k] *= beta / vl
            jac[N, N] += dbeta / vl * acc[N]
    else:
        f[N] = 0.0
        if want_jac:
            for k in range(n1):
                jac[N, k] = 0.0
                jac[k, N] = 0.0
    flows[0] = q_del - q_sd - q_dr
    flows[1] = q_suc
    flows[2] = q_sd
    flows[3] = q_dr
    flows[4] = q_rest


@njit
def outer_gear_load(y, theta, omega, ex, ey, kc, tab, period, shift, prm):
    """Load on the outer gear, F_est = F_p + F_c (eqs. 24–27 of [1]) [N].

    Returns (fx, fy, contact_force, unloaded_flag).  Pressures act as gauge
    pressures (the ambient integrates to zero over the closed gear).  The
    viscous torque is eq. (27), corrected: 2π μ ω₂ L r³ / (c √(1−ε²)).
    """
    N = int(prm[P_N])
    p_atm = prm[FP_ATMOSPHERIC]
    fx = 0.0
    fy = 0.0
    cp = 0.0
    for j in range(N):
        tj = theta + j * shift
        pg = y[j] - p_atm
        fx += pg * interp(tab, FX, tj, period)       # eq. (24), p_j (printed p_i)
        fy += pg * interp(tab, FY, tj, period)
        cp += pg * interp(tab, TQ, tj, period)       # eq. (25)
    c = prm[P_C]
    eps = min(math.hypot(ex, ey) / c, 0.999)
    omega2 = omega * (N - 1) / N
    rj = prm[P_RJ]
    cjb = -2.0 * math.pi * prm[FP_VISCOSITY] * omega2 * prm[P_WIDTH] * rj ** 3 / (c * math.sqrt(1.0 - eps * eps))  # eq. (27), corrected
    tk = theta + kc * shift
    arm = interp(tab, ARM, tk, period)
    fc = 0.0
    unloaded = 0
    if abs(arm) > 1e-9:
        fc = -(cp + cjb) / arm                     # eq. (26): C_p + C_jb + r_c × F_c = 0
    if fc < 0.0:
        fc = 0.0
        unloaded = 1
    nx = interp(tab, GX, tk, period)
    ny = interp(tab, GY, tk, period)
    nn = math.hypot(nx, ny)
    return fx + fc * nx / nn, fy + fc * ny / nn, fc, unloaded


@njit
def pressure_step(y, theta, omega, ps, pd, h, h_gap0, h_gap1, tab, period, shift, prm, ynew, flows):
    """One ROS2 step of the pressures over dt = h (gaps at the two stage angles given)."""
    n1 = y.shape[0]
    f0 = np.empty(n1)
    f1 = np.empty(n1)
    jac = np.empty((n1, n1))
    rhs(y, theta, omega, ps, pd, h_gap0, tab, period, shift, prm, f0, jac, True, flows)
    w = -GAMMA * h * jac
    for i in range(n1):
        w[i, i] += 1.0
    k1 = np.linalg.solve(w, f0)
    y1 = y + h * k1
    rhs(y1, theta + omega * h, omega, ps, pd, h_gap1, tab, period, shift, prm, f1, jac, False, flows)
    k2 = np.linalg.solve(w, f1 - 2.0 * k1)
    for i in range(n1):
        ynew[i] = y[i] + 1.5 * h * k1[i] + 0.5 * h * k2[i]


@njit
def _clamp_floor(y, p_floor, restriction):
    n = y.shape[0] if restriction else y.shape[0] - 1
    hits = 0
    for i in range(n):
        if y[i] < p_floor:
            y[i] = p_floor
            hits += 1
    return hits


@njit
def integrate(y, e, theta, t, omega, ps, pd, n_steps, h, tab, period, shift, prm, bearing_kind,
              rec, rec_p, rec_gap, counters, acc):
    """Advance ``n_steps`` fixed steps of size h [s] (fixed or mobility bearing).

    Writes one record per step into ``rec`` (N_REC columns), ``rec_p`` (chamber
    pressures) and ``rec_gap`` (gap heights); ``acc`` accumulates
    [∫q_del dt, ∫q_suc dt, ∫q_sd dt, ∫q_dr dt, ∫q_rest dt] (trapezoidal).
    Returns the new (theta, t, ex, ey).
    """
    N = int(prm[P_N])
    delta = prm[P_DELTA]
    restriction = prm[P_MODE] > 0.5
    c = prm[P_C]
    epsmax = prm[P_EPSMAX]
    coef = np.empty(9)
    g0 = np.empty(N)
    g1 = np.empty(N)
    ynew = np.empty(y.shape[0])
    flows = np.empty(5)
    flows_prev = np.empty(5)
    ex, ey = e[0], e[1]
    p_floor = prm[FP_VAPOUR] + 1.0
    omega2 = omega * (N - 1) / N
    # flows at the start of the step (for trapezoidal accumulation)
    ex, ey, gam, kc = contact(tab, period, shift, N, delta, theta, ex, ey, g0, coef)
    fdum = np.empty(y.shape[0])
    jdum = np.empty((y.shape[0], y.shape[0]))
    rhs(y, theta, omega, ps, pd, g0, tab, period, shift, prm, fdum, jdum, False, flows_prev)
    for n in range(n_steps):
        ex, ey, gam, kc = contact(tab, period, shift, N, delta, theta, ex, ey, g0, coef)
        _x, _y, _g, _k = contact(tab, period, shift, N, delta, theta + omega * h, ex, ey, g1, coef)
        pressure_step(y, theta, omega, ps, pd, h, g0, g1, tab, period, shift, prm, ynew, flows)
        counters[C_CAVITATION] += _clamp_floor(ynew, p_floor, restriction)
        for i in range(y.shape[0]):
            y[i] = ynew[i]
        if not restriction:
            y[N] = pd
        theta_new = theta + omega * h
        fx = 0.0
        fy = 0.0
        if bearing_kind == BEARING_MOBILITY:
            # Heun on the journal centre, load from the new pressures
            fx, fy, fc, unl = outer_gear_load(y, theta_new, omega, ex, ey, kc, tab, period, shift, prm)
            counters[C_CONTACT_UNLOADED] += unl
            d1x, d1y = mobility_velocity(ex, ey, fx, fy, omega2, c, prm[P_WIDTH], 2.0 * prm[P_RJ],
                                         prm[FP_VISCOSITY])
            px, py, _g, kc2 = contact(tab, period, shift, N, delta, theta_new, ex + h * d1x, ey + h * d1y,
                                      g1, coef)
            fx2, fy2, fc2, unl2 = outer_gear_load(y, theta_new, omega, px, py, kc2, tab, period, shift, prm)
            d2x, d2y = mobility_velocity(px, py, fx2, fy2, omega2, c, prm[P_WIDTH], 2.0 * prm[P_RJ],
                                         prm[FP_VISCOSITY])
            ex += 0.5 * h * (d1x + d2x)
            ey += 0.5 * h * (d1y + d2y)
            en = math.hypot(ex, ey)
            if en > epsmax * c:
                ex *= epsmax * c / en
                ey *= epsmax * c / en
                counters[C_HOUSING_CONTACT] += 1
        elif bearing_kind == BEARING_FIXED:
            fx, fy, fc, unl = outer_gear_load(y, theta_new, omega, ex, ey, kc, tab, period, shift, prm)
        ex0, ey0 = ex, ey
        ex, ey, gam, kc = contact(tab, period, shift, N, delta, theta_new, ex, ey, g1, coef)
        if ex != ex0 or ey != ey0:
            counters[C_GEAR_CONTACT] += 1
        rhs(y, theta_new, omega, ps, pd, g1, tab, period, shift, prm, fdum, jdum, False, flows)
        for i in range(5):
            acc[i] += 0.5 * h * (flows_prev[i] + flows[i])
            flows_prev[i] = flows[i]
        theta = theta_new
        t += h
        counters[C_STEPS] += 1
        rec[n, R_T] = t
        rec[n, R_THETA] = theta
        rec[n, R_QDEL] = flows[0]
        rec[n, R_QSUC] = flows[1]
        rec[n, R_QSD] = flows[2]
        rec[n, R_QDR] = flows[3]
        rec[n, R_QREST] = flows[4]
        rec[n, R_PD] = y[N]
        rec[n, R_EX] = ex
        rec[n, R_EY] = ey
        rec[n, R_FX] = fx
        rec[n, R_FY] = fy
        rec[n, R_GAMMA] = gam
        rec[n, R_KC] = kc
        rec[n, R_MIN_GAP] = np.min(g1)
        for i in range(N):
            rec_p[n, i] = y[i]
            rec_gap[n, i] = g1[i]
    e[0] = ex
    e[1] = ey
    return theta, t
