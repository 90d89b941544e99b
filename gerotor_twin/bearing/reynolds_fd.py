"""Finite-difference Reynolds bearing (sec. 2.3 of [1]_, Eqs. (14)-(19)).

The film is unwrapped onto ``x = R theta`` in [0, 2 pi R) (periodic) and
``y`` in [-L/2, L/2] with ``p = 0`` on both edges.  Full Reynolds equation,
Eq. (14) of [1]_::

    d/dx(h^3 dp/dx) + d/dy(h^3 dp/dy) = 6 mu omega R dh/dx + 12 mu dh/dt
    h(x) = c - e_x cos(x/R) - e_y sin(x/R)                      (Eq. (15))

Discretisation (the paper's list after Eq. (15); the labels of the ``y``
differences are printed as ``dp/dx`` over ``Delta x`` there, a typo; we use
``dp/dy`` over ``Delta y``):

* nodes ``x_i = i dx``, ``i = 0..Nx-1``, ``dx = 2 pi R / Nx``;
  ``y_j = -L/2 + j dy``, ``j = 0..Ny-1``, ``dy = L / (Ny - 1)``: the rows
  ``j = 0`` and ``j = Ny-1`` are the edges (``p = 0``), ``Ny - 2`` unknown rows;
* ``d/dx(h^3 dp/dx) ~ [h_b^3 (p_{i+1} - p_i) - h_a^3 (p_i - p_{i-1})] / dx^2``,
  ``h_b = (h_i + h_{i+1}) / 2``, ``h_a = (h_{i-1} + h_i) / 2``;
* ``d/dy(h^3 dp/dy) = h_i^3 (p_{j+1} - 2 p_j + p_{j-1}) / dy^2`` (h is independent of y);
* ``dh/dx ~ (h_{i+1} - h_{i-1}) / (2 dx)``;
* ``dh/dt = -de_x/dt cos(x_i/R) - de_y/dt sin(x_i/R)``: exact in the unknown
  velocity.  (The paper's backward difference ``(e(t) - e(t - dt)) / dt``
  turns each time step into an implicit-Euler step of the same equations;
  here the velocity is solved for and the common integrator of
  :mod:`gerotor_twin.bearing.simulate` advances ``e``.)

Fast solve.  ``h`` and the right-hand side depend on ``x`` only, so the
``y`` operator (second difference with Dirichlet ends) is diagonalised by a
discrete sine transform (DST-I): each sine mode ``k`` gives one periodic
tridiagonal system in ``x``, solved by the Thomas algorithm with a
Sherman-Morrison correction, ``O(Nx)``.  A constant-in-``y`` right-hand side
only excites odd modes.  Reynolds is linear in ``dh/dt``, hence in
``e_dot``::

    p = p_wedge + e_dot_x p_x + e_dot_y p_y        (three right-hand sides)

Force, Eqs. (17)-(18): ``F = -sum max(p, 0) dx dy (cos, sin)(x_i/R)``
(negative pressures clipped: cavitation).  Motion equation, Eq. (19) of [1],
``F(e_dot) + F_est = 0``, is piecewise linear in ``e_dot`` and is solved by
(semismooth) Newton, started from the mobility-method velocity.

References
----------
.. [1] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2.3 (``../shared/paper``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from gerotor_twin._jit import njit
from gerotor_twin.bearing.base import KernelBearing, cap_eccentricity
from gerotor_twin.bearing.geometry import BearingGeometry
from gerotor_twin.bearing.mobility import mobility_velocity
from gerotor_twin.errors import InputError

__all__ = ["FdmBearing", "FdGrid", "make_grid", "fd_fields", "fdm_velocity", "fdm_kernel", "velocity_from_fields",
           "fdm_load", "parse_grid"]

_NEWTON_MAX_ITER = 60
_NEWTON_RTOL = 1e-12
NX_MIN, NY_MIN = 8, 3
NX_MAX, NY_MAX = 20000, 2000


@dataclass(frozen=True)
class FdGrid:
    """Grid of the unwrapped film and the precomputed sine-transform data.

    Attributes
    ----------
    nx, ny : int
        Nodes around and across the film (``ny`` includes the two edges).
    dx, dy : float
        Node spacing [m].
    x, y : numpy.ndarray
        Node coordinates [m], shapes (nx,), (ny,).
    cos_t, sin_t : numpy.ndarray
        ``cos(x_i/R)``, ``sin(x_i/R)`` [-], shape (nx,).
    lam : numpy.ndarray
        Eigenvalues of the Dirichlet second difference for the odd sine
        modes [1/m^2], shape (n_odd,).
    synth : numpy.ndarray
        ``sigma_k sin(pi k j / (ny - 1))`` for odd ``k`` and interior ``j``
        [-], shape (n_odd, ny - 2): maps modal solutions of a right-hand
        side constant in ``y`` to the interior rows.
    """

    nx: int
    ny: int
    dx: float
    dy: float
    x: np.ndarray
    y: np.ndarray
    cos_t: np.ndarray
    sin_t: np.ndarray
    lam: np.ndarray
    synth: np.ndarray


def parse_grid(text: str) -> tuple[int, int]:
    """Parse ``"320x40"`` into ``(nx, ny)``; :class:`InputError` if malformed."""
    try:
        a, b = str(text).lower().split("x")
        return int(a), int(b)
    except ValueError:
        raise InputError("grid", text, "NXxNY, e.g. 320x40") from None


def make_grid(geometry: BearingGeometry, nx: int, ny: int) -> FdGrid:
    """Build the FDM grid and its DST-I data.

    Parameters
    ----------
    geometry : BearingGeometry
        Bearing [m].
    nx : int
        Nodes around the circumference [-], >= 8 (periodic).
    ny : int
        Nodes across the width including both edges [-], >= 3.

    Returns
    -------
    FdGrid
    """
    for field, val, lo, hi in (("grid.nx", nx, NX_MIN, NX_MAX), ("grid.ny", ny, NY_MIN, NY_MAX)):
        if isinstance(val, bool) or not isinstance(val, (int, np.integer)) or not lo <= val <= hi:
            raise InputError(field, val, f"integer in [{lo}, {hi}]")
    nx, ny = int(nx), int(ny)
    r, length = geometry.radius_m, geometry.length_m
    dx = 2.0 * math.pi * r / nx
    dy = length / (ny - 1)
    x = dx * np.arange(nx)
    y = -0.5 * length + dy * np.arange(ny)
    m = ny - 2                     # unknown rows
    k = np.arange(1, m + 1, 2)     # odd sine modes (even ones are not excited)
    j = np.arange(1, m + 1)
    sines = np.sin(np.pi * np.outer(k, j) / (m + 1))
    sigma = 2.0 / (m + 1) * sines.sum(axis=1)  # sine coefficients of the constant 1
    lam = -4.0 / dy ** 2 * np.sin(0.5 * np.pi * k / (m + 1)) ** 2
    return FdGrid(nx, ny, dx, dy, x, y, np.cos(x / r), np.sin(x / r), lam,
                  np.ascontiguousarray(sigma[:, None] * sines))


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def fd_fields(ex, ey, omega, c, radius, mu, dx, cos_t, sin_t, lam, synth):
    """Solve the discrete Reynolds equation for the three right-hand sides.

    Returns ``(p_wedge, p_x, p_y)``, each of shape ``(nx, ny - 2)`` (interior
    rows): ``p = p_wedge + e_dot_x p_x + e_dot_y p_y`` [Pa] (unclipped).
    """
    nx = cos_t.size
    n_odd = lam.size
    h = c - ex * cos_t - ey * sin_t  # Eq. (15)
    h3 = h * h * h
    hb3 = np.empty(nx)  # h_b^3 at i + 1/2
    for i in range(nx):
        hb = 0.5 * (h[i] + h[(i + 1) % nx])
        hb3[i] = hb * hb * hb
    inv_dx2 = 1.0 / (dx * dx)
    # right-hand sides of Eq. (14): wedge, and 12 mu dh/dt per unit e_dot_x, e_dot_y
    rhs = np.empty((nx, 3))
    for i in range(nx):
        dhdx = (h[(i + 1) % nx] - h[(i - 1) % nx]) / (2.0 * dx)
        rhs[i, 0] = 6.0 * mu * omega * radius * dhdx
        rhs[i, 1] = -12.0 * mu * cos_t[i]
        rhs[i, 2] = -12.0 * mu * sin_t[i]
    q = np.empty((3, nx, n_odd))  # modal solutions
    cp = np.empty(nx)
    dp = np.empty((nx, 4))
    for kk in range(n_odd):
        # periodic tridiagonal: a_i q_{i-1} + b_i q_i + c_i q_{i+1} = d_i
        # a_i = h_a^3/dx^2 = hb3[i-1]/dx^2, c_i = hb3[i]/dx^2, b_i = -(a_i + c_i) + lam_k h_i^3
        a0 = hb3[nx - 1] * inv_dx2
        b0 = -(hb3[nx - 1] + hb3[0]) * inv_dx2 + lam[kk] * h3[0]
        cl = hb3[nx - 1] * inv_dx2  # c_{n-1}: couples the last row to q_0
        gam = -b0
        # Sherman-Morrison: T = T' + u v^T, u = (gam, 0.., c_{n-1}), v = (1, 0.., a_0/gam)
        for i in range(nx):
            ai = hb3[i - 1] * inv_dx2 if i > 0 else 0.0
            ci = hb3[i] * inv_dx2
            bi = -(hb3[i - 1] + hb3[i]) * inv_dx2 + lam[kk] * h3[i]
            if i == 0:
                bi -= gam
            if i == nx - 1:
                bi -= a0 * cl / gam
            d0 = rhs[i, 0]
            d1 = rhs[i, 1]
            d2 = rhs[i, 2]
            d3 = gam if i == 0 else (cl if i == nx - 1 else 0.0)
            if i == 0:
                den = bi
                dp[i, 0] = d0 / den
                dp[i, 1] = d1 / den
                dp[i, 2] = d2 / den
                dp[i, 3] = d3 / den
            else:
                den = bi - ai * cp[i - 1]
                dp[i, 0] = (d0 - ai * dp[i - 1, 0]) / den
                dp[i, 1] = (d1 - ai * dp[i - 1, 1]) / den
                dp[i, 2] = (d2 - ai * dp[i - 1, 2]) / den
                dp[i, 3] = (d3 - ai * dp[i - 1, 3]) / den
            cp[i] = ci / den
        for i in range(nx - 2, -1, -1):
            for r in range(4):
                dp[i, r] -= cp[i] * dp[i + 1, r]
        vz = dp[0, 3] + a0 / gam * dp[nx - 1, 3]
        for r in range(3):
            vy_ = dp[0, r] + a0 / gam * dp[nx - 1, r]
            fac = vy_ / (1.0 + vz)
            for i in range(nx):
                q[r, i, kk] = dp[i, r] - fac * dp[i, 3]
    p_w = np.dot(q[0], synth)
    p_x = np.dot(q[1], synth)
    p_y = np.dot(q[2], synth)
    return p_w, p_x, p_y


@njit
def _clipped_force(p_w, p_x, p_y, vx, vy, cos_t, sin_t, area):
    """Eqs. (17)-(18) at ``e_dot = (vx, vy)``: force [N] and its Jacobian [N s/m]."""
    nx, m = p_w.shape
    fx = 0.0
    fy = 0.0
    j11 = 0.0
    j12 = 0.0
    j21 = 0.0
    j22 = 0.0
    for i in range(nx):
        s = 0.0
        sx = 0.0
        sy = 0.0
        for j in range(m):
            p = p_w[i, j] + vx * p_x[i, j] + vy * p_y[i, j]
            if p > 0.0:
                s += p
                sx += p_x[i, j]
                sy += p_y[i, j]
        fx -= s * cos_t[i]
        fy -= s * sin_t[i]
        j11 -= sx * cos_t[i]
        j12 -= sy * cos_t[i]
        j21 -= sx * sin_t[i]
        j22 -= sy * sin_t[i]
    return fx * area, fy * area, j11 * area, j12 * area, j21 * area, j22 * area


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def _full_jacobian(p_x, p_y, cos_t, sin_t, area):
    """Jacobian of the unclipped force: fallback when no node is in the loaded film."""
    nx, m = p_x.shape
    j = np.zeros(4)
    for i in range(nx):
        sx = 0.0
        sy = 0.0
        for k in range(m):
            sx += p_x[i, k]
            sy += p_y[i, k]
        j[0] -= sx * cos_t[i] * area
        j[1] -= sy * cos_t[i] * area
        j[2] -= sx * sin_t[i] * area
        j[3] -= sy * sin_t[i] * area
    return j


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def _invertible(j11, j12, j21, j22, p_x, p_y, cos_t, sin_t, area):
    """The clipped force's Jacobian and its determinant, or the unclipped one's where no loaded node makes it
    singular."""
    det = j11 * j22 - j12 * j21
    jn = abs(j11) + abs(j12) + abs(j21) + abs(j22)
    if abs(det) <= 1e-14 * jn * jn:
        fj = _full_jacobian(p_x, p_y, cos_t, sin_t, area)
        j11, j12, j21, j22 = fj[0], fj[1], fj[2], fj[3]
        det = j11 * j22 - j12 * j21
    return j11, j12, j21, j22, det


@njit(_nrt=True)     # allocates arrays: with numba's reference counting (gerotor_twin._jit)
def fdm_velocity(ex, ey, fx, fy, omega, c, length, diameter, mu, dx, dy, cos_t, sin_t, lam,
                 synth):
    """Journal-centre velocity by the FDM: solve Eq. (19) of [1]_ for ``e_dot`` [m/s].

    Parameters
    ----------
    ex, ey : float
        Journal-centre displacement [m] (scaled back to ``|e| <= 0.9999 c``).
    fx, fy : float
        External load on the journal [N].
    omega : float
        Journal angular speed [rad/s].
    c, length, diameter : float
        Clearance, ``L``, ``D`` [m].
    mu : float
        Viscosity [Pa s].
    dx, dy : float
        Grid spacing [m].
    cos_t, sin_t, lam, synth : numpy.ndarray
        Grid data of :class:`FdGrid`.

    Returns
    -------
    tuple of float
        ``(de_x/dt, de_y/dt)`` [m/s].
    """
    ex, ey = cap_eccentricity(ex, ey, c)
    p_w, p_x, p_y = fd_fields(ex, ey, omega, c, 0.5 * diameter, mu, dx, cos_t, sin_t, lam, synth)
    return velocity_from_fields(p_w, p_x, p_y, ex, ey, fx, fy, omega, c, length, diameter, mu, dx * dy, cos_t, sin_t)


@njit(_nrt=True)     # allocates arrays (the fallback Jacobian): with numba's reference counting
def velocity_from_fields(p_w, p_x, p_y, ex, ey, fx, fy, omega, c, length, diameter, mu, area, cos_t, sin_t):
    """:func:`fdm_velocity` from the fields of :func:`fd_fields` at (ex, ey) [m] (capped): Eq. (19) of [1]_ solved
    for ė [m/s] by semismooth Newton from the mobility method's velocity; ``area`` = dx·dy [m²]."""
    vx, vy = mobility_velocity(ex, ey, fx, fy, omega, c, length, diameter, mu)
    gx, gy, j11, j12, j21, j22 = _clipped_force(p_w, p_x, p_y, vx, vy, cos_t, sin_t, area)
    rx = gx + fx  # Eq. (19): F_film + F_est = 0
    ry = gy + fy
    res = math.sqrt(rx * rx + ry * ry)
    scale = math.sqrt(fx * fx + fy * fy) + area * np.abs(p_w).sum()
    for _ in range(_NEWTON_MAX_ITER):
        if res <= _NEWTON_RTOL * scale:
            break
        j11, j12, j21, j22, det = _invertible(j11, j12, j21, j22, p_x, p_y, cos_t, sin_t, area)
        sx = -(j22 * rx - j12 * ry) / det
        sy = -(j11 * ry - j21 * rx) / det
        lam_ = 1.0
        for _ in range(40):
            tx = vx + lam_ * sx
            ty = vy + lam_ * sy
            hx, hy, k11, k12, k21, k22 = _clipped_force(p_w, p_x, p_y, tx, ty, cos_t, sin_t, area)
            qx = hx + fx
            qy = hy + fy
            qn = math.sqrt(qx * qx + qy * qy)
            if qn < res or lam_ < 1e-9:
                break
            lam_ *= 0.5
        if qn >= res:  # no decrease possible: converged to round-off
            break
        vx, vy, j11, j12, j21, j22, rx, ry, res = tx, ty, k11, k12, k21, k22, qx, qy, qn
    return vx, vy


@njit(_nrt=True)     # allocates arrays (the fallback Jacobian): with numba's reference counting
def fdm_load(p_w, p_x, p_y, vx, vy, cos_t, sin_t, area):
    r"""The load under which the FDM film moves the journal at ė = (vx, vy) [m/s], and ∂ė/∂F there, from the fields
    of :func:`fd_fields` at its position: Eq. (19) of [1]_ read the other way,

    .. math::
        \mathbf F = -\mathbf F_{film}(\dot{\mathbf e}),\qquad
        \frac{\partial\dot{\mathbf e}}{\partial\mathbf F} = -J^{-1},\quad J = \frac{\partial\mathbf F_{film}}
        {\partial\dot{\mathbf e}}

    (the clipped force is piecewise linear in ė, its Jacobian exact between the nodes' sign changes; where no node
    carries pressure, the unclipped one's, as in :func:`velocity_from_fields`).  No Reynolds solve and no Newton:
    one pass over the grid.  Returns ``(F_x, F_y, G_xx, G_xy, G_yx, G_yy)`` [N, m/(s·N)]."""
    gx, gy, j11, j12, j21, j22 = _clipped_force(p_w, p_x, p_y, vx, vy, cos_t, sin_t, area)
    j11, j12, j21, j22, det = _invertible(j11, j12, j21, j22, p_x, p_y, cos_t, sin_t, area)
    return -gx, -gy, -j22 / det, j12 / det, j21 / det, -j11 / det


@njit
def fdm_kernel(ex, ey, fx, fy, omega, params):
    """:func:`fdm_velocity` with ``params = (c, L, D, mu, dx, dy, cos_t, sin_t, lam, synth)``."""
    return fdm_velocity(ex, ey, fx, fy, omega, params[0], params[1], params[2], params[3],
                        params[4], params[5], params[6], params[7], params[8], params[9])


class FdmBearing(KernelBearing):
    """Full Reynolds equation by finite differences (``name = "fdm"``).

    Parameters
    ----------
    geometry : BearingGeometry
        Bearing [m, Pa s].
    nx : int, optional
        Nodes around the circumference [-] (paper: 320).
    ny : int, optional
        Nodes across the width, both edges included [-] (paper: 40).
    """

    name = "fdm"

    def __init__(self, geometry: BearingGeometry, nx: int = 320, ny: int = 40):
        super().__init__(geometry)
        self.grid = make_grid(geometry, nx, ny)
        g, gr = geometry, self.grid
        self.kernel = fdm_kernel
        self.params = (g.clearance_m, g.length_m, g.diameter_m, g.viscosity_pa_s, gr.dx, gr.dy,
                       gr.cos_t, gr.sin_t, gr.lam, gr.synth)

    def _fields(self, e, omega):
        g, gr = self.geometry, self.grid
        ex, ey = e
        return fd_fields(ex, ey, omega, g.clearance_m, g.radius_m, g.viscosity_pa_s, gr.dx,
                         gr.cos_t, gr.sin_t, gr.lam, gr.synth)

    def pressure_field(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        """Solution of the discrete Eq. (16) on the whole grid [Pa], unclipped.

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
        numpy.ndarray, shape (nx, ny)
            ``p[i, j]`` at ``(grid.x[i], grid.y[j])``; the edge columns are 0.
        """
        ev, ed, w = self._film_args(e, e_dot, omega)
        p_w, p_x, p_y = self._fields(ev, w)
        p = np.zeros((self.grid.nx, self.grid.ny))
        p[:, 1:-1] = p_w + ed[0] * p_x + ed[1] * p_y
        return p

    def film_force(self, e: np.ndarray, e_dot: np.ndarray, omega: float) -> np.ndarray:
        """Film force on the journal [N], Eqs. (17)-(18) (negative pressure clipped).

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
        p_w, p_x, p_y = self._fields(ev, w)
        gr = self.grid
        f = _clipped_force(p_w, p_x, p_y, ed[0], ed[1], gr.cos_t, gr.sin_t, gr.dx * gr.dy)
        return np.array(f[:2])
