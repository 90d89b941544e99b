"""Method 1 of [1]_ (sec. 2.1): short-bearing pressure, positive part, force balance.

Pressure (Ocvirk short bearing with squeeze, Eq. (4) of [1]_)::

    p = 3 mu / c^2 * [(omega - 2 phi_dot) eps sin(a) - 2 eps_dot cos(a)]
        / (1 - eps cos(a))^3 * (z^2 - L^2/4),        a = theta - phi

The bracket equals ``-(2/c) v . n(theta)`` with the squeeze velocity
``v = e_dot - (omega/2) k x e`` (radial component ``c eps_dot``, tangential
``c eps (phi_dot - omega/2)``); that Cartesian form is what the kernel
evaluates, because it has no polar singularity at ``e = 0``.  ``p > 0`` exactly
on the half circle ``v . n > 0``: the positive-pressure region is known
analytically once ``v`` is known, and the force of Eq. (5) is integrated
numerically over that half circle only:

* the ``z`` integral is analytic: ``int (z^2 - L^2/4) dz = -L^3/6``;
* the ``theta`` integral is Gauss-Legendre in the Sommerfeld variable
  ``gamma`` (``1 - eps cos a = (1 - eps^2)/(1 + eps cos gamma)``), which
  clusters the nodes at the pressure peak and stays accurate up to
  ``eps -> 1`` (24 nodes give round-off accuracy).

The motion equation, Eq. (6) of [1], ``F_film(e, e_dot) + F_est = 0``, is solved for
``e_dot`` by Newton's method.  Inside the positive region the force is linear
in ``v``, ``F = -A(v_dir) v``, and the derivative of the region boundary adds
nothing (the pressure is zero there), so the exact Jacobian is ``-A``; the
iteration starts from the mobility-method velocity and converges in 1-4
steps (typically 3).

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2.1 (``../shared/paper``).
.. [2] F. W. Ocvirk, "Short-bearing approximation for full journal
   bearings", NACA TN 2808, 1952.
.. [3] B. J. Hamrock, S. R. Schmid, B. O. Jacobson, *Fundamentals of Fluid
   Film Lubrication*, 2nd ed., 2004.
"""
from __future__ import annotations

import math

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.bearing.base import KernelBearing, cap_eccentricity
from gerotor_twin.bearing.geometry import BearingGeometry
from gerotor_twin.bearing.mobility import mobility_velocity
from gerotor_twin.errors import InputError

__all__ = ["ShortBearing", "pressure", "short_film_force", "short_velocity", "short_kernel", "short_load"]

_NEWTON_MAX_ITER = 60
_NEWTON_RTOL = 1e-12


def pressure(theta, z, eps, phi, eps_dot, phi_dot, omega, geometry: BearingGeometry):
    """Short-bearing film pressure, Eq. (4) of [1]_ (unclipped).

    Parameters
    ----------
    theta : array_like
        Angle in the housing frame [rad].
    z : array_like
        Axial position [m], -L/2 <= z <= L/2.
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1.
    phi : float
        Angle of the eccentricity vector (minimum film) [rad].
    eps_dot : float
        d(eps)/dt [1/s].
    phi_dot : float
        d(phi)/dt [rad/s].
    omega : float
        Journal angular speed [rad/s].
    geometry : BearingGeometry
        Bearing [m, Pa s].

    Returns
    -------
    numpy.ndarray
        Gauge pressure [Pa] (negative values are not physical: cavitation).
    """
    g = geometry
    a = np.asarray(theta, dtype=float) - phi
    z = np.asarray(z, dtype=float)
    bracket = ((omega - 2.0 * phi_dot) * eps * np.sin(a) - 2.0 * eps_dot * np.cos(a)) \
        / (1.0 - eps * np.cos(a)) ** 3
    # Eq. (4)
    return 3.0 * g.viscosity_pa_s / g.clearance_m ** 2 * bracket * (z ** 2 - g.length_m ** 2 / 4.0)


@njit
def _pi_film(ex, ey, vx, vy, c, length, radius, mu, nodes, weights):
    """Force of the positive film for squeeze velocity ``v`` and its Jacobian.

    Returns ``(Fx, Fy, a11, a12, a22)``: force on the journal [N] and the
    matrix ``A = -dF/dv`` [N s/m].
    """
    fx = 0.0
    fy = 0.0
    a11 = 0.0
    a12 = 0.0
    a22 = 0.0
    r = math.sqrt(ex * ex + ey * ey)
    eps = r / c
    phi = math.atan2(ey, ex)
    root = math.sqrt((1.0 - eps) * (1.0 + eps))
    beta = math.sqrt((1.0 + eps) / (1.0 - eps))
    pbar_scale = mu * length ** 3 / c ** 3  # (3 mu / c^2) * (L^3 / 6) * (2 / c)
    # direction of v relative to the line of centres, in (-pi, pi]
    alpha_v = math.atan2(vy, vx) - phi
    if alpha_v > math.pi:
        alpha_v -= 2.0 * math.pi
    elif alpha_v <= -math.pi:
        alpha_v += 2.0 * math.pi
    lo = alpha_v - 0.5 * math.pi
    hi = alpha_v + 0.5 * math.pi
    # split the half circle where the Sommerfeld map wraps (alpha = +-pi)
    for piece in range(2):
        if piece == 0:
            a0 = max(lo, -math.pi)
            a1 = min(hi, math.pi)
        elif lo < -math.pi:
            a0 = lo + 2.0 * math.pi
            a1 = math.pi
        elif hi > math.pi:
            a0 = -math.pi
            a1 = hi - 2.0 * math.pi
        else:
            break
        g0 = 2.0 * math.atan2(beta * math.sin(0.5 * a0), math.cos(0.5 * a0))
        g1 = 2.0 * math.atan2(beta * math.sin(0.5 * a1), math.cos(0.5 * a1))
        gm = 0.5 * (g0 + g1)
        gh = 0.5 * (g1 - g0)
        for k in range(nodes.size):
            gam = gm + gh * nodes[k]
            alpha = 2.0 * math.atan2(math.sin(0.5 * gam), beta * math.cos(0.5 * gam))
            dalpha = weights[k] * gh * root / (1.0 + eps * math.cos(gam))
            theta = phi + alpha
            nx = math.cos(theta)
            ny = math.sin(theta)
            hbar = 1.0 - eps * math.cos(alpha)  # h / c, Eq. (3)
            # z-integrated Eq. (4): bracket = -(2/c) v.n, int (z^2 - L^2/4) dz = -L^3/6
            weight = pbar_scale / (hbar * hbar * hbar)
            pbar = weight * (vx * nx + vy * ny)
            if pbar < 0.0:
                pbar = 0.0
            # Eq. (5), corrected: area element R d(theta) dz; force on the journal = -int p n
            fx -= radius * pbar * nx * dalpha
            fy -= radius * pbar * ny * dalpha
            wa = radius * weight * dalpha
            a11 += wa * nx * nx
            a12 += wa * nx * ny
            a22 += wa * ny * ny
    return fx, fy, a11, a12, a22


@njit
def short_film_force(ex, ey, edx, edy, omega, c, length, diameter, mu, nodes, weights):
    """Film force on the journal by Method 1, Eqs. (4)-(5) of [1]_ [N].

    Parameters as :func:`short_velocity`, with ``edx, edy`` the journal-centre
    velocity [m/s].  Returns ``(Fx, Fy)``.
    """
    ex, ey = cap_eccentricity(ex, ey, c)
    vx = edx + 0.5 * omega * ey  # v = e_dot - (omega/2) k x e
    vy = edy - 0.5 * omega * ex
    if vx == 0.0 and vy == 0.0:
        return 0.0, 0.0
    fx, fy, _, _, _ = _pi_film(ex, ey, vx, vy, c, length, 0.5 * diameter, mu, nodes, weights)
    return fx, fy


@njit
def short_velocity(ex, ey, fx, fy, omega, c, length, diameter, mu, nodes, weights):
    """Journal-centre velocity by Method 1: solve Eq. (6) of [1]_ for ``e_dot``.

    Parameters
    ----------
    ex, ey : float
        Journal-centre displacement [m] (scaled back to ``|e| <= 0.9999 c``).
    fx, fy : float
        External load on the journal [N].
    omega : float
        Journal angular speed [rad/s].
    c, length, diameter : float
        Clearance, length ``L`` and diameter ``D`` [m].
    mu : float
        Viscosity [Pa s].
    nodes, weights : numpy.ndarray
        Gauss-Legendre rule on [-1, 1] for the theta quadrature.

    Returns
    -------
    tuple of float
        ``(de_x/dt, de_y/dt)`` [m/s].
    """
    ex, ey = cap_eccentricity(ex, ey, c)
    wx = 0.5 * omega * ey  # (omega/2) k x e = (-omega ey / 2, omega ex / 2)
    wy = -0.5 * omega * ex
    fmag = math.sqrt(fx * fx + fy * fy)
    if fmag == 0.0:
        return -wx, -wy
    radius = 0.5 * diameter
    # start: mobility-method squeeze velocity (Booker's fit of the same film)
    dmx, dmy = mobility_velocity(ex, ey, fx, fy, omega, c, length, diameter, mu)
    vx = dmx + wx
    vy = dmy + wy
    gx, gy, a11, a12, a22 = _pi_film(ex, ey, vx, vy, c, length, radius, mu, nodes, weights)
    rx = gx + fx  # Eq. (6): F_film + F_est = 0
    ry = gy + fy
    res = math.sqrt(rx * rx + ry * ry)
    for _ in range(_NEWTON_MAX_ITER):
        if res <= _NEWTON_RTOL * fmag:
            break
        det = a11 * a22 - a12 * a12
        sx = (a22 * rx - a12 * ry) / det  # Newton step: dv = A^-1 r (Jacobian dF/dv = -A)
        sy = (a11 * ry - a12 * rx) / det
        lam = 1.0
        for _ in range(30):
            tx = vx + lam * sx
            ty = vy + lam * sy
            hx, hy, b11, b12, b22 = _pi_film(ex, ey, tx, ty, c, length, radius, mu, nodes, weights)
            qx = hx + fx
            qy = hy + fy
            qn = math.sqrt(qx * qx + qy * qy)
            if qn < res or lam < 1e-6:
                break
            lam *= 0.5
        vx, vy, a11, a12, a22, rx, ry, res = tx, ty, b11, b12, b22, qx, qy, qn
    return vx - wx, vy - wy


@njit
def short_kernel(ex, ey, fx, fy, omega, params):
    """:func:`short_velocity` with ``params = (c, L, D, mu, nodes, weights)``."""
    return short_velocity(ex, ey, fx, fy, omega, params[0], params[1], params[2], params[3],
                          params[4], params[5])


@njit
def short_load(ex, ey, vx, vy, omega, params):
    r"""The load under which Method 1 moves the journal at ė = (vx, vy) [m/s], and ∂ė/∂F there: the inverse of
    :func:`short_kernel` in closed form, with ``params = (c, L, D, mu, nodes, weights)``.

    Eq. (6) of [1]_ read the other way: the positive film's force at the squeeze velocity u = ė + (ω/2) k × e
    balances the load,

    .. math::
        \mathbf F = -\mathbf F_{film}(\mathbf u),\qquad
        \frac{\partial\dot{\mathbf e}}{\partial\mathbf F} = A^{-1},\quad A = -\frac{\partial\mathbf F_{film}}
        {\partial\mathbf u}

    (the film's edges carry no pressure, so A is the Jacobian :func:`_pi_film` integrates; it is symmetric
    positive definite for |e| < c).  One film integral, where :func:`short_kernel` iterates Newton on it.

    Returns
    -------
    tuple of float
        ``(F_x, F_y, G_xx, G_xy, G_yx, G_yy)``: the load [N] and ∂ė/∂F row-major [m/(s·N)].
    """
    c, length, diameter, mu, nodes, weights = params
    ex, ey = cap_eccentricity(ex, ey, c)
    ux = vx + 0.5 * omega * ey          # u = ė + (ω/2) k × e, as in :func:`short_velocity`
    uy = vy - 0.5 * omega * ex
    gx, gy, a11, a12, a22 = _pi_film(ex, ey, ux, uy, c, length, 0.5 * diameter, mu, nodes, weights)
    det = a11 * a22 - a12 * a12
    return -gx, -gy, a22 / det, -a12 / det, -a12 / det, a11 / det


class ShortBearing(KernelBearing):
    """Method 1: Ocvirk short bearing with squeeze, pi-film, numerical force.

    Parameters
    ----------
    geometry : BearingGeometry
        Bearing [m, Pa s].
    n_nodes : int, optional
        Gauss-Legendre nodes per arc of the positive film [-], 4..200
        (default 24: round-off accuracy for any eps < 1).
    """

    name = "short"

    def __init__(self, geometry: BearingGeometry, n_nodes: int = 24):
        super().__init__(geometry)
        if isinstance(n_nodes, bool) or not isinstance(n_nodes, (int, np.integer)) \
                or not 4 <= n_nodes <= 200:
            raise InputError("n_nodes", n_nodes, "integer in [4, 200]")
        nodes, weights = np.polynomial.legendre.leggauss(int(n_nodes))
        g = geometry
        self.kernel = short_kernel
        self.params = (g.clearance_m, g.length_m, g.diameter_m, g.viscosity_pa_s,
                       np.ascontiguousarray(nodes), np.ascontiguousarray(weights))

    def film_force(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        """Film force on the journal [N], Eqs. (4)-(5) of [1]_, positive pressure only.

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
        """
        ev, ed, w = self._film_args(e, e_dot, omega)
        p = self.params
        return np.array(short_film_force(ev[0], ev[1], ed[0], ed[1], w, *p))
