"""Load on the outer gear from the chamber pressures and the driving contact (sec. 3.6 of [1]).

References
----------
.. [1] The paper, sec. 3.6, Eqs. (24)–(27) (``../shared/paper``).
"""
from __future__ import annotations

import math

from .._jit import njit
from ..geometry.tables import ARM, FX, FY, GX, GY, TQ
from .contact import column, locate

__all__ = ["outer_gear_load", "journal_torque"]


@njit(inline="always")
def journal_torque(ex, ey, omega, pc):
    """Journal-bearing torque on the outer gear, Eq. (27) of [1] corrected [N·m].

    The Petroff-type torque −2π μ ω₂ L r³ / (c √(1 − ε²)), ω₂ = ω (N − 1)/N the outer gear's speed
    [rad/s], ε = |e|/c capped at 0.999; (ex, ey) [m], ω the shaft speed [rad/s], ``pc`` the
    :class:`~.params.PumpConstants`.
    """
    c = pc.housing_clearance
    eps = min(math.hypot(ex, ey) / c, 0.999)
    omega2 = omega * (pc.n - 1) / pc.n
    return (-2.0 * math.pi * pc.viscosity * omega2 * pc.width * pc.journal_radius ** 3
            / (c * math.sqrt(1.0 - eps * eps)))     # Eq. (27), corrected


@njit
def outer_gear_load(pres, theta, omega, ex, ey, kc, km):
    """Load on the outer gear, F_est = F_p + F_c, Eqs. (24)–(27) of [1] [N].

    Parameters
    ----------
    pres : ndarray (N+1,)
        Absolute pressures of the chambers (and delivery volume) [Pa].
    theta : float
        Shaft angle [rad].
    omega : float
        Shaft speed [rad/s].
    ex, ey : float
        Outer-gear displacement [m].
    kc : int
        Lobe in contact.
    km : KernelModel

    Returns
    -------
    (fx, fy, contact_force, unloaded) : (float, float, float, int)
        Load [N], contact force [N] (≥ 0), 1 if the contact would pull (then F_c = 0).

    Notes
    -----
    Pressures act as gauge pressures (the ambient integrates to zero over the
    closed gear).  Eq. (24) is written with p_j (printed p_i); Eq. (27) is
    corrected to the Petroff-type torque 2π μ ω₂ L r³ / (c √(1−ε²)).
    """
    tab, pc = km.tab, km.pc
    n = pc.n
    fx = 0.0
    fy = 0.0
    cp = 0.0
    for j in range(n):
        i0, i1, f = locate(tab, theta + j * tab.shift)
        pg = pres[j] - km.eos.p_atm
        fx += pg * column(tab, FX, i0, i1, f)       # Eq. (24), corrected: p_j (printed p_i)
        fy += pg * column(tab, FY, i0, i1, f)
        cp += pg * column(tab, TQ, i0, i1, f)       # Eq. (25)
    cjb = journal_torque(ex, ey, omega, pc)
    i0, i1, f = locate(tab, theta + kc * tab.shift)
    arm = column(tab, ARM, i0, i1, f)
    fc = 0.0
    unloaded = 0
    if abs(arm) > 1e-9:
        fc = -(cp + cjb) / arm                     # Eq. (26): C_p + C_jb + r_c × F_c = 0
    if fc < 0.0:
        fc = 0.0
        unloaded = 1
    nx = column(tab, GX, i0, i1, f)
    ny = column(tab, GY, i0, i1, f)
    nn = math.hypot(nx, ny)
    return fx + fc * nx / nn, fy + fc * ny / nn, fc, unloaded
