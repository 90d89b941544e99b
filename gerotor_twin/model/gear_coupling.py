r"""The outer gear inside the pressure step: the mobility method's velocity as a squeeze flow of the stages.

The mobility method gives the outer-gear velocity as an algebraic function of its position and
load, :math:`\dot{\mathbf e} = \mathbf M(\mathbf e, \mathbf F)` (no inertia: sec. 2.2 of [1]), and
the load is linear in the chamber pressures (Eqs. (24)–(26) of [1]).  Over one output step the
position is held at :math:`\mathbf e_0` and the velocity is linearised in the load,

.. math::
    \dot{\mathbf e}(p, \theta) = \dot{\mathbf e}_0 + G\,\big(\mathbf F(p, \theta) - \mathbf F_0\big),
    \qquad G = \partial\mathbf M/\partial\mathbf F\,(\mathbf e_0, \mathbf F_0),

    \mathbf F(p, \theta) = \sum_j (p_j - p_{atm})\,\big(\mathbf f_j(\theta) + T_j(\theta)\,\mathbf c\big)
        + C_{jb}\,\mathbf c,\qquad \mathbf c = -\hat{\mathbf n}/r_c

(:math:`\mathbf f_j`, :math:`T_j`: force and torque per unit pressure, Eqs. (24)–(25); the contact
force of Eq. (26) with the lever :math:`r_c` and normal :math:`\hat{\mathbf n}` of the lobe in
contact and the journal torque :math:`C_{jb}` held at the step start; :math:`\mathbf c = 0` while
the contact is unloaded).  Each chamber's squeeze flow :math:`-\mathbf f_j\cdot\dot{\mathbf e}`
(:mod:`.volumes`: :math:`\partial V_j/\partial\mathbf e = \mathbf f_j`) and its Jacobian

.. math::
    \frac{\partial}{\partial y_k}\big(-\mathbf f_j\cdot\dot{\mathbf e}\big)
        = -\big(G^{T}\mathbf f_j\big)\cdot\mathbf g_k\,\beta_k,\qquad
    \mathbf g_k = \mathbf f_k + T_k\,\mathbf c

enter the ROS2 stages, so a pressure spike moves the gear, and the gear relieves it, within the
same sub-step; the partitioned scheme (gear moved after the step by the end pressures, its squeeze
spread over the next step) answers one output step late.  The trapezoid of
:math:`\dot{\mathbf e}` over the accepted sub-steps is the gear's move (so the volumes the stages
squeezed are where the gear is); the housing cap and the overlap check's pull-back change it a
little, and that remainder is squeezed over the next step as before (:func:`.volumes.move_volumes`).
Numerics config ``gear_coupling: partitioned`` keeps the former scheme; Method 1 and the FDM
bearing always use it (docs/numerics.md, "The gear in the stages").

References
----------
.. [1] The paper, sec. 2.2 (mobility method) and 3.6 (``../shared/paper``).
"""
from __future__ import annotations

import math

from .._jit import njit
from ..bearing.mobility import mobility_kernel
from ..geometry.tables import ARM, FX, FY, GX, GY, TQ
from .contact import column, locate

__all__ = ["GC_ON", "N_GEAR", "coupled_load", "coupled_load_at", "gear_velocity", "gear_squeeze", "linearise",
           "linearise_with", "set_velocity", "close_pending", "gear_move"]

#: ``Workspace.gear``: coupling on (1) or off (0); ė₀ [m/s]; F₀ [N]; G row-major [m/(s·N)]; the contact
#: coefficient c [1/m] and the constant load C_jb·c [N]; ė at the last right-hand side; ė at the last
#: accepted state; ∫ė dt over the output step so far [m]; length of the accepted sub-step whose ∫ė dt is
#: pending [s]
(GC_ON, GC_V0X, GC_V0Y, GC_F0X, GC_F0Y, GC_GXX, GC_GXY, GC_GYX, GC_GYY, GC_CX, GC_CY, GC_FCX, GC_FCY,
 GC_VX, GC_VY, GC_VPX, GC_VPY, GC_DEX, GC_DEY, GC_PEND) = range(20)
N_GEAR = 20

#: Relative load step of the finite-difference G (the velocity is smooth in F away from F = 0).
_DF_REL = 1e-6


@njit(inline="always")
def coupled_load(pres, theta, tab, n, p_atm, gc, rows):
    """Load F(p, θ) [N] with the contact held as at the step start; per chamber (f_j, g_j) into ``rows`` (N, 4).

    ``pres``: chamber pressures [Pa]; ``tab``, ``n``: the kernel tables and N; ``p_atm`` [Pa].
    """
    fx = gc[GC_FCX]
    fy = gc[GC_FCY]
    for j in range(n):
        i0, i1, f = locate(tab, theta + j * tab.shift)
        a = column(tab, FX, i0, i1, f)
        b = column(tab, FY, i0, i1, f)
        t = column(tab, TQ, i0, i1, f)
        gx = a + t * gc[GC_CX]
        gy = b + t * gc[GC_CY]
        rows[j, 0] = a
        rows[j, 1] = b
        rows[j, 2] = gx
        rows[j, 3] = gy
        pg = pres[j] - p_atm
        fx += pg * gx                                   # Eqs. (24)-(26)
        fy += pg * gy
    return fx, fy


@njit(inline="always")
def gear_velocity(fx, fy, gc):
    """ė [m/s] of the linearised mobility at the load (fx, fy) [N]."""
    dx = fx - gc[GC_F0X]
    dy = fy - gc[GC_F0Y]
    return (gc[GC_V0X] + gc[GC_GXX] * dx + gc[GC_GXY] * dy,
            gc[GC_V0Y] + gc[GC_GYX] * dx + gc[GC_GYY] * dy)


@njit          # called, not inlined: inlined into the right-hand side it slowed the fixed centre too (3 %)
def gear_squeeze(theta, tab, n, p_atm, p, beta, acc, gc, rows, jac, want_jac):
    """Squeeze flow −f_j·ė of every chamber into ``acc`` [m³/s] (and its ∂/∂y into ``jac``, before the volume
    scaling of :func:`.flows.assemble`); ė into ``gc``.  ``p``, ``beta``: pressures and bulk moduli of the
    volumes [Pa]; takes arrays, not the ``Workspace`` (as :func:`.flows.closing_ports`)."""
    fx, fy = coupled_load(p, theta, tab, n, p_atm, gc, rows)
    vx, vy = gear_velocity(fx, fy, gc)
    gc[GC_VX] = vx
    gc[GC_VY] = vy
    for j in range(n):
        acc[j] -= rows[j, 0] * vx + rows[j, 1] * vy
    if want_jac:
        for j in range(n):
            ax = gc[GC_GXX] * rows[j, 0] + gc[GC_GYX] * rows[j, 1]      # Gᵀ f_j
            ay = gc[GC_GXY] * rows[j, 0] + gc[GC_GYY] * rows[j, 1]
            for k in range(n):
                jac[j, k] -= (ax * rows[k, 2] + ay * rows[k, 3]) * beta[k]
        _squeeze_rate(theta, tab, n, p_atm, p, gc, rows, vx, vy, jac)


@njit(inline="always")
def _squeeze_rate(theta, tab, n, p_atm, p, gc, rows, vx, vy, jac):
    """∂/∂θ of the squeeze flows at fixed pressures [m³/(s·rad)] into ∂f/∂t's column N+1 of ``jac`` (before
    :func:`.flows.assemble` scales it), from the slopes of the tables' linear interpolation:
    −f_j′·ė − f_j·G·∂F/∂θ, ∂F/∂θ = Σ_k (p_k − p_atm)(f_k′ + T_k′ c)."""
    dfx = 0.0
    dfy = 0.0
    for j in range(n):
        i0, i1, _f = locate(tab, theta + j * tab.shift)
        ax = (tab.rows[i1, FX] - tab.rows[i0, FX]) * tab.scale
        ay = (tab.rows[i1, FY] - tab.rows[i0, FY]) * tab.scale
        at = (tab.rows[i1, TQ] - tab.rows[i0, TQ]) * tab.scale
        pg = p[j] - p_atm
        dfx += pg * (ax + at * gc[GC_CX])
        dfy += pg * (ay + at * gc[GC_CY])
        jac[j, n + 1] -= ax * vx + ay * vy
    dvx = gc[GC_GXX] * dfx + gc[GC_GXY] * dfy
    dvy = gc[GC_GYX] * dfx + gc[GC_GYY] * dfy
    for j in range(n):
        jac[j, n + 1] -= rows[j, 0] * dvx + rows[j, 1] * dvy


@njit(inline="always")
def coupled_load_at(ex, ey, theta, omega, kc, km, pres, gc, rows):
    """Set up the coupled load of the next output step at (ex, ey) [m], θ [rad], the lobe kc in contact and the
    chamber pressures ``pres`` [Pa] (as :func:`.loads.outer_gear_load`: Eqs. (24)–(27) of [1]); returns F₀ [N]."""
    tab, pc = km.tab, km.pc
    n = pc.n
    cp = 0.0
    for j in range(n):
        i0, i1, f = locate(tab, theta + j * tab.shift)
        cp += (pres[j] - km.eos.p_atm) * column(tab, TQ, i0, i1, f)     # Eq. (25)
    c = pc.housing_clearance
    eps = min(math.hypot(ex, ey) / c, 0.999)
    omega2 = omega * (n - 1) / n
    cjb = (-2.0 * math.pi * pc.viscosity * omega2 * pc.width * pc.journal_radius ** 3
           / (c * math.sqrt(1.0 - eps * eps)))                          # Eq. (27), corrected
    i0, i1, f = locate(tab, theta + kc * tab.shift)
    arm = column(tab, ARM, i0, i1, f)
    gc[GC_CX] = 0.0
    gc[GC_CY] = 0.0
    if abs(arm) > 1e-9 and -(cp + cjb) / arm > 0.0:                     # Eq. (26), contact loaded
        nx = column(tab, GX, i0, i1, f)
        ny = column(tab, GY, i0, i1, f)
        nn = math.hypot(nx, ny)
        gc[GC_CX] = -nx / (nn * arm)
        gc[GC_CY] = -ny / (nn * arm)
    gc[GC_FCX] = cjb * gc[GC_CX]
    gc[GC_FCY] = cjb * gc[GC_CY]
    return coupled_load(pres, theta, tab, n, km.eos.p_atm, gc, rows)


@njit(inline="always")
def load_step(fx, fy):
    """Load step [N] of the finite-difference G at the load (fx, fy) [N]."""
    return _DF_REL * max(math.hypot(fx, fy), 1.0)


@njit(inline="always")
def set_velocity(gc, fx, fy, v0, v1, v2, d):
    """Store F₀ = (fx, fy) [N], ė₀ = v0 and G from v1 = M(F₀ + d x̂), v2 = M(F₀ + d ŷ) [m/s] (d [N]); start the
    step's ∫ė dt and switch the coupling on."""
    gc[GC_F0X], gc[GC_F0Y] = fx, fy
    gc[GC_V0X], gc[GC_V0Y] = v0[0], v0[1]
    gc[GC_GXX], gc[GC_GYX] = (v1[0] - v0[0]) / d, (v1[1] - v0[1]) / d
    gc[GC_GXY], gc[GC_GYY] = (v2[0] - v0[0]) / d, (v2[1] - v0[1]) / d
    gc[GC_VX], gc[GC_VY] = v0[0], v0[1]
    gc[GC_VPX], gc[GC_VPY] = v0[0], v0[1]
    gc[GC_DEX] = 0.0
    gc[GC_DEY] = 0.0
    gc[GC_PEND] = 0.0
    gc[GC_ON] = 1.0


@njit(inline="always")
def linearise(ex, ey, theta, omega, kc, km, pres, gc, rows):
    """Set up the coupling of the next output step with the mobility method (compiled in): the coupled load
    (:func:`coupled_load_at`), ė₀ and G (Eqs. (7)–(13) of [1])."""
    pc = km.pc
    fx, fy = coupled_load_at(ex, ey, theta, omega, kc, km, pres, gc, rows)
    bp = (pc.housing_clearance, pc.width, 2.0 * pc.journal_radius, pc.viscosity)
    omega2 = omega * (pc.n - 1) / pc.n
    d = load_step(fx, fy)
    set_velocity(gc, fx, fy, mobility_kernel(ex, ey, fx, fy, omega2, bp),
                 mobility_kernel(ex, ey, fx + d, fy, omega2, bp), mobility_kernel(ex, ey, fx, fy + d, omega2, bp), d)


def linearise_with(bearing, ex, ey, theta, omega, kc, km, pres, gc, rows):
    """:func:`linearise` with another bearing model's velocity kernel (Method 1, FDM), from Python: numba caches
    no compiled function that takes a function."""
    fx, fy = coupled_load_at(ex, ey, theta, omega, kc, km, pres, gc, rows)
    omega2 = omega * (km.pc.n - 1) / km.pc.n
    d = load_step(fx, fy)
    k, bp = bearing.kernel, bearing.params
    set_velocity(gc, fx, fy, k(ex, ey, fx, fy, omega2, bp), k(ex, ey, fx + d, fy, omega2, bp),
                 k(ex, ey, fx, fy + d, omega2, bp), d)


@njit(inline="always")
def close_pending(gc):
    """Add the pending sub-step's trapezoid of ė (its start: the last accepted state; its end: the last
    right-hand side, which must be the one at the accepted end state) to ∫ė dt."""
    h = gc[GC_PEND]
    if h > 0.0:
        gc[GC_DEX] += 0.5 * h * (gc[GC_VPX] + gc[GC_VX])
        gc[GC_DEY] += 0.5 * h * (gc[GC_VPY] + gc[GC_VY])
    gc[GC_VPX] = gc[GC_VX]
    gc[GC_VPY] = gc[GC_VY]
    gc[GC_PEND] = 0.0


@njit(inline="always")
def gear_move(ex, ey, theta, km, pres, gc, rows):
    """The gear's position [m] after the output step from (ex, ey): the start plus ∫ė dt of the stages.

    Closes the pending trapezoid at the end pressures ``pres`` [Pa] and θ [rad].  The position
    dependence of **M** is taken at the step start (a Heun correction with the end load,
    h/2·[M(e₀ + Δe, F₁) − M(e₀, F₁)], measured worse: twice the position error against the
    reference, docs/numerics.md).
    """
    fx, fy = coupled_load(pres, theta, km.tab, km.pc.n, km.eos.p_atm, gc, rows)
    gc[GC_VX], gc[GC_VY] = gear_velocity(fx, fy, gc)
    close_pending(gc)
    return ex + gc[GC_DEX], ey + gc[GC_DEY]
