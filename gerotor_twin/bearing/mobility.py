"""Booker's mobility method for the short bearing (sec. 2.2 of [1]_).

The mobility method [2]_ inverts the film-force law: instead of solving the
force balance for the velocity, it gives the velocity explicitly from the
load.  For the short bearing the squeeze velocity (journal-centre velocity
relative to a frame turning at half the journal speed) is

.. math::

    \\mathbf v = c\\,K\\,R(\\psi)\\,\\mathbf M(\\zeta,\\kappa),\\qquad
    K = \\frac{|\\mathbf F|\\,(c/R)^2}{\\mu L D},

with ``psi`` the load direction, ``R(psi)`` the rotation by ``psi`` and
``zeta``, ``kappa`` the eccentricity-ratio components along and across the
load.  In the housing-fixed frame (DESIGN.md, "Known errata") the centre
velocity is

.. math::

    \\dot{\\mathbf e} = c\\,K\\,R(\\psi)\\,\\mathbf M(\\zeta,\\kappa)
                      + \\tfrac{\\omega}{2}\\,\\mathbf k\\times\\mathbf e ,

which is Eqs. (7)-(8) of [1]_ (written there in a frame turning with the
load, ``omega_bar = omega/2 - psi_dot``) without the polar singularity at
``e = 0`` and valid for any load history.

The short-bearing mobility is Eq. (9) of [1]_ with the corrected kappa term
(see :func:`mobility_components`).  It is Booker's closed-form fit of the
short pi-film mobility, not the exact inverse of the film force: against the
exact pi-film force (:func:`gerotor_twin.bearing.closed_form.short_bearing_force`)
the load it implies is within ~5 %, and the steady equilibrium within 0.5 %
in eccentricity and 0.7 deg in attitude angle of Ocvirk's closed form.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2.2 (``../shared/paper``).
.. [2] J. F. Booker, "Dynamically loaded journal bearings: mobility method of
   solution", J. Basic Eng. 87 (1965) 537-546.
.. [3] F. W. Ocvirk, "Short-bearing approximation for full journal
   bearings", NACA TN 2808, 1952.
"""
from __future__ import annotations

import math

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.bearing.base import KernelBearing, cap_eccentricity
from gerotor_twin.bearing.closed_form import short_bearing_force
from gerotor_twin.bearing.geometry import BearingGeometry

__all__ = ["MobilityBearing", "mobility_velocity", "mobility_kernel", "mobility_components", "mobility_linearised",
           "mobility_linearised_kernel"]


@njit
def mobility_components(zeta, kappa, ld):
    """Short-bearing mobility vector in the load frame, Eq. (9) of [1]_ corrected.

    .. math::

        M^\\zeta = \\frac{(1-\\zeta)^{5/2}}{\\pi (L/D)^2},\\qquad
        M^\\kappa = -\\frac{4\\kappa(1-\\zeta)^{3/2}}{\\pi^2 (L/D)^2}

    Parameters
    ----------
    zeta : float
        Eccentricity ratio along the load [-], |zeta| < 1.
    kappa : float
        Eccentricity ratio across the load (90 deg counter-clockwise) [-].
    ld : float
        Slenderness ``L / D`` [-].

    Returns
    -------
    tuple of float
        ``(M_zeta, M_kappa)`` [-].

    Notes
    -----
    The paper's second branch (``F < 0``: ``zeta -> -zeta`` and the sign of
    ``M_kappa`` flipped) is a load of the opposite direction; with the load
    direction ``psi = atan2(F_y, F_x)`` and ``|F| >= 0`` it is never needed
    (it equals ``psi -> psi + pi``).
    """
    one_m = 1.0 - zeta
    if one_m < 0.0:
        one_m = 0.0
    den = ld * ld
    root = math.sqrt(one_m)                   # (1 − ζ)^{5/2}, ^{3/2} by one root: a pow() costs ≈ 14 ns
    m_zeta = one_m * one_m * root / (math.pi * den)  # Eq. (9)
    # Eq. (9), corrected: M^kappa = -4 kappa (1 - zeta)^{3/2} / (pi^2 (L/D)^2); the printed
    # (1 - zeta)^{1/2} and pi give an attitude angle 2-4x too small (DESIGN.md, Known errata).
    m_kappa = -4.0 * kappa * (one_m * root) / (math.pi * math.pi * den)
    return m_zeta, m_kappa


@njit(inline="always")
def _load_frame(ex, ey, fx, fy, c, length, diameter, mu):
    """The state in the load's frame, Eqs. (7)-(13) of [1]_: e capped (:func:`cap_eccentricity`) [m], |F| [N], the
    load's direction (cos ψ, sin ψ; (1, 0) at zero load), ζ, κ [-] and the scale s = c (c/R)² / (μ L D) [m/(s·N)]."""
    ex, ey = cap_eccentricity(ex, ey, c)
    fmag = math.sqrt(fx * fx + fy * fy)
    if fmag > 0.0:
        cpsi = fx / fmag  # R(psi): rotation to the load direction
        spsi = fy / fmag
    else:
        cpsi = 1.0
        spsi = 0.0
    zeta = (ex * cpsi + ey * spsi) / c  # Eq. (12), in the load frame
    kappa = (ey * cpsi - ex * spsi) / c  # Eq. (13)
    radius = 0.5 * diameter
    s = c * (c / radius) ** 2 / (mu * length * diameter)
    return ex, ey, fmag, cpsi, spsi, zeta, kappa, s


@njit
def mobility_velocity(ex, ey, fx, fy, omega, c, length, diameter, mu):
    """Journal-centre velocity by the short-bearing mobility method.

    Housing-fixed form of Eqs. (7)-(13) of [1]_ (see the module docstring).
    Scalar, numba-compiled: callable from other numba kernels.

    Parameters
    ----------
    ex, ey : float
        Journal-centre displacement [m] (scaled back to ``|e| <= 0.9999 c``
        if beyond, so the result is always finite).
    fx, fy : float
        External load on the journal [N]; any direction, may be zero.
    omega : float
        Journal angular speed [rad/s], counter-clockwise positive.
    c : float
        Radial clearance [m].
    length : float
        Bearing length ``L`` [m].
    diameter : float
        Journal diameter ``D`` [m].
    mu : float
        Dynamic viscosity [Pa s].

    Returns
    -------
    tuple of float
        ``(de_x/dt, de_y/dt)`` [m/s].
    """
    ex, ey, _fmag, _cpsi, _spsi, zeta, kappa, s = _load_frame(ex, ey, fx, fy, c, length, diameter, mu)
    m_zeta, m_kappa = mobility_components(zeta, kappa, length / diameter)
    # c K R(psi) M with K = |F| (c/R)^2 / (mu L D), Eqs. (7)-(8); |F| R(psi) = [[fx, -fy], [fy, fx]]
    vx = s * (fx * m_zeta - fy * m_kappa)
    vy = s * (fy * m_zeta + fx * m_kappa)
    # + (omega/2) k x e: the frame of Eqs. (7)-(8) turns at omega_bar = omega/2 - psi_dot
    return vx - 0.5 * omega * ey, vy + 0.5 * omega * ex


@njit
def mobility_linearised(ex, ey, fx, fy, omega, c, length, diameter, mu):
    r"""Journal-centre velocity by the mobility method and its derivative in the load, in closed form.

    The velocity is :func:`mobility_velocity`'s, to the last bit; its load derivative
    :math:`G = \partial\dot{\mathbf e}/\partial\mathbf F` follows from Eqs. (7)–(13) of [1]_ (Eq. (9)
    corrected) by the chain rule through the load's magnitude and direction.  With
    :math:`\mathbf u = \mathbf F/|\mathbf F|`, :math:`\partial\mathbf u/\partial\mathbf F = (I - \mathbf u
    \mathbf u^T)/|\mathbf F|`:

    .. math::

        \frac{\partial\zeta}{\partial\mathbf F} = \frac{\mathbf e/c - \zeta\mathbf u}{|\mathbf F|},\qquad
        \frac{\partial\kappa}{\partial\mathbf F} = \frac{\mathbf w - \kappa\mathbf u}{|\mathbf F|},\quad
        \mathbf w = (e_y, -e_x)/c,

        \dot e_x = s\,(F_x M^\zeta - F_y M^\kappa),\qquad \dot e_y = s\,(F_y M^\zeta + F_x M^\kappa)
        \;(+\ \tfrac{\omega}{2}\mathbf k\times\mathbf e),

    with :math:`dM^\zeta/d\zeta = -\tfrac52 (1-\zeta)^{3/2}/(\pi (L/D)^2)`,
    :math:`\partial M^\kappa/\partial\zeta = 6\kappa(1-\zeta)^{1/2}/(\pi^2 (L/D)^2)`,
    :math:`\partial M^\kappa/\partial\kappa = -4(1-\zeta)^{3/2}/(\pi^2 (L/D)^2)`.

    Parameters
    ----------
    ex, ey, fx, fy, omega, c, length, diameter, mu
        As :func:`mobility_velocity` [m, N, rad/s, m, m, m, Pa s].

    Returns
    -------
    tuple of float
        ``(de_x/dt, de_y/dt)`` [m/s] and G row-major ``(gxx, gxy, gyx, gyy)`` [m/(s·N)].

    Notes
    -----
    At zero load the direction is undefined and the velocity is not differentiable there (a cone in F): G is
    then taken by a forward difference of 1 N along each axis, as a finite difference would.  Where the
    ζ-clip of :func:`mobility_components` is active (never for a finite load and ``|e| < c``) the derivative is
    the clipped branch's, zero.
    """
    if fx == 0.0 and fy == 0.0:
        vx, vy = mobility_velocity(ex, ey, 0.0, 0.0, omega, c, length, diameter, mu)
        ax, ay = mobility_velocity(ex, ey, 1.0, 0.0, omega, c, length, diameter, mu)
        bx, by = mobility_velocity(ex, ey, 0.0, 1.0, omega, c, length, diameter, mu)
        return vx, vy, ax - vx, bx - vx, ay - vy, by - vy
    ex, ey, fmag, ux, uy, zeta, kappa, s = _load_frame(ex, ey, fx, fy, c, length, diameter, mu)
    m_zeta, m_kappa = mobility_components(zeta, kappa, length / diameter)
    vx = s * (fx * m_zeta - fy * m_kappa)                # Eqs. (7)-(8)
    vy = s * (fy * m_zeta + fx * m_kappa)
    ld2 = (length / diameter) ** 2
    one_m = max(1.0 - zeta, 0.0)
    root = math.sqrt(one_m)
    dz_dz = -2.5 * one_m * root / (math.pi * ld2)                          # dM^ζ/dζ
    dk_dz = 6.0 * kappa * root / (math.pi * math.pi * ld2)                 # ∂M^κ/∂ζ
    dk_dk = -4.0 * one_m * root / (math.pi * math.pi * ld2)                # ∂M^κ/∂κ
    zx = (ex / c - zeta * ux) / fmag                     # ∂ζ/∂F
    zy = (ey / c - zeta * uy) / fmag
    kx = (ey / c - kappa * ux) / fmag                    # ∂κ/∂F
    ky = (-ex / c - kappa * uy) / fmag
    mzx, mzy = dz_dz * zx, dz_dz * zy                    # ∂M^ζ/∂F
    mkx, mky = dk_dz * zx + dk_dk * kx, dk_dz * zy + dk_dk * ky            # ∂M^κ/∂F
    gxx = s * (m_zeta + fx * mzx - fy * mkx)
    gxy = s * (fx * mzy - m_kappa - fy * mky)
    gyx = s * (fy * mzx + m_kappa + fx * mkx)
    gyy = s * (m_zeta + fy * mzy + fx * mky)
    return vx - 0.5 * omega * ey, vy + 0.5 * omega * ex, gxx, gxy, gyx, gyy


@njit
def mobility_linearised_kernel(ex, ey, fx, fy, omega, params):
    """:func:`mobility_linearised` with ``params = (c, L, D, mu)``."""
    return mobility_linearised(ex, ey, fx, fy, omega, params[0], params[1], params[2], params[3])


@njit
def mobility_kernel(ex, ey, fx, fy, omega, params):
    """:func:`mobility_velocity` with ``params = (c, L, D, mu)``: the simulate kernel."""
    return mobility_velocity(ex, ey, fx, fy, omega, params[0], params[1], params[2], params[3])


class MobilityBearing(KernelBearing):
    """Short-bearing mobility method (``name = "mobility"``).

    Parameters
    ----------
    geometry : BearingGeometry
        Bearing [m, Pa s].
    """

    name = "mobility"

    def __init__(self, geometry: BearingGeometry):
        super().__init__(geometry)
        g = geometry
        self.kernel = mobility_kernel
        self.params = (g.clearance_m, g.length_m, g.diameter_m, g.viscosity_pa_s)

    def film_force(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        """Film force implied by the mobility method: the inverse of :meth:`velocity`.

        Solves ``velocity(e, W, omega) = e_dot`` for the load ``W`` (2x2
        Newton, started from the exact short-bearing pi-film force) and
        returns ``-W``.

        Parameters
        ----------
        e : array_like, shape (2,)
            Journal-centre displacement [m], ``|e| < c``.
        e_dot : array_like, shape (2,)
            Journal-centre velocity [m/s].
        omega : float
            Journal angular speed [rad/s].

        Returns
        -------
        numpy.ndarray, shape (2,)
            Force on the journal [N].
        """
        ev, ed, w = self._film_args(e, e_dot, omega)
        c, length, diameter, mu = self.params
        v = ed - 0.5 * w * np.array([-ev[1], ev[0]])  # squeeze velocity to reproduce
        vn = math.hypot(v[0], v[1])
        if vn == 0.0:
            return np.zeros(2)

        def resid(load):
            return np.array(mobility_velocity(ev[0], ev[1], load[0], load[1], 0.0,
                                              c, length, diameter, mu)) - v

        load = -short_bearing_force(ev, ed, w, self.geometry)
        r = resid(load)
        for _ in range(60):
            if math.hypot(r[0], r[1]) <= 1e-13 * vn:
                break
            h = 1e-7 * max(math.hypot(load[0], load[1]), 1e-30)
            jac = np.empty((2, 2))
            for k in range(2):
                d = np.zeros(2)
                d[k] = h
                jac[:, k] = (resid(load + d) - resid(load - d)) / (2.0 * h)
            step = np.linalg.solve(jac, -r)
            lam = 1.0
            while lam > 1e-4:
                r_new = resid(load + lam * step)
                if np.linalg.norm(r_new) < np.linalg.norm(r):
                    break
                lam *= 0.5
            load = load + lam * step
            r = r_new
        return -load
