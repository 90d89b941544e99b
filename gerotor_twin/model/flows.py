"""Right-hand side of the chamber-pressure ODE: port, tooth-tip and leakage flows.

State y (length N+1): the log-densities y = ln(ρ/ρ₀) of the N chambers and of
the delivery volume.  Mass conservation per volume, d(ρV)/dt = Σ ρ_up Q, gives

.. math::
    \\frac{dy_j}{dt} = \\frac{1}{V_j}\\Big(\\sum_i \\frac{\\rho_{up,i}}{\\rho_j} Q_i
        - \\omega \\frac{dV_j}{d\\theta}\\Big)

which is Eq. (20) of [1] (corrected: dp/dθ = β/(Vω)(ΣQ − ω dV/dθ); the
printed 1/ω_int is not dimensionally right) multiplied through by 1/β, since
dp = β dy.  Q_i are volume flows at upstream conditions; the density ratios
(at most 0.2 % here) make the mass balance close exactly.  ∂f/∂y is assembled
alongside, exactly: ∂Q/∂p · β(p) / V and the derivatives of the density
ratios (:func:`transfer`).

The parts, each a function of its own: :func:`chamber_geometry` (table rows of
every chamber, read once per angle: :func:`table_geometry`), :func:`volume_states` (p, β, ρ of every volume),
:func:`transfer` (one flow between two volumes),
:func:`port_flows` (Eq. (21)), :func:`tip_flows` (Eq. (22) and sec. 3.2),
:func:`line_flows` (sec. 3.3, 3.4 and the delivery restriction of sec. 4),
:func:`assemble` and :func:`rhs`.

References
----------
.. [1] The paper, sec. 3 (``../shared/paper``).
"""
from __future__ import annotations

import math

from .._jit import njit
from ..geometry.tables import AD, AS, DFX, DFY, DV, FX, FY, KREL, V, VR
from ..hydraulics.gaps import tooth_tip_flow
from ..hydraulics.orifice import port_orifice_flow
from ..hydraulics.state_equation import exp_small, state_of
from .contact import column, locate
from .gear_coupling import GC_ON, gear_squeeze
from .volumes import displace_chamber, volumes_moved
from .params import (CT_GEO_OK, CT_GEO_TABLE, CT_GEO_THETA, FL_DELIVERY, FL_DRAIN, FL_MASS_IN, FL_MASS_OUT,
                     FL_RESTRICTION, FL_SUCTION, FL_SUCTION_DELIVERY, N_JAC_EXTRA)

__all__ = ["rhs", "chamber_geometry", "table_geometry", "volume_states", "transfer", "port_flows", "tip_flows",
           "line_flows", "assemble", "area_derivative", "closing_ports", "closing_share", "time_to_close",
           "G_V", "G_DV", "G_AS", "G_AD", "G_KREL", "G_VR", "G_SV", "G_DAS", "G_DAD", "G_DDV", "G_V0", "G_DV0", "G_FX",
           "G_FY", "G_DFX", "G_DFY",
           "J_FT", "J_CS", "J_TCS", "J_CD", "J_CDN", "J_TCD", "N_JAC_EXTRA"]

#: columns of Workspace.geo: V, dV/dθ, A_s, A_d, κ_rel, v_r/ω, the slopes of the interpolated V, A_s, A_d and
#: dV/dθ in θ (the time derivative of the right-hand side), and the table values the displaced V and dV/dθ are
#: made of: V and dV/dθ of the centred gear set, FX, FY and their θ-derivatives (:func:`chamber_geometry`)
G_V, G_DV, G_AS, G_AD, G_KREL, G_VR, G_SV, G_DAS, G_DAD, G_DDV, G_V0, G_DV0, G_FX, G_FY, G_DFX, G_DFY = range(16)
#: Columns of Workspace.jac after ∂f/∂y (N+1 columns), as offsets from N+1: ∂f/∂t without the closing ports,
#: then per row j the closing ports' shares of it and the time until they close (:func:`closing_ports`,
#: :func:`closing_share`): suction port → chamber row [1/s²], its time to close [s]; delivery port → chamber
#: row, → delivery row, its time to close [s] (0: not closing within the horizon).
J_FT, J_CS, J_TCS, J_CD, J_CDN, J_TCD = range(N_JAC_EXTRA)


@njit(inline="always")
def table_geometry(theta, tab, n, geo):
    """The table values of every chamber at shaft angle θ [rad] into ``geo``: A_s, A_d, κ_rel, v_r/ω, the slopes,
    and V, dV/dθ, FX, FY, dFX/dθ, dFY/dθ of the centred gear set (``G_V0`` …), from which
    :func:`chamber_geometry` makes the displaced V and dV/dθ."""
    for j in range(n):
        i0, i1, f = locate(tab, theta + j * tab.shift)
        geo[j, G_V0] = column(tab, V, i0, i1, f)
        geo[j, G_DV0] = column(tab, DV, i0, i1, f)
        geo[j, G_AS] = column(tab, AS, i0, i1, f)
        geo[j, G_AD] = column(tab, AD, i0, i1, f)
        geo[j, G_KREL] = column(tab, KREL, i0, i1, f)
        geo[j, G_VR] = column(tab, VR, i0, i1, f)
        geo[j, G_SV] = (tab.rows[i1, V] - tab.rows[i0, V]) * tab.scale
        geo[j, G_DAS] = (tab.rows[i1, AS] - tab.rows[i0, AS]) * tab.scale
        geo[j, G_DAD] = (tab.rows[i1, AD] - tab.rows[i0, AD]) * tab.scale
        geo[j, G_DDV] = (tab.rows[i1, DV] - tab.rows[i0, DV]) * tab.scale
        if tab.volumes_follow_gear:
            geo[j, G_FX] = column(tab, FX, i0, i1, f)
            geo[j, G_FY] = column(tab, FY, i0, i1, f)
            geo[j, G_DFX] = column(tab, DFX, i0, i1, f)
            geo[j, G_DFY] = column(tab, DFY, i0, i1, f)


@njit(inline="always")
def chamber_geometry(theta, tab, n, geo, disp, acc, ctrl):
    """V, dV/dθ, port areas, κ_rel and v_r/ω of every chamber at shaft angle θ [rad] into ``geo``, with the slopes
    of the interpolated V, A_s, A_d [m³/rad, m²/rad] and dV/dθ [m³/rad²] in θ (exact for the interpolated columns).

    V and dV/dθ are those of the outer gear displaced by ``disp`` (:mod:`.volumes`), whose
    squeeze flow goes into ``acc`` (which must be initialised: :func:`volume_states`).  The table values
    (:func:`table_geometry`) are read once per angle: a sub-step's second stage and the next sub-step's first stage
    are at the same θ, so the first stage takes them from ``geo``; ``ctrl[CT_GEO_OK]``, ``ctrl[CT_GEO_THETA]`` and
    ``ctrl[CT_GEO_TABLE]`` (the table's address: a workspace used with another model's tables reads those) say
    which values ``geo`` holds.
    """
    table = float(tab.rows.ctypes.data)
    if ctrl[CT_GEO_OK] == 0.0 or ctrl[CT_GEO_THETA] != theta or ctrl[CT_GEO_TABLE] != table:
        table_geometry(theta, tab, n, geo)
        ctrl[CT_GEO_THETA] = theta
        ctrl[CT_GEO_TABLE] = table
        ctrl[CT_GEO_OK] = 1.0
    moved = volumes_moved(disp)
    for j in range(n):
        geo[j, G_V] = geo[j, G_V0]
        geo[j, G_DV] = geo[j, G_DV0]
        if moved:                                   # micro_motion.chamber_volumes: displaced
            displace_chamber(geo[j, G_FX], geo[j, G_FY], geo[j, G_DFX], geo[j, G_DFY], j, disp, geo, acc, G_V, G_DV)


@njit(inline="always")
def volume_states(y, km, op, ws):
    """Pressure [Pa], bulk modulus [Pa] and ρ/ρ₀ of every volume from the log-densities."""
    n = km.pc.n
    for i in range(n + 1):
        if i == n and not km.pc.restriction:             # imposed delivery pressure (Operating)
            ws.p[i] = op.p_d
            ws.beta[i] = op.beta_d
            ws.rho[i] = op.rho_d
        else:
            ws.p[i], ws.beta[i] = state_of(y[i], km.eos)
            ws.rho[i] = exp_small(y[i])
        ws.acc[i] = 0.0


@njit(inline="always")
def transfer(a, b, q, dq, ws, jac, want_jac):
    """Book a volume flow q from volume a to volume b [m³/s] (dq = ∂q/∂(p_a − p_b)) into acc and ∂f/∂y.

    q is measured at upstream conditions: the downstream volume receives (ρ_up/ρ_down)·q.
    Exact derivatives with y = ln(ρ/ρ₀) (∂p/∂y = β, ∂ρ/∂y = ρ):
    ∂acc_d/∂y_u = r(q + q'β_u), ∂acc_d/∂y_d = −r(q + q'β_d), ∂acc_u/∂y_u = −q'β_u,
    ∂acc_u/∂y_d = q'β_d, with r = ρ_u/ρ_d and q ≥ 0 from u to d.
    """
    u, d = (a, b) if q >= 0.0 else (b, a)
    qa = abs(q)
    r = ws.rho[u] / ws.rho[d]
    ws.acc[d] += r * qa
    ws.acc[u] -= qa
    if want_jac:
        jac[d, u] += r * (qa + dq * ws.beta[u])
        jac[d, d] -= r * (qa + dq * ws.beta[d])
        jac[u, u] -= dq * ws.beta[u]
        jac[u, d] += dq * ws.beta[d]


@njit(inline="always")
def area_derivative(q, dq, dp, area):
    r"""∂Q/∂A [m/s] of an orifice flow q [m³/s] with dq = ∂Q/∂Δp [m³/(s·Pa)] at Δp [Pa] and area A [m²].

    Notes
    -----
    Both orifice laws (:mod:`gerotor_twin.hydraulics.orifice`) have Q = A v F(Re) with Re built
    on v = √(2|Δp|/ρ) and D_h ∝ √A, so Q(Δp/s², s²A) = s Q(Δp, A); differentiating at s = 1,

    .. math::
        \frac{\partial Q}{\partial A} = \frac{Q/2 + \Delta p\,\partial Q/\partial\Delta p}{A}

    (turbulent: Q/A; laminar: 3Q/(2A)).  0 for a closed port (Q ∝ A^{3/2} as A → 0).
    """
    if not area > 0.0:
        return 0.0
    return (0.5 * q + dp * dq) / area


@njit(inline="always")
def transfer_rate(a, b, q, qt, ws, jac):
    """∂/∂θ of :func:`transfer` for a flow q from a to b whose θ-derivative at fixed pressures is qt [m³/(s·rad)],
    into the ∂f/∂t column of ``jac`` (densities held)."""
    u, d = (a, b) if q >= 0.0 else (b, a)
    st = qt if q >= 0.0 else -qt
    t = ws.p.shape[0]                      # the ∂f/∂t column, right after ∂f/∂y
    jac[d, t] += ws.rho[u] / ws.rho[d] * st
    jac[u, t] -= st


@njit(inline="always")
def port_flows(km, op, ws, jac, want_jac):
    """Suction and delivery port → chamber flows, Eq. (21) of [1] with Cd(λ).

    With ``want_jac`` also their θ-derivative at fixed pressures (through the port areas) into
    the ∂f/∂t column of ``jac`` (column N+1; the closing ports' columns follow it), [m³/(s·rad)]
    until :func:`assemble` turns it into ∂f/∂t.
    """
    pc = km.pc
    n = pc.n
    p, beta, rho, acc, geo, fl = ws.p, ws.beta, ws.rho, ws.acc, ws.geo, ws.flows
    for j in range(n):
        if geo[j, G_AS] > 0.0:                          # a closed port books nothing (Q = dQ/dΔp = ∂Q/∂A = 0)
            q, dq = port_orifice_flow(op.p_s - p[j], geo[j, G_AS], pc.orifice_law, pc.cd_max, pc.lambda_crit,
                                      pc.laminar_delta, pc.density, pc.viscosity)  # Eq. (21)
            r = op.rho_s / rho[j] if q > 0.0 else 1.0   # the suction port is a source at p_s, not a state
            acc[j] += r * q
            fl[FL_SUCTION] += q
            fl[FL_MASS_IN] += (op.rho_s if q > 0.0 else rho[j]) * q
            if want_jac:
                jac[j, j] -= r * dq * beta[j] + (r * q if q > 0.0 else 0.0)
                jac[j, n + 1] += r * area_derivative(q, dq, op.p_s - p[j], geo[j, G_AS]) * geo[j, G_DAS]
        if geo[j, G_AD] > 0.0:
            dp = p[n] - p[j]
            q, dq = port_orifice_flow(dp, geo[j, G_AD], pc.orifice_law, pc.cd_max, pc.lambda_crit,
                                      pc.laminar_delta, pc.density, pc.viscosity)  # Eq. (21)
            fl[FL_MASS_OUT] -= (rho[n] if q > 0.0 else rho[j]) * q
            fl[FL_DELIVERY] -= q if q > 0.0 else rho[j] / rho[n] * q      # at delivery conditions
            transfer(n, j, q, dq, ws, jac, want_jac)
            if want_jac:
                transfer_rate(n, j, q, area_derivative(q, dq, dp, geo[j, G_AD]) * geo[j, G_DAD], ws, jac)


@njit(inline="always")
def tip_flows(gaps, km, op, ws, jac, want_jac):
    """Chamber j−1 → chamber j across lobe j: tooth-tip gap (Eq. (22) of [1]) + lateral land (sec. 3.2).

    The lateral leakage across the lobe land does not depend on the micro-motion, as in [1].
    """
    pc = km.pc
    n = pc.n
    p, geo = ws.p, ws.geo
    for j in range(n):
        jm = j - 1 if j > 0 else n - 1      # not (j − 1) % n: an integer division per chamber
        q = 0.0
        dq = 0.0
        hk = gaps[j]
        if hk > 0.0:
            le = 2.0 * math.sqrt(2.0 * hk * pc.tip_dh / geo[j, G_KREL])       # osculating-circle length
            q, dq = tooth_tip_flow(p[jm] - p[j], hk, le, op.omega * geo[j, G_VR], pc.width, pc.viscosity)  # Eq. (22)
            q *= pc.tip_flow_factor
            dq *= pc.tip_flow_factor
        q += pc.g_lateral * (p[jm] - p[j])                                   # sec. 3.2
        dq += pc.g_lateral
        transfer(jm, j, q, dq, ws, jac, want_jac)


@njit(inline="always")
def line_flows(km, op, ws, jac, want_jac):
    """Suction–delivery (sec. 3.3) and drain (sec. 3.4) leakages and the delivery restriction (sec. 4)."""
    pc = km.pc
    n = pc.n
    dp = ws.p[n] - op.p_s
    q_sd = pc.g_suction_delivery * dp
    q_dr = pc.g_drain * dp
    ws.acc[n] -= q_sd + q_dr
    ws.flows[FL_SUCTION_DELIVERY] = q_sd
    ws.flows[FL_DRAIN] = q_dr
    ws.flows[FL_DELIVERY] -= q_sd + q_dr
    if pc.restriction:
        q, dq = port_orifice_flow(ws.p[n] - pc.p_tank, pc.restriction_area, pc.orifice_law, pc.cd_max,
                                  pc.lambda_crit, pc.laminar_delta, pc.density, pc.viscosity)
        ws.acc[n] -= q
        ws.flows[FL_RESTRICTION] = q
        if want_jac:
            jac[n, n] -= (pc.g_suction_delivery + pc.g_drain + dq) * ws.beta[n]


@njit(inline="always")
def assemble(km, op, ws, f, jac, want_jac):
    r"""dy/dt = (Σ ρ-weighted Q − ω dV/dθ) / V into ``f``; the Jacobian rows divided by the volumes.

    With ``want_jac`` also ∂f/∂t at fixed y into column N+1 of ``jac`` (from ∂(Σ Q)/∂θ booked by
    :func:`port_flows`):

    .. math::
        \frac{\partial f_j}{\partial t} = \omega\Big(\frac{\partial_\theta \Sigma Q_j
            - \omega\, d^2V_j/d\theta^2}{V_j} - f_j \frac{dV_j/d\theta}{V_j}\Big)

    Left out (small, and any approximation keeps ROS2 second order): the θ-dependence of the
    tooth-tip flows (κ_rel, v_r), of the displaced-volume terms and of the gaps; the lateral and line
    leakages do not depend on θ.  The squeeze of the gear in the stages books its own
    (:func:`.gear_coupling.gear_squeeze`).
    """
    n = km.pc.n
    n1 = n + 1
    w = op.omega
    for j in range(n):
        inv = 1.0 / ws.geo[j, G_V]
        f[j] = (ws.acc[j] - w * ws.geo[j, G_DV]) * inv
        if want_jac:
            jac[j, n1] = w * ((jac[j, n1] - w * ws.geo[j, G_DDV]) * inv - f[j] * ws.geo[j, G_SV] * inv)
            for k in range(n1):
                jac[j, k] *= inv
    if km.pc.restriction:
        inv = 1.0 / km.pc.line_volume
        f[n] = ws.acc[n] * inv
        if want_jac:
            jac[n, n1] *= w * inv
            for k in range(n1):
                jac[n, k] *= inv
    else:
        # imposed delivery pressure: y_N is not a state but the quadrature ∫ Q_delivered dt [m³],
        # integrated by the same Rosenbrock stages as the chambers (nothing depends on it)
        f[n] = ws.acc[n]
        if want_jac:
            jac[n, n1] *= w
            for k in range(n1):
                jac[k, n] = 0.0


@njit(inline="always")
def time_to_close(area, slope, omega, horizon):
    """Time [s] until a port of open area [m²] falling at slope [m²/rad] closes, if within ``horizon`` [s];
    else 0."""
    if area > 0.0 and slope < 0.0 and area < -slope * omega * horizon:
        return area / (-slope * omega)
    return 0.0


@njit          # called, not inlined: inlined into the stepper it cost 8 % per revolution, called with arrays 3 %
def closing_ports(pc, op, p, rho, geo, jac, horizon):
    """Move the shares of the ports that close within ``horizon`` [s] out of ∂f/∂t (``jac`` after
    :func:`rhs` with the Jacobian) into their own columns, with their time to close (``J_*``), for
    :func:`closing_share`.  The time to close is the linear extrapolation A / (−ω dA/dθ) (:func:`time_to_close`);
    ``horizon`` must be at least the longest sub-step (the stepper passes 8 output steps).  What the step
    control makes of closing and opening ports is its own (:func:`.step_control.port_event`).

    A port is closing where its open area falls (table slope < 0).  Its share is recomputed from the
    first stage's pressures, densities and chamber geometry (``Workspace.p``, ``rho``, ``geo``):
    ω·(∂Q/∂A)(dA/dθ)·(density ratio)/V for the chamber, ω·(...) for the delivery volume (/ its volume
    behind a restriction), as :func:`assemble` scales it.  Takes arrays, not the ``Workspace``: passing
    that tuple to a called (not inlined) function costs ≈ 0.2 µs.  Returns how many ports it found.
    """
    n = pc.n
    n1 = n + 1
    w = op.omega
    count = 0
    scale_n = w / pc.line_volume if pc.restriction else w
    for j in range(n):
        tc = time_to_close(geo[j, G_AS], geo[j, G_DAS], w, horizon)
        jac[j, n1 + J_TCS] = tc
        if tc > 0.0:
            count += 1
            inv = w / geo[j, G_V]
            dp = op.p_s - p[j]
            q, dq = port_orifice_flow(dp, geo[j, G_AS], pc.orifice_law, pc.cd_max, pc.lambda_crit,
                                      pc.laminar_delta, pc.density, pc.viscosity)  # Eq. (21)
            r = op.rho_s / rho[j] if q > 0.0 else 1.0
            c = r * area_derivative(q, dq, dp, geo[j, G_AS]) * geo[j, G_DAS] * inv
            jac[j, n1 + J_CS] = c
            jac[j, n1 + J_FT] -= c
        tc = time_to_close(geo[j, G_AD], geo[j, G_DAD], w, horizon)
        jac[j, n1 + J_TCD] = tc
        if tc > 0.0:
            count += 1
            inv = w / geo[j, G_V]
            dp = p[n] - p[j]
            q, dq = port_orifice_flow(dp, geo[j, G_AD], pc.orifice_law, pc.cd_max, pc.lambda_crit,
                                      pc.laminar_delta, pc.density, pc.viscosity)  # Eq. (21)
            st = area_derivative(q, dq, dp, geo[j, G_AD]) * geo[j, G_DAD]
            if q < 0.0:
                st = -st
            cj, cn = (rho[n] / rho[j] * st, -st) if q >= 0.0 else (-st, rho[j] / rho[n] * st)
            jac[j, n1 + J_CD] = cj * inv
            jac[j, n1 + J_CDN] = cn * scale_n
            jac[j, n1 + J_FT] -= cj * inv
            jac[n, n1 + J_FT] -= cn * scale_n
    return count


@njit          # called, not inlined (as closing_ports)
def closing_share(n, h, jac, out):
    """∂f/∂t for a sub-step of h [s] into ``out``: ∂f/∂t without the closing ports (``jac``) plus their
    shares, each scaled by min(1, t_close/h), so that the linearised flow of a port stops at its closing
    angle instead of running on through a negative area (:func:`closing_ports`)."""
    n1 = n + 1
    for i in range(n1):
        out[i] = jac[i, n1 + J_FT]
    for j in range(n):
        if jac[j, n1 + J_TCS] > 0.0:
            out[j] += jac[j, n1 + J_CS] * min(1.0, jac[j, n1 + J_TCS] / h)
        if jac[j, n1 + J_TCD] > 0.0:
            c = min(1.0, jac[j, n1 + J_TCD] / h)
            out[j] += jac[j, n1 + J_CD] * c
            out[n] += jac[j, n1 + J_CDN] * c


@njit(forceinline=True)
def rhs(y, theta, gaps, km, op, ws, f, jac, want_jac):
    """dy/dt [1/s] into ``f`` (and ∂f/∂(y, t) into ``jac`` if ``want_jac``); flows into ``ws.flows``.

    Parameters
    ----------
    y : ndarray (N+1,)
        Log-densities ln(ρ/ρ₀) [-].
    theta : float
        Shaft angle [rad].
    gaps : ndarray (N,)
        Tooth-tip gap heights at θ [m] (from :func:`gerotor_twin.model.contact.contact`).
    km, op, ws : KernelModel, Operating, Workspace

    Notes
    -----
    Inlined by LLVM (``forceinline``), not at numba's IR level: numba compiles it once, where an IR-inlined
    function is typed and lowered again at every call site.  The kernel's callers pass ``want_jac`` as
    ``bool(True)`` / ``bool(False)``: a literal ``True`` would be typed ``Literal[bool]`` and numba would compile
    one specialisation per value; after LLVM has inlined the call, the constant prunes the Jacobian's branches
    all the same (docs/performance.md, "First compile").
    """
    n = km.pc.n
    volume_states(y, km, op, ws)
    chamber_geometry(theta, km.tab, n, ws.geo, ws.disp, ws.acc, ws.ctrl)
    for i in range(ws.flows.shape[0]):
        ws.flows[i] = 0.0
    if want_jac:
        for i in range(n + 1):
            for k in range(n + 2):      # the closing ports' columns are written by closing_ports
                jac[i, k] = 0.0
    port_flows(km, op, ws, jac, want_jac)
    tip_flows(gaps, km, op, ws, jac, want_jac)
    line_flows(km, op, ws, jac, want_jac)
    if ws.gear[GC_ON] != 0.0:           # the mobility method's gear inside the stages (gear_coupling)
        gear_squeeze(theta, n, km.eos.p_atm, ws.p, ws.beta, ws.acc, ws.gear, ws.gear_rows, jac, want_jac)
    assemble(km, op, ws, f, jac, want_jac)
