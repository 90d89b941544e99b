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
Where the step starts with the gear on the teeth, ė₀ and G are taken at the load the film carries there, the
free load plus the teeth's reactions solved through the full film law (:func:`linearise_in_contact`, Josephy–Newton
[2]).  Method 1 and the FDM bearing are linearised the same way with their own velocity kernels
(:func:`linearise_with`, :func:`linearise_short`); numerics config ``gear_coupling: partitioned`` keeps the former scheme for
every bearing model (docs/numerics.md, "The gear in the stages").

References
----------
.. [1] The paper, sec. 2.2 (mobility method) and 3.6 (``../shared/paper``).
.. [2] N.H. Josephy, "Newton's method for generalized equations", Technical Summary Report 1965, Mathematics
   Research Center, University of Wisconsin, 1979; F. Facchinei, J.-S. Pang, *Finite-Dimensional Variational
   Inequalities and Complementarity Problems*, Springer 2003, sec. 7.3.
.. [3] E. Hairer, G. Wanner, *Solving Ordinary Differential Equations II*, 2nd ed., Springer 1996, sec. IV.8
   (the simplified Newton iteration of implicit Runge–Kutta methods: its stopping criterion).
"""
from __future__ import annotations

import math

from .._jit import njit
from ..bearing.mobility import mobility_linearised_kernel
from ..bearing.base import cap_eccentricity
from ..bearing.reynolds_fd import fd_fields, fdm_kernel, fdm_load, velocity_from_fields
from ..bearing.short_bearing import short_kernel, short_load
from ..geometry.tables import ARM, FX, FY, GX, GY, TQ
from .contact import column, gap_coefficients, gap_unturned, gap_value, locate
from .loads import journal_torque
from .tooth_constraint import constrained_velocity, contact_pair, projected_mobility, reactions

__all__ = ["GC_ON", "N_GEAR", "coupled_load", "coupled_load_at", "gear_velocity", "gear_squeeze", "linearise",
           "linearise_mobility",
           "linearise_with", "linearise_short", "set_velocity", "set_constraint", "velocity_jacobian", "close_pending",
           "gear_move", "held_reactions", "contact_load", "contact_newton_step", "linearise_in_contact", "short_in_contact",
           "fdm_in_contact", "film_start", "film_iterate", "set_linearisation", "FULL_ITERATIONS", "FULL_RTOL",
           "CONTACT_RTOL_PER_TOLERANCE", "contact_rtol", "warm_reactions", "newton_converged",
           "substep_rates", "keep_first_stage"]

#: ``Workspace.gear``: coupling on (1) or off (0); ė₀ [m/s]; F₀ [N]; G row-major [m/(s·N)]; the contact
#: coefficient c [1/m] and the constant load C_jb·c [N]; ė at the last right-hand side; ė at the last
#: accepted state; ∫ė dt over the output step so far [m]; length of the accepted sub-step whose ∫ė dt is
#: pending [s]; shaft angle of the step start θ₀ [rad]; the angle [rad] whose table values ``ROW_RAW1`` holds,
#: and 1 if it holds any; the tooth constraint (``gear_coupling: constrained``, :mod:`.tooth_constraint`): on (1)
#: or off (0), the reactions λ₁, λ₂ at the last right-hand side [N], from ``GC_PAIR`` the two lobes' data of
#: :func:`.tooth_constraint.constrained_velocity` (10 slots), then the indices of those two lobes
#: (:func:`set_constraint`), the last Josephy–Newton's correction of the linearised reactions λ* − λ^lin [N] on the
#: teeth with the lobes they act on (:func:`warm_reactions`; 0 where it did not converge or the gear was free), and
#: from ``GC_CORR_BEFORE`` those four as that Josephy–Newton found them (what a state carries,
#: :attr:`.records.PumpState.contact_correction`, so that a call that starts there sets the step up as the call
#: before it did), then the first stage's velocity and reactions (``GC_STAGE1``)
(GC_ON, GC_V0X, GC_V0Y, GC_F0X, GC_F0Y, GC_GXX, GC_GXY, GC_GYX, GC_GYY, GC_CX, GC_CY, GC_FCX, GC_FCY,
 GC_VX, GC_VY, GC_VPX, GC_VPY, GC_DEX, GC_DEY, GC_PEND, GC_TH0, GC_TH_RAW1, GC_RAW1_OK,
 GC_CON, GC_LAM1, GC_LAM2, GC_PAIR) = range(27)
GC_LOBE1, GC_LOBE2, GC_CORR1, GC_CORR2, GC_CORR_LOBE1, GC_CORR_LOBE2, GC_CORR_BEFORE = range(GC_PAIR + 10, GC_PAIR + 17)
#: from ``GC_STAGE1``: ė [m/s] and λ₁, λ₂ [N] of the current first stage (:func:`keep_first_stage`)
GC_STAGE1 = GC_CORR_BEFORE + 4
N_GEAR = GC_STAGE1 + 4
#: columns of ``Workspace.gear_rows`` (N, 18): per chamber f_j = ∂V_j/∂e [m³/m] and g_j = ∂F/∂p_j [N/Pa] at θ₀,
#: their slopes in θ over the output step [1/rad], both at the angle of the last right-hand side, and the
#: table values (FX, FY, TQ) at θ₀ and at the step's end (reused as the next step's θ₀)
ROW_F, ROW_G, ROW_DF, ROW_DG, ROW_NOW_F, ROW_NOW_G, ROW_RAW0, ROW_RAW1 = 0, 2, 4, 6, 8, 10, 12, 15
N_ROWS = 18

#: Relative load step of the finite-difference G (the velocity is smooth in F away from F = 0).
_DF_REL = 1e-6


@njit(inline="always")
def _table_values(theta, tab, n, rows, col):
    """FX, FY, TQ (Eqs. (24)–(25) per unit pressure) of every chamber at θ [rad] into ``rows[:, col:col + 3]``."""
    for j in range(n):
        i0, i1, f = locate(tab, theta + j * tab.shift)
        rows[j, col] = column(tab, FX, i0, i1, f)
        rows[j, col + 1] = column(tab, FY, i0, i1, f)
        rows[j, col + 2] = column(tab, TQ, i0, i1, f)


@njit(inline="always")
def _load_rows(n, gc, rows, raw, col):
    """f_j and g_j = f_j + T_j c from the table values ``rows[:, raw:raw + 3]`` into ``rows[:, col:col + 4]``."""
    for j in range(n):
        a = rows[j, raw]
        b = rows[j, raw + 1]
        t = rows[j, raw + 2]
        rows[j, col] = a
        rows[j, col + 1] = b
        rows[j, col + 2] = a + t * gc[GC_CX]
        rows[j, col + 3] = b + t * gc[GC_CY]


@njit(inline="always")
def coupled_load(pres, theta, n, p_atm, gc, rows):
    """Load F(p, θ) [N] with the contact held as at the step start; f_j, g_j at θ into ``rows`` (``ROW_NOW_*``).

    f_j and g_j are interpolated linearly in θ over the output step (no table lookup in the right-hand
    side; their curvature over 1.5° is far below the tables' own resolution error).
    ``pres``: chamber pressures [Pa]; ``n``: N; ``p_atm`` [Pa].
    """
    w = theta - gc[GC_TH0]
    fx = gc[GC_FCX]
    fy = gc[GC_FCY]
    for j in range(n):
        for k in range(4):
            rows[j, ROW_NOW_F + k] = rows[j, ROW_F + k] + w * rows[j, ROW_DF + k]
        pg = pres[j] - p_atm
        fx += pg * rows[j, ROW_NOW_G]                   # Eqs. (24)-(26)
        fy += pg * rows[j, ROW_NOW_G + 1]
    return fx, fy


@njit(inline="always")
def gear_velocity(fx, fy, gc):
    """ė [m/s] of the linearised mobility at the load (fx, fy) [N]; with the tooth constraint on, the constrained
    velocity (:func:`.tooth_constraint.constrained_velocity`) and λ₁, λ₂ in ``gc``."""
    dx = fx - gc[GC_F0X]
    dy = fy - gc[GC_F0Y]
    vx = gc[GC_V0X] + gc[GC_GXX] * dx + gc[GC_GXY] * dy
    vy = gc[GC_V0Y] + gc[GC_GYX] * dx + gc[GC_GYY] * dy
    if gc[GC_CON] != 0.0:
        vx, vy, gc[GC_LAM1], gc[GC_LAM2] = constrained_velocity(vx, vy, gc[GC_PAIR:GC_PAIR + 10])
    return vx, vy


@njit(inline="always")
def velocity_jacobian(gc):
    """∂ė/∂F [m/(s·N)], row-major, at the last :func:`gear_velocity`: G; G_c where one contact holds (λ > 0); 0
    where both hold (:func:`.tooth_constraint.projected_mobility`)."""
    if gc[GC_CON] != 0.0:
        c = GC_PAIR
        if gc[GC_LAM1] > 0.0 and gc[GC_LAM2] > 0.0:
            return 0.0, 0.0, 0.0, 0.0
        if gc[GC_LAM1] > 0.0:
            return projected_mobility(gc[GC_GXX], gc[GC_GXY], gc[GC_GYX], gc[GC_GYY], gc[c], gc[c + 1])
        if gc[GC_LAM2] > 0.0:
            return projected_mobility(gc[GC_GXX], gc[GC_GXY], gc[GC_GYX], gc[GC_GYY], gc[c + 2], gc[c + 3])
    return gc[GC_GXX], gc[GC_GXY], gc[GC_GYX], gc[GC_GYY]


@njit          # called, not inlined: inlined into the right-hand side it slowed the fixed centre too (3 %)
def gear_squeeze(theta, n, p_atm, p, beta, acc, gc, rows, jac, want_jac):
    """Squeeze flow −f_j·ė of every chamber into ``acc`` [m³/s] (and its ∂/∂y into ``jac``, before the volume
    scaling of :func:`.flows.assemble`, and its ∂/∂θ into ∂f/∂t's column N+1); ė into ``gc``.  ``p``,
    ``beta``: pressures and bulk moduli of the volumes [Pa]; takes arrays, not the ``Workspace`` (as
    :func:`.flows.closing_ports`)."""
    fx, fy = coupled_load(p, theta, n, p_atm, gc, rows)
    vx, vy = gear_velocity(fx, fy, gc)
    gc[GC_VX] = vx
    gc[GC_VY] = vy
    for j in range(n):
        acc[j] -= rows[j, ROW_NOW_F] * vx + rows[j, ROW_NOW_F + 1] * vy
    if want_jac:
        dfx = 0.0                                       # ∂F/∂θ at fixed pressures
        dfy = 0.0
        for j in range(n):
            pg = p[j] - p_atm
            dfx += pg * rows[j, ROW_DG]
            dfy += pg * rows[j, ROW_DG + 1]
        gxx, gxy, gyx, gyy = velocity_jacobian(gc)
        dvx = gxx * dfx + gxy * dfy
        dvy = gyx * dfx + gyy * dfy
        held = gxx == 0.0 and gxy == 0.0 and gyx == 0.0 and gyy == 0.0    # both lobes hold: ė does not follow p
        for j in range(n):
            a = rows[j, ROW_NOW_F]
            b = rows[j, ROW_NOW_F + 1]
            if not held:
                ax = gxx * a + gyx * b                  # Gᵀ f_j
                ay = gxy * a + gyy * b
                for k in range(n):
                    jac[j, k] -= (ax * rows[k, ROW_NOW_G] + ay * rows[k, ROW_NOW_G + 1]) * beta[k]
            jac[j, n + 1] -= rows[j, ROW_DF] * vx + rows[j, ROW_DF + 1] * vy + a * dvx + b * dvy


@njit(inline="always")
def coupled_load_at(ex, ey, theta, omega, h, kc, km, pres, gc, rows):
    """Set up the coupled load of the output step of h [s] from θ [rad] at (ex, ey) [m], the lobe kc in contact
    and the chamber pressures ``pres`` [Pa] (as :func:`.loads.outer_gear_load`: Eqs. (24)–(27) of [1]):
    the contact coefficients, f_j and g_j at θ and their slopes to θ + ωh.  Returns F₀ [N]."""
    tab, pc = km.tab, km.pc
    n = pc.n
    if gc[GC_RAW1_OK] != 0.0 and gc[GC_TH_RAW1] == theta:              # the last step ended at θ
        for j in range(n):              # a loop: an array-to-slice copy compiles numba's shape-error message (2.3 s)
            for k in range(3):
                rows[j, ROW_RAW0 + k] = rows[j, ROW_RAW1 + k]
    else:
        _table_values(theta, tab, n, rows, ROW_RAW0)
    cp = 0.0
    for j in range(n):
        cp += (pres[j] - km.eos.p_atm) * rows[j, ROW_RAW0 + 2]          # Eq. (25)
    cjb = journal_torque(ex, ey, omega, pc)                               # Eq. (27), corrected
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
    gc[GC_TH0] = theta
    _load_rows(n, gc, rows, ROW_RAW0, ROW_F)
    dth = omega * h
    gc[GC_RAW1_OK] = 0.0
    if dth > 0.0:
        _table_values(theta + dth, tab, n, rows, ROW_RAW1)
        gc[GC_TH_RAW1] = theta + dth
        gc[GC_RAW1_OK] = 1.0
        _load_rows(n, gc, rows, ROW_RAW1, ROW_DF)
        for j in range(n):
            for k in range(4):
                rows[j, ROW_DF + k] = (rows[j, ROW_DF + k] - rows[j, ROW_F + k]) / dth
    else:
        rows[:, ROW_DF:ROW_DF + 4] = 0.0
    return coupled_load(pres, theta, n, km.eos.p_atm, gc, rows)


@njit(inline="always")
def load_step(fx, fy):
    """Load step [N] of the finite-difference G at the load (fx, fy) [N]."""
    return _DF_REL * max(math.hypot(fx, fy), 1.0)


@njit(inline="always")
def set_linearisation(gc, fx, fy, vx, vy, gxx, gxy, gyx, gyy):
    """Store F₀ = (fx, fy) [N], ė₀ = (vx, vy) [m/s] and G row-major [m/(s·N)]; start the step's ∫ė dt and switch
    the coupling on (the tooth constraint off until :func:`set_constraint`)."""
    gc[GC_F0X], gc[GC_F0Y] = fx, fy
    gc[GC_V0X], gc[GC_V0Y] = vx, vy
    gc[GC_GXX], gc[GC_GYX] = gxx, gyx
    gc[GC_GXY], gc[GC_GYY] = gxy, gyy
    gc[GC_VX], gc[GC_VY] = vx, vy
    gc[GC_VPX], gc[GC_VPY] = vx, vy
    gc[GC_DEX] = 0.0
    gc[GC_DEY] = 0.0
    gc[GC_PEND] = 0.0
    gc[GC_CON] = 0.0
    gc[GC_LAM1] = 0.0
    gc[GC_LAM2] = 0.0
    gc[GC_ON] = 1.0


@njit(inline="always")
def set_velocity(gc, fx, fy, v0, v1, v2, d):
    """:func:`set_linearisation` at F₀ = (fx, fy) [N] with ė₀ = v0 and G from v1 = M(F₀ + d x̂), v2 = M(F₀ + d ŷ)
    [m/s] (d [N])."""
    set_linearisation(gc, fx, fy, v0[0], v0[1], (v1[0] - v0[0]) / d, (v2[0] - v0[0]) / d, (v1[1] - v0[1]) / d,
                      (v2[1] - v0[1]) / d)


@njit(inline="always")
def set_constraint(ex, ey, theta, h, km, gc, cmat):
    """Switch the tooth constraint on for the output step of h [s] that ends at shaft angle θ [rad], the gear at
    (ex, ey) [m]: the two lobes whose gaps (inner gear unturned) are smallest there, their normals, G n and the
    rates r = g/h that hold each gap at zero at the step's end (Moreau's time-stepping, :mod:`.tooth_constraint`;
    the reactions at the step's start are solved with them, each sub-step takes its own, :func:`substep_rates`),
    and the two lobes' indices.  Call after :func:`set_velocity` (G).  The gap expansions at θ are left in ``cmat`` (N, 9), where the overlap
    check at the step's end reads them (:func:`.contact.contact`, ``reuse``)."""
    tab, pc = km.tab, km.pc
    g1 = g2 = math.inf
    n1x = n1y = n2x = n2y = 0.0
    k1 = k2 = -1
    for k in range(pc.n):
        gap_coefficients(tab, theta, k, cmat[k])
        c0 = cmat[k, 0]
        c1 = cmat[k, 1]
        cxx = cmat[k, 3]
        cxy = cmat[k, 4]
        cyy = cmat[k, 5]
        g = pc.tip_clearance + c0 * ex + c1 * ey + 0.5 * (cxx * ex * ex + 2.0 * cxy * ex * ey + cyy * ey * ey)
        nx = c0 + cxx * ex + cxy * ey                  # .contact.gap_value (γ = 0) and .tooth_constraint.gap_normal
        ny = c1 + cxy * ex + cyy * ey
        if g < g1:
            g2, n2x, n2y, k2 = g1, n1x, n1y, k1
            g1, n1x, n1y, k1 = g, nx, ny, k
        elif g < g2:
            g2, n2x, n2y, k2 = g, nx, ny, k
    gc[GC_LOBE1] = k1
    gc[GC_LOBE2] = k2
    contact_pair(gc[GC_GXX], gc[GC_GXY], gc[GC_GYX], gc[GC_GYY], n1x, n1y, n2x, n2y, g1 / h, g2 / h,
                 gc[GC_PAIR:GC_PAIR + 10])
    gc[GC_CON] = 1.0


#: Josephy–Newton iterations at most of the reactions through the full film law (:func:`contact_newton_step`)
FULL_ITERATIONS = 60
#: their convergence: the reactions' change below this fraction of |F₀| + |λ| [-] (the references', and the least
#: of :func:`contact_rtol`)
FULL_RTOL = 1e-10
#: the twin's convergence of those reactions as a fraction of its sub-step tolerance (:func:`contact_rtol`) [-]
CONTACT_RTOL_PER_TOLERANCE = 1e-4


@njit(inline="always")
def contact_rtol(pc):
    r"""The convergence [-] of the Josephy–Newton on the teeth (:func:`contact_newton_step`) for the numerics ``pc``:

    .. math:: \epsilon_\lambda = \max(\epsilon_{full},\ 10^{-4}\,\mathrm{tol})

    A reaction off by ε_λ(|F₀| + |λ|) moves the gear's velocity in the step by ≈ ε_λ of the load's velocity scale,
    and each chamber's squeeze flow (a share of its flows) by at most as much relative: four orders below the
    sub-step tolerance ``pc.tolerance`` that bounds the error of the pressures the flows integrate to.  The twin
    (tol 0.03) converges to 3e-6, a reference (tol 1e-8) to :data:`FULL_RTOL`.
    """
    return max(FULL_RTOL, CONTACT_RTOL_PER_TOLERANCE * pc.tolerance)


@njit(inline="always")
def held_reactions(gc):
    """The reactions (λ₁, λ₂) [N] at the step's start load F₀ of the contacts set by :func:`set_constraint`, with
    the linearisation of :func:`set_velocity` (0, 0: the free motion opens both gaps)."""
    _vx, _vy, l1, l2 = constrained_velocity(gc[GC_V0X], gc[GC_V0Y], gc[GC_PAIR:GC_PAIR + 10])
    return l1, l2


@njit(inline="always")
def contact_load(fx, fy, l1, l2, gc):
    """The load [N] the film carries: F₀ = (fx, fy) plus the reactions λ₁, λ₂ along the contacts' normals."""
    c = GC_PAIR
    return fx + l1 * gc[c] + l2 * gc[c + 2], fy + l1 * gc[c + 1] + l2 * gc[c + 3]


@njit(inline="always")
def contact_newton_step(gc, fx, fy, l1, l2):
    r"""One Josephy–Newton step [2] of the reactions through the full film law; returns (λ₁, λ₂, δ): the new
    reactions [N] and their change as a fraction of |F₀| + |λ| [-] (:func:`newton_converged`).

    The film carries the load and the reactions together, ė = M(e, F₀ + λ₁n₁ + λ₂n₂), with each gap's rate
    w_k = n_k·ė + r_k ≥ 0, λ_k ≥ 0, w_k λ_k = 0: a nonlinear complementarity problem.  ``gc`` holds ė and G at
    the iterate's load :func:`contact_load` (``fx, fy``, ``l1, l2``; :func:`set_velocity` there) and the contacts of
    :func:`set_constraint`; the step solves the linear complementarity problem of
    :func:`.tooth_constraint.reactions` with A = NᵀG N and s = w(λ) − Aλ, and leaves the constraint on with G n at
    this iterate.
    """
    c = gc[GC_PAIR:GC_PAIR + 10]
    contact_pair(gc[GC_GXX], gc[GC_GXY], gc[GC_GYX], gc[GC_GYY], c[0], c[1], c[2], c[3], c[8], c[9], c)
    gc[GC_CON] = 1.0
    a11, a12 = c[0] * c[4] + c[1] * c[5], c[0] * c[6] + c[1] * c[7]
    a21, a22 = c[2] * c[4] + c[3] * c[5], c[2] * c[6] + c[3] * c[7]
    s1 = c[0] * gc[GC_V0X] + c[1] * gc[GC_V0Y] + c[8] - (a11 * l1 + a12 * l2)
    s2 = c[2] * gc[GC_V0X] + c[3] * gc[GC_V0Y] + c[9] - (a21 * l1 + a22 * l2)
    m1, m2 = reactions(s1, s2, a11, a12, a21, a22)
    return m1, m2, (abs(m1 - l1) + abs(m2 - l2)) / (math.hypot(fx, fy) + m1 + m2)


@njit(inline="always")
def newton_converged(delta, delta_prev, rtol):
    r"""True when the Josephy–Newton's iterate is within ``rtol`` [-] of the solution, from its last change δ and the
    one before, δ_prev (fractions of |F₀| + |λ|; δ_prev = ∞ at the first iterate): δ ≤ rtol, or the error of the new
    iterate estimated from the observed contraction Θ = δ/δ_prev [3],

    .. math:: \frac{\Theta}{1 - \Theta}\,\delta \le \mathrm{rtol},\qquad \Theta < 1

    (the Newton iteration's stopping criterion of the implicit Runge–Kutta codes, [3] eqs. (8.10)–(8.11)).  Near
    the solution Newton's contraction is quadratic, Θ ∝ δ, so the estimate stops one iterate before δ itself
    falls below ``rtol``.
    """
    if delta <= rtol:
        return True
    if not delta_prev < math.inf:                       # the first iterate: no contraction observed yet
        return False
    theta = delta / delta_prev
    return theta < 1.0 and theta / (1.0 - theta) * delta <= rtol


@njit(inline="always")
def warm_reactions(gc, l1, l2):
    r"""The start [N] of :func:`linearise_in_contact`'s iteration from the reactions (l1, l2) linearised at the free
    load: each plus the correction the last iteration found on the same lobe (:data:`GC_LOBE1`, :data:`GC_LOBE2`),

    .. math:: \lambda_k^{(0)} = \max\big(0,\ \lambda_k^{lin} + (\lambda_{k}^{*} - \lambda_{k}^{lin})_{prev}\big)

    The full film law's share of the reactions, λ* − λ^lin, changes little over the 1.5° between output steps
    where the reactions themselves follow the load; no correction on a lobe the last one did not hold.  Measured
    per output step over a revolution, stopping on the change itself at 3e-6 (docs/performance.md): Josephy–Newton
    iterations 3.1 against 4.2 from the linearised reactions at the default pump's rated point, 2.1 against 3.0 on 07
    at 1650 rpm / 27.5 bar, where starting from the last converged reactions themselves took 3.5 (the load moves
    more than the correction).
    """
    return max(0.0, l1 + _correction_on(gc, gc[GC_LOBE1])), max(0.0, l2 + _correction_on(gc, gc[GC_LOBE2]))


@njit(inline="always")
def _correction_on(gc, lobe):
    """The last Josephy–Newton's λ* − λ^lin [N] on lobe ``lobe`` (0 if it did not hold it)."""
    if gc[GC_CORR_LOBE1] == lobe:
        return gc[GC_CORR1]
    if gc[GC_CORR_LOBE2] == lobe:
        return gc[GC_CORR2]
    return 0.0


@njit(inline="always")
def linearise_in_contact(ex, ey, omega, km, gc, rtol):
    r"""Move the step's linearisation of the mobility to the load the film carries on the teeth.

    :func:`linearise` takes ė₀ and G at the free load F₀; where the step starts on the teeth the film carries
    F₀ + λ₁n₁ + λ₂n₂, and a reaction comparable with F₀ turns the load, where the mobility is far from linear.
    The reactions at the step's start are solved through the full mobility (:func:`contact_newton_step` from the
    linearised ones corrected by the last step's full-law share: :func:`warm_reactions`; ė₀ and G taken
    afresh at each iterate's load, one closed-form evaluation each; converged to ``rtol``, :func:`contact_rtol`) and
    the linearisation is left at the last:
    the constrained velocity at F₀ is then M(e, F₀ + Nλ) itself, the reactions within the step are linear
    about it.  Off the teeth (λ = 0 at F₀) nothing changes.  Call after :func:`set_constraint`.  Returns the
    Josephy–Newton iterations (:data:`FULL_ITERATIONS` + 1: not converged; 0: off the teeth).
    """
    for i in range(4):
        gc[GC_CORR_BEFORE + i] = gc[GC_CORR1 + i]
    lin1, lin2 = held_reactions(gc)
    l1, l2 = warm_reactions(gc, lin1, lin2)
    gc[GC_CORR1] = 0.0                              # until this iteration converges
    gc[GC_CORR2] = 0.0
    if lin1 == 0.0 and lin2 == 0.0:
        return 0
    pc = km.pc
    bp = (pc.housing_clearance, pc.width, 2.0 * pc.journal_radius, pc.viscosity)
    omega2 = omega * (pc.n - 1) / pc.n
    fx, fy = gc[GC_F0X], gc[GC_F0Y]
    delta = math.inf
    for it in range(FULL_ITERATIONS):
        gx, gy = contact_load(fx, fy, l1, l2, gc)
        vx, vy, gxx, gxy, gyx, gyy = mobility_linearised_kernel(ex, ey, gx, gy, omega2, bp)
        set_linearisation(gc, gx, gy, vx, vy, gxx, gxy, gyx, gyy)
        delta_prev = delta
        l1, l2, delta = contact_newton_step(gc, fx, fy, l1, l2)
        if newton_converged(delta, delta_prev, rtol):
            gc[GC_CORR1], gc[GC_CORR2] = l1 - lin1, l2 - lin2
            gc[GC_CORR_LOBE1], gc[GC_CORR_LOBE2] = gc[GC_LOBE1], gc[GC_LOBE2]
            return it + 1
    return FULL_ITERATIONS + 1


@njit
def short_in_contact(params, ex, ey, omega2, gc):
    r""":func:`linearise_in_contact` for Method 1 (``params``: :func:`.short_bearing.short_kernel`'s), Josephy–Newton
    in the film's own form: each iterate is a velocity, its load and G one film integral away.

    Method 1 is the film's force as a function of the journal's velocity, inverted by Newton in
    :func:`.short_bearing.short_kernel`; :func:`linearise_in_contact`'s iteration through that inverse would take
    three Newton solves per iterate (ė₀ and two for G).  Here the iterate is ė itself: the load it takes and G there
    are :func:`.short_bearing.short_load`'s closed form, linearised about them the constrained velocity at the free
    load F₀ (:func:`gear_velocity`: the two-contact LCP of the same Josephy–Newton step) is the next iterate.  The
    fixed point is the same, ė = M(e, F₀ + λ₁n₁ + λ₂n₂) with the gaps held; converged and left as
    :func:`linearise_in_contact` leaves it (F₀ in ``gc`` the load of the last iterate, which the step's load
    change is taken from).  Call after :func:`set_constraint`.  Returns the iterations (:data:`FULL_ITERATIONS` + 1:
    not converged; 0: off the teeth).
    """
    on, fx, fy, vx, vy, l1, l2 = film_start(gc)
    if not on:
        return 0
    for it in range(FULL_ITERATIONS):
        lx, ly, gxx, gxy, gyx, gyy = short_load(ex, ey, vx, vy, omega2, params)
        vx, vy, l1, l2, done = film_iterate(gc, fx, fy, l1, l2, lx, ly, vx, vy, gxx, gxy, gyx, gyy)
        if done:
            return it + 1
    return FULL_ITERATIONS + 1


@njit(_nrt=True)     # the FDM film's fallback Jacobian allocates: with numba's reference counting
def fdm_in_contact(p_w, p_x, p_y, cos_t, sin_t, area, gc):
    """:func:`short_in_contact` for the FDM film, from its fields at the gear's position (:func:`.reynolds_fd.fd_fields`
    once per output step; each iterate's load and G by :func:`.reynolds_fd.fdm_load`, one pass over the grid)."""
    on, fx, fy, vx, vy, l1, l2 = film_start(gc)
    if not on:
        return 0
    for it in range(FULL_ITERATIONS):
        lx, ly, gxx, gxy, gyx, gyy = fdm_load(p_w, p_x, p_y, vx, vy, cos_t, sin_t, area)
        vx, vy, l1, l2, done = film_iterate(gc, fx, fy, l1, l2, lx, ly, vx, vy, gxx, gxy, gyx, gyy)
        if done:
            return it + 1
    return FULL_ITERATIONS + 1


@njit(inline="always")
def film_start(gc):
    """The start of :func:`short_in_contact`'s iteration: on the teeth (the linearised reactions at the free load
    not both zero), the free load F₀ [N], the constrained velocity there [m/s] and those reactions [N]."""
    vx, vy, l1, l2 = constrained_velocity(gc[GC_V0X], gc[GC_V0Y], gc[GC_PAIR:GC_PAIR + 10])    # :func:`held_reactions`
    return l1 != 0.0 or l2 != 0.0, gc[GC_F0X], gc[GC_F0Y], vx, vy, l1, l2


@njit(inline="always")
def film_iterate(gc, fx, fy, l1, l2, lx, ly, vx, vy, gxx, gxy, gyx, gyy):
    """One Josephy–Newton iterate in a film's own form (:func:`short_in_contact`): the linearisation about the
    velocity (vx, vy) [m/s], the load it takes (lx, ly) [N] and G there; returns the constrained velocity at the free
    load (fx, fy) [N], its reactions and whether they moved by less than :data:`FULL_RTOL` of |F₀| + |λ| from
    (l1, l2).  The reactions in ``gc`` are left at zero, as :func:`set_velocity` leaves them for the step's own
    right-hand sides."""
    set_linearisation(gc, lx, ly, vx, vy, gxx, gxy, gyx, gyy)
    c = gc[GC_PAIR:GC_PAIR + 10]
    contact_pair(gxx, gxy, gyx, gyy, c[0], c[1], c[2], c[3], c[8], c[9], c)
    gc[GC_CON] = 1.0
    vx, vy = gear_velocity(fx, fy, gc)
    m1, m2 = gc[GC_LAM1], gc[GC_LAM2]
    gc[GC_LAM1] = 0.0
    gc[GC_LAM2] = 0.0
    return vx, vy, m1, m2, abs(m1 - l1) + abs(m2 - l2) <= FULL_RTOL * (math.hypot(fx, fy) + m1 + m2)


@njit(forceinline=True)     # per output step, inside linearise_mobility: inlined by LLVM
def linearise(ex, ey, theta, omega, h, kc, km, pres, gc, rows):
    """Set up the coupling of the next output step of h [s] with the mobility method (compiled in): the coupled
    load (:func:`coupled_load_at`), ė₀ and G (Eqs. (7)–(13) of [1]; G in closed form,
    :func:`~gerotor_twin.bearing.mobility.mobility_linearised`)."""
    pc = km.pc
    fx, fy = coupled_load_at(ex, ey, theta, omega, h, kc, km, pres, gc, rows)
    bp = (pc.housing_clearance, pc.width, 2.0 * pc.journal_radius, pc.viscosity)
    omega2 = omega * (pc.n - 1) / pc.n
    vx, vy, gxx, gxy, gyx, gyy = mobility_linearised_kernel(ex, ey, fx, fy, omega2, bp)
    set_linearisation(gc, fx, fy, vx, vy, gxx, gxy, gyx, gyy)


@njit(forceinline=True)     # per output step, the stepper's two sites: typed and lowered once, inlined by LLVM
def linearise_mobility(ex, ey, theta, omega, h, kc, km, pres, gc, rows, cmat, constrained):
    """The mobility gear's set-up of the output step of h [s] from θ [rad]: :func:`linearise`, and with the tooth
    constraint (``constrained``, h > 0) :func:`set_constraint` and :func:`linearise_in_contact`.  Returns True
    when the constraint was set (``cmat`` then holds the gap expansions at the step's end)."""
    linearise(ex, ey, theta, omega, h, kc, km, pres, gc, rows)
    if constrained and h > 0.0:
        set_constraint(ex, ey, theta + omega * h, h, km, gc, cmat)
        linearise_in_contact(ex, ey, omega, km, gc, contact_rtol(km.pc))
        return True
    return False


@njit
def linearise_short(params, ex, ey, theta, omega, h, kc, km, pres, gc, rows, cmat, constrained):
    """Set up the coupling of the next output step with Method 1's film (:func:`linearise` with
    :func:`~gerotor_twin.bearing.short_bearing.short_kernel`, ``params`` its parameters), compiled: ė₀ by the film's
    Newton solve, G in closed form there (:func:`~gerotor_twin.bearing.short_bearing.short_load`: A⁻¹, where the
    other films take finite differences), and where ``constrained`` the tooth constraint with the reactions through
    the film (:func:`short_in_contact`).  Called by :func:`.kernel.integrate_short` without a return to Python per
    output step, and by :func:`linearise_with` for Method 1 (the Python loop)."""
    fx, fy = coupled_load_at(ex, ey, theta, omega, h, kc, km, pres, gc, rows)
    omega2 = omega * (km.pc.n - 1) / km.pc.n
    vx, vy = short_kernel(ex, ey, fx, fy, omega2, params)
    _lx, _ly, gxx, gxy, gyx, gyy = short_load(ex, ey, vx, vy, omega2, params)     # G in closed form at ė₀
    set_linearisation(gc, fx, fy, vx, vy, gxx, gxy, gyx, gyy)
    if constrained and h > 0.0:
        set_constraint(ex, ey, theta + omega * h, h, km, gc, cmat)
        short_in_contact(params, ex, ey, omega2, gc)


def linearise_with(bearing, ex, ey, theta, omega, h, kc, km, pres, gc, rows, cmat):
    """:func:`linearise` with another bearing model's velocity kernel, from Python (numba caches no compiled function
    that takes a function): Method 1 and the FDM film by their own set-ups in the film's form
    (:func:`linearise_short`, :func:`_linearise_fdm`); any other kernel by finite differences and
    :func:`linearise_in_contact`'s iteration through it."""
    k, bp = bearing.kernel, bearing.params
    if k is short_kernel:                       # Method 1: its compiled set-up, G and the contact in closed form
        linearise_short(bp, ex, ey, theta, omega, h, kc, km, pres, gc, rows, cmat, km.pc.gear_constrained)
        return
    if k is fdm_kernel:                         # the FDM film: its fields once, G and the contact from them
        _linearise_fdm(bp, ex, ey, theta, omega, h, kc, km, pres, gc, rows, cmat)
        return
    fx, fy = coupled_load_at(ex, ey, theta, omega, h, kc, km, pres, gc, rows)
    omega2 = omega * (km.pc.n - 1) / km.pc.n
    d = load_step(fx, fy)
    set_velocity(gc, fx, fy, k(ex, ey, fx, fy, omega2, bp), k(ex, ey, fx + d, fy, omega2, bp),
                 k(ex, ey, fx, fy + d, omega2, bp), d)
    if km.pc.gear_constrained and h > 0.0:
        set_constraint(ex, ey, theta + omega * h, h, km, gc, cmat)
        l1, l2 = held_reactions(gc)            # on the teeth: :func:`linearise_in_contact` with this film's law
        for _ in range(FULL_ITERATIONS if l1 != 0.0 or l2 != 0.0 else 0):
            gx, gy = contact_load(fx, fy, l1, l2, gc)
            d = load_step(gx, gy)
            set_velocity(gc, gx, gy, k(ex, ey, gx, gy, omega2, bp), k(ex, ey, gx + d, gy, omega2, bp),
                         k(ex, ey, gx, gy + d, omega2, bp), d)
            l1, l2, delta = contact_newton_step(gc, fx, fy, l1, l2)
            if delta <= contact_rtol(km.pc):
                break


def _linearise_fdm(params, ex, ey, theta, omega, h, kc, km, pres, gc, rows, cmat):
    """:func:`linearise_with` for the FDM film (``params``: :func:`.reynolds_fd.fdm_kernel`'s): its three Reynolds
    solves once at the gear's position, ė₀ by its Newton from them, G in closed form there
    (:func:`.reynolds_fd.fdm_load`), on the teeth :func:`fdm_in_contact` — where its velocity kernel would solve
    Reynolds again for each of three calls per Josephy–Newton iterate."""
    c, length, diameter, mu, dx, dy, cos_t, sin_t, lam, synth = params
    fx, fy = coupled_load_at(ex, ey, theta, omega, h, kc, km, pres, gc, rows)
    omega2 = omega * (km.pc.n - 1) / km.pc.n
    exc, eyc = cap_eccentricity(ex, ey, c)
    p_w, p_x, p_y = fd_fields(exc, eyc, omega2, c, 0.5 * diameter, mu, dx, cos_t, sin_t, lam, synth)
    area = dx * dy
    vx, vy = velocity_from_fields(p_w, p_x, p_y, exc, eyc, fx, fy, omega2, c, length, diameter, mu, area, cos_t, sin_t)
    _lx, _ly, gxx, gxy, gyx, gyy = fdm_load(p_w, p_x, p_y, vx, vy, cos_t, sin_t, area)
    set_linearisation(gc, fx, fy, vx, vy, gxx, gxy, gyx, gyy)
    if km.pc.gear_constrained and h > 0.0:
        set_constraint(ex, ey, theta + omega * h, h, km, gc, cmat)
        fdm_in_contact(p_w, p_x, p_y, cos_t, sin_t, area, gc)


@njit(inline="always")
def keep_first_stage(gc):
    """Note the gear's velocity and reactions of the right-hand side just evaluated (the sub-step's first stage), which
    :func:`substep_rates` judges that stage's validity by."""
    gc[GC_STAGE1], gc[GC_STAGE1 + 1] = gc[GC_VX], gc[GC_VY]
    gc[GC_STAGE1 + 2], gc[GC_STAGE1 + 3] = gc[GC_LAM1], gc[GC_LAM2]


@njit          # called, not inlined: inlined at the stepper's sites it added 7–10 s to the first compile
def substep_rates(gc, ex, ey, theta_now, theta_end, h, remaining, tab, delta, cmat, at_end):
    r"""The rates [m/s] of the two lobes :func:`set_constraint` chose, for the ROS2 sub-step of h [s] from θ_now to
    θ_end [rad], with ``remaining`` [s] of the output step left at its start: the gap's change over the sub-step at
    the gear's present position (the teeth's turn) plus the present gap closed over the rest of the output step,

    .. math::
        r_k = \frac{g_k(\mathbf e, \theta_{end}) - g_k(\mathbf e, \theta_{now})}{h}
            + \frac{g_k(\mathbf e, \theta_{now})}{H_{rem}},\qquad
        \mathbf e = \mathbf e_0 + \textstyle\int\dot{\mathbf e}\,dt

    (Moreau's time-stepping, :mod:`.tooth_constraint`; (ex, ey) = e₀ [m], the output step's start; ∫ė dt over
    the accepted sub-steps, the last one's trapezoid closed with the velocity of the last right-hand side).  Over a
    single sub-step, or the output step's last, it is g_k(e, θ_end)/h, and from e₀ over the whole output step the
    set-up's own rates.  The turn taken per sub-step lets a lobe that recedes or closes inside the output step hold
    or release the gear where it does, where the set-up's rates spread it over the whole step; the gap (or what the
    trapezoid leaves of an overlap) closed over the rest of the step, not over the sub-step, keeps the rates finite
    as h shrinks (Moreau's g/h over a rejected sub-step's retry drives the gear at |g|/h; docs/numerics.md, "The
    tooth contact as a constraint").  ``tab``: the kernel tables; ``delta``: the nominal tip clearance [m];
    ``at_end``: θ_end is the output step's end, whose gap expansions :func:`set_constraint` left in ``cmat`` (the
    same values as the tables give).  Returns True where the first stage already evaluated
    (:func:`keep_first_stage`) does not hold under the new rates: it had a reaction, or its velocity would close a
    gap within the sub-step (n·ė + r < 0); a free gear's first stage stays valid, bit for bit, and so does any whose
    rates are unchanged.
    """
    c = GC_PAIR
    px = ex + gc[GC_DEX] + 0.5 * gc[GC_PEND] * (gc[GC_VPX] + gc[GC_VX])
    py = ey + gc[GC_DEY] + 0.5 * gc[GC_PEND] * (gc[GC_VPY] + gc[GC_VY])
    k1, k2 = int(gc[GC_LOBE1]), int(gc[GC_LOBE2])
    if at_end:                          # θ_end is the output step's end: its expansions, from set_constraint
        r1 = gap_value(cmat[k1], delta, px, py, 0.0) / h
        r2 = gap_value(cmat[k2], delta, px, py, 0.0) / h
    else:
        r1 = gap_unturned(tab, theta_end, k1, delta, px, py) / h
        r2 = gap_unturned(tab, theta_end, k2, delta, px, py) / h
    if h < remaining:                   # the gap now is closed over the rest of the output step, not this sub-step
        g1 = gap_unturned(tab, theta_now, k1, delta, px, py)
        g2 = gap_unturned(tab, theta_now, k2, delta, px, py)
        r1 += g1 * (1.0 / remaining - 1.0 / h)
        r2 += g2 * (1.0 / remaining - 1.0 / h)
    if r1 == gc[c + 8] and r2 == gc[c + 9]:            # the output step's own rates (one sub-step from e₀)
        return False
    gc[c + 8] = r1
    gc[c + 9] = r2
    if gc[GC_STAGE1 + 2] != 0.0 or gc[GC_STAGE1 + 3] != 0.0:
        return True
    vx, vy = gc[GC_STAGE1], gc[GC_STAGE1 + 1]
    return gc[c] * vx + gc[c + 1] * vy + gc[c + 8] < 0.0 or gc[c + 2] * vx + gc[c + 3] * vy + gc[c + 9] < 0.0


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


@njit(forceinline=True)
def gear_move(ex, ey, theta, km, pres, gc, rows):
    """The gear's position [m] after the output step from (ex, ey): the start plus ∫ė dt of the stages; and the
    coupled load at the end pressures ``pres`` [Pa] and θ [rad] (contact held from the step start) [N].

    Closes the pending trapezoid there.  The position
    dependence of **M** is taken at the step start (a Heun correction with the end load,
    h/2·[M(e₀ + Δe, F₁) − M(e₀, F₁)], measured worse: twice the position error against the
    reference, docs/numerics.md).
    """
    fx, fy = coupled_load(pres, theta, km.pc.n, km.eos.p_atm, gc, rows)
    gc[GC_VX], gc[GC_VY] = gear_velocity(fx, fy, gc)
    close_pending(gc)
    return ex + gc[GC_DEX], ey + gc[GC_DEY], fx, fy
