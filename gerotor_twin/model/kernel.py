"""Compiled hot loop of the pump model: right-hand side, Jacobian, stepper.

State vector y (length N+1): the log-densities y = ln(ρ/ρ₀) of the N
chambers and of the delivery volume (a state in ``restriction`` mode; held at
the imposed pressure in ``imposed`` mode).  Pressures follow from the
barotropic equation of state, dp = β(p) dy, β of eq. (23) smoothed
(:mod:`gerotor_twin.hydraulics.fluid`).  Carrying ln ρ instead of p makes the
mass balance exact and removes the dβ/dp feedback of the cavitation switch
from the Jacobian: in a cavitating chamber (β → 0 towards the vapour
pressure) inflow raises y while p stays near the floor, as a collapsing
vapour fraction would; p never falls below the vapour pressure.

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
    P_AREST, P_PTANK, P_EPSMAX, P_PHI, P_SHI, P_PLO, P_SLO, P_ATOL = range(7, 28)
N_PARAMS = 28
BAND_NODES = 256   # tabulated inverse of the equation of state inside the switch band (appended to prm)

# ------------------------------------------------------------------ outputs
# per-step record columns besides the chamber pressures and gaps
R_T, R_THETA, R_QDEL, R_QSUC, R_QSD, R_QDR, R_QREST, R_PD, R_EX, R_EY, R_FX, R_FY, R_GAMMA, R_KC, \
    R_MIN_GAP = range(15)
N_REC = 15

# counters
C_STEPS, C_CAVITATION, C_CONTACT_UNLOADED, C_HOUSING_CONTACT, C_GEAR_CONTACT, C_SUBSTEPS, C_REJECTED, \
    C_FAILED = range(8)
N_COUNTERS = 8

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
        h_out[k] = max(_gap_value(cmat[k], delta, ex, ey, gamma), 0.0)
        if h_out[k] < h_out[kc]:
            kc = k
    return ex, ey, gamma, kc


@njit
def log_density_of(p, prm):
    """ln(ρ(p)/ρ₀) [-]: closed forms outside the switch band, quadrature inside.

    Same function as :func:`gerotor_twin.hydraulics.fluid.log_density`, with the
    band-end anchors precomputed in ``prm`` (P_SLO, P_SHI).
    """
    if p >= prm[P_PHI]:
        return prm[P_SHI] + (p - prm[P_PHI]) / prm[FP_BULK_MODULUS]
    if p >= prm[P_PLO]:
        return log_density(p, prm[FP_BULK_MODULUS], prm[FP_CAVITATION_RATIO], prm[FP_ATMOSPHERIC],
                           prm[FP_SWITCH_BAND], prm[FP_VAPOUR])
    width = prm[P_PLO] - prm[FP_VAPOUR]
    beta_low = prm[FP_BULK_MODULUS] / prm[FP_CAVITATION_RATIO]
    sig = max((p - prm[FP_VAPOUR]) / width, 1e-300)
    return prm[P_SLO] + 0.5 * width / beta_low * math.log(sig / (2.0 - sig))


@njit
def pressure_of(s, prm):
    """Absolute pressure [Pa] of log-density s (inverse of :func:`log_density_of`)."""
    if s >= prm[P_SHI]:
        return prm[P_PHI] + (s - prm[P_SHI]) * prm[FP_BULK_MODULUS]   # liquid, β = β*
    width = prm[P_PLO] - prm[FP_VAPOUR]
    if s <= prm[P_SLO]:                                                 # vapour floor, closed form
        beta_low = prm[FP_BULK_MODULUS] / prm[FP_CAVITATION_RATIO]
        x = 2.0 * (s - prm[P_SLO]) * beta_low / width
        if x < -700.0:
            return prm[FP_VAPOUR]
        big_e = math.exp(x)
        return prm[FP_VAPOUR] + width * 2.0 * big_e / (1.0 + big_e)
    # inside the switch band: tabulated inverse (uniform in s), then one Newton step (dp/ds = β)
    x = (s - prm[P_SLO]) / (prm[P_SHI] - prm[P_SLO]) * (BAND_NODES - 1)
    i = min(int(x), BAND_NODES - 2)
    f = x - i
    p = prm[N_PARAMS + i] * (1.0 - f) + prm[N_PARAMS + i + 1] * f
    beta, _d = bulk_modulus(p, prm[FP_BULK_MODULUS], prm[FP_CAVITATION_RATIO], prm[FP_ATMOSPHERIC],
                            prm[FP_SWITCH_BAND], prm[FP_VAPOUR])
    return p - (log_density_of(p, prm) - s) * beta


@njit
def rhs(y, theta, omega, ps, pd_in, h_gap, tab, period, shift, prm, f, jac, want_jac, flows):
    """Right-hand side dy/dt of the log-densities y = ln(ρ/ρ₀) [1/s], and ∂f/∂y.

    Mass conservation per volume: d(ρV)/dt = Σ ρ_up Q, i.e.
    dy_j/dt = (Σ (ρ_up/ρ_j) Q − ω dV_j/dθ) / V_j, and dp = β dy, so this is
    eq. (20) (corrected) multiplied through by 1/β.  ``flows`` receives
    (q_delivery_out, q_suction_in, q_sd, q_drain, q_restriction) [m³/s].
    """
    N = int(prm[P_N])
    beta_s, ratio, p_atm = prm[FP_BULK_MODULUS], prm[FP_CAVITATION_RATIO], prm[FP_ATMOSPHERIC]
    band, p_vap = prm[FP_SWITCH_BAND], prm[FP_VAPOUR]
    rho, mu = prm[FP_DENSITY], prm[FP_VISCOSITY]
    cd, lam = prm[P_CD], prm[P_LAMBDA]
    b, dh, glat = prm[P_WIDTH], prm[P_DH], prm[P_GLAT]
    restriction = prm[P_MODE] > 0.5
    n1 = N + 1
    p = np.empty(n1)
    beta = np.empty(n1)
    s = np.empty(n1)
    for i in range(n1):
        if i == N and not restriction:
            p[i] = pd_in
            s[i] = log_density_of(pd_in, prm)
        else:
            p[i] = pressure_of(y[i], prm)
            s[i] = y[i]
        beta[i], _db = bulk_modulus(p[i], beta_s, ratio, p_atm, band, p_vap)
    pd = p[N]
    s_ps = log_density_of(ps, prm)
    acc = np.zeros(n1)        # Σ (ρ_up/ρ_i) Q_i into each volume [m³/s]
    if want_jac:
        for i in range(n1):
            for k in range(n1):
                jac[i, k] = 0.0
    q_del = 0.0
    q_suc = 0.0
    m_suc = 0.0
    m_del = 0.0
    for j in range(N):
        tj = theta + j * shift
        pj = p[j]
        # suction port -> chamber j, eq. (21)
        q, dq = orifice_flow(ps - pj, interp(tab, AS, tj, period), cd, lam, rho, mu)
        fac = math.exp(s_ps - s[j]) if q > 0.0 else 1.0
        acc[j] += fac * q
        q_suc += q
        m_suc += math.exp(s_ps if q > 0.0 else s[j]) * q
        if want_jac:
            jac[j, j] -= fac * dq * beta[j]
        # delivery port -> chamber j
        q, dq = orifice_flow(pd - pj, interp(tab, AD, tj, period), cd, lam, rho, mu)
        m_del -= math.exp(s[N] if q > 0.0 else s[j]) * q
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
            jac[j, j] -= dq * beta[j]
            jac[N, j] += dq * beta[j]
            jac[j, N] += dq * beta[N]
            jac[N, N] -= dq * beta[N]
        # tooth-tip gap at lobe j: chamber j-1 -> chamber j, eq. (22)
        jm = (j - 1) % N
        hk = h_gap[j]
        q = 0.0
        dq = 0.0
        if hk > 0.0:
            krel = interp(tab, KREL, tj, period)
            le = 2.0 * math.sqrt(2.0 * hk * dh / krel)
            q, dq = tooth_tip_flow(p[jm] - pj, hk, le, omega * interp(tab, VR, tj, period), b, mu)
        # lateral leakage across the lobe land, sec. 3.2 (independent of the micro-motion, as in [1])
        q += glat * (p[jm] - pj)
        dq += glat
        if q > 0.0:
            acc[j] += math.exp(s[jm] - s[j]) * q
            acc[jm] -= q
        else:
            acc[j] += q
            acc[jm] -= math.exp(s[j] - s[jm]) * q
        if want_jac:
            jac[j, jm] += dq * beta[jm]
            jac[j, j] -= dq * beta[j]
            jac[jm, jm] -= dq * beta[jm]
            jac[jm, j] += dq * beta[j]
    # suction-delivery (sec. 3.3) and drain (sec. 3.4) leakages leave the delivery volume
    q_sd = prm[P_GSD] * (pd - ps)
    q_dr = prm[P_GDR] * (pd - ps)
    q_rest = 0.0
    dqr = 0.0
    acc[N] -= q_sd + q_dr
    if restriction:
        q_rest, dqr = orifice_flow(pd - prm[P_PTANK], prm[P_AREST], cd, lam, rho, mu)
        acc[N] -= q_rest
    # assemble: dy/dt = (Σ ρ-weighted Q − ω dV/dθ) / V
    for j in range(N):
        tj = theta + j * shift
        vol = interp(tab, V, tj, period)
        f[j] = (acc[j] - omega * interp(tab, DV, tj, period)) / vol
        if want_jac:
            for k in range(n1):
                jac[j, k] /= vol
    if restriction:
        vl = prm[P_VLINE]
        f[N] = acc[N] / vl
        if want_jac:
            jac[N, N] -= (prm[P_GSD] + prm[P_GDR] + dqr) * beta[N]
            for k in range(n1):
                jac[N, k] /= vl
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
    flows[5] = m_suc
    flows[6] = m_del


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
def ros2_step(y, theta, omega, ps, pd, h, h_gap0, h_gap1, tab, period, shift, prm, ynew, err, flows):
    """One ROS2 step over dt = h (gaps at the two stage angles); ``err`` gets the embedded error."""
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
        err[i] = 0.5 * h * (k1[i] + k2[i])        # against the embedded first-order y + h k1


@njit
def pressure_step(y, theta, omega, ps, pd, big_h, ex, ey, tab, period, shift, prm, ctrl, counters):
    """Advance the pressures over one output step ``big_h`` [s] with adaptive ROS2 sub-steps.

    The gear displacement (ex, ey) is frozen over the step; the gaps follow
    the shaft angle.  ``ctrl[0]`` carries the proposed sub-step between calls.
    Error control on the log-densities with absolute tolerance ``prm[P_ATOL]``.
    """
    N = int(prm[P_N])
    n1 = y.shape[0]
    coef = np.empty(9)
    g0 = np.empty(N)
    g1 = np.empty(N)
    ynew = np.empty(n1)
    err = np.empty(n1)
    flows = np.empty(7)
    atol = prm[P_ATOL]
    delta = prm[P_DELTA]
    h = big_h if ctrl[0] <= 0.0 else min(big_h, ctrl[0])
    h_min = big_h * 1e-5
    done = 0.0
    while done < big_h * (1.0 - 1e-12):
        h = min(h, big_h - done)
        th = theta + omega * done
        contact(tab, period, shift, N, delta, th, ex, ey, g0, coef)
        contact(tab, period, shift, N, delta, th + omega * h, ex, ey, g1, coef)
        ros2_step(y, th, omega, ps, pd, h, g0, g1, tab, period, shift, prm, ynew, err, flows)
        en = 0.0
        for i in range(n1):
            v = abs(err[i]) / atol
            if not (v <= en):          # also catches NaN
                en = v
        if en <= 1.0 or h <= h_min:
            if en > 1.0 or not np.all(np.isfinite(ynew)):
                counters[C_FAILED] += 1
                if not np.all(np.isfinite(ynew)):
                    return
            for i in range(n1):
                y[i] = ynew[i]
            done += h
            counters[C_SUBSTEPS] += 1
        else:
            counters[C_REJECTED] += 1
        fac = 4.0 if en < 1e-8 else min(4.0, max(0.2, 0.9 / math.sqrt(en)))
        h = max(h * fac, h_min)
    ctrl[0] = h


@njit
def to_pressures(y, prm, out):
    """Pressures [Pa] of the log-density state; returns how many volumes are cavitating."""
    cav = 0
    for i in range(y.shape[0]):
        out[i] = pressure_of(y[i], prm)
        if out[i] < prm[FP_ATMOSPHERIC] - 0.5 * prm[FP_SWITCH_BAND]:
            cav += 1
    return cav


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
    flows = np.empty(7)
    flows_prev = np.empty(7)
    ex, ey = e[0], e[1]
    pres = np.empty(y.shape[0])
    omega2 = omega * (N - 1) / N
    # flows at the start of the step (for trapezoidal accumulation)
    ex, ey, gam, kc = contact(tab, period, shift, N, delta, theta, ex, ey, g0, coef)
    fdum = np.empty(y.shape[0])
    jdum = np.empty((y.shape[0], y.shape[0]))
    rhs(y, theta, omega, ps, pd, g0, tab, period, shift, prm, fdum, jdum, False, flows_prev)
    for n in range(n_steps):
        ex, ey, gam, kc = contact(tab, period, shift, N, delta, theta, ex, ey, g0, coef)
        pressure_step(y, theta, omega, ps, pd, h, ex, ey, tab, period, shift, prm, acc[5:6], counters)
        if not restriction:
            y[N] = log_density_of(pd, prm)
        counters[C_CAVITATION] += to_pressures(y, prm, pres)
        theta_new = theta + omega * h
        fx = 0.0
        fy = 0.0
        if bearing_kind == BEARING_MOBILITY:
            # Heun on the journal centre, load from the new pressures
            fx, fy, fc, unl = outer_gear_load(pres, theta_new, omega, ex, ey, kc, tab, period, shift, prm)
            counters[C_CONTACT_UNLOADED] += unl
            d1x, d1y = mobility_velocity(ex, ey, fx, fy, omega2, c, prm[P_WIDTH], 2.0 * prm[P_RJ],
                                         prm[FP_VISCOSITY])
            px, py, _g, kc2 = contact(tab, period, shift, N, delta, theta_new, ex + h * d1x, ey + h * d1y,
                                      g1, coef)
            fx2, fy2, fc2, unl2 = outer_gear_load(pres, theta_new, omega, px, py, kc2, tab, period, shift, prm)
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
            fx, fy, fc, unl = outer_gear_load(pres, theta_new, omega, ex, ey, kc, tab, period, shift, prm)
        ex0, ey0 = ex, ey
        ex, ey, gam, kc = contact(tab, period, shift, N, delta, theta_new, ex, ey, g1, coef)
        if ex != ex0 or ey != ey0:
            counters[C_GEAR_CONTACT] += 1
        rhs(y, theta_new, omega, ps, pd, g1, tab, period, shift, prm, fdum, jdum, False, flows)
        for i in range(7):
            k = i if i < 5 else i + 1          # acc[5] is the sub-step carrier
            acc[k] += 0.5 * h * (flows_prev[i] + flows[i])
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
        rec[n, R_PD] = pres[N]
        rec[n, R_EX] = ex
        rec[n, R_EY] = ey
        rec[n, R_FX] = fx
        rec[n, R_FY] = fy
        rec[n, R_GAMMA] = gam
        rec[n, R_KC] = kc
        rec[n, R_MIN_GAP] = np.min(g1)
        for i in range(N):
            rec_p[n, i] = pres[i]
            rec_gap[n, i] = g1[i]
    e[0] = ex
    e[1] = ey
    return theta, t
