"""Closed forms of the short (Ocvirk) journal bearing with a pi-film.

These are the references the bearing models are tested against.  They are
analytic (no quadrature), written independently of the numerical models.

Short-bearing theory [1]_ drops the circumferential Poiseuille term of the
Reynolds equation (Eq. (2) of [4]_); the pressure is parabolic across the
width and proportional to the *squeeze velocity*

.. math::

    \\mathbf v = \\dot{\\mathbf e} - \\tfrac{\\omega}{2}\\,\\mathbf k\\times\\mathbf e ,

the velocity of the journal centre seen from a frame turning at half the
journal speed.  With the half-Sommerfeld (pi-film, "cavitated") condition
only the positive half of the film carries load, which is exactly the half
circle where :math:`\\mathbf v\\cdot\\mathbf n(\\theta) > 0`.

Conventions: housing-fixed frame, angles counter-clockwise from +x, journal
speed ``omega`` > 0 counter-clockwise, ``e`` is the journal-centre
displacement (minimum film at the angle of ``e``), forces are forces *on the
journal*.  Under a steady load ``W`` the journal settles at ``e`` rotated
from the direction of ``W`` by the attitude angle ``phi`` in the sense of
rotation.

References
----------
.. [1] F. W. Ocvirk, "Short-bearing approximation for full journal bearings",
   NACA TN 2808, 1952.
.. [2] J. F. Booker, "Dynamically loaded journal bearings: mobility method of
   solution", J. Basic Eng. 87 (1965) 537-546.
.. [3] B. J. Hamrock, S. R. Schmid, B. O. Jacobson, *Fundamentals of Fluid
   Film Lubrication*, 2nd ed., Marcel Dekker, 2004 (short-bearing and
   squeeze-film journal bearings).
.. [4] "Modelling of a Gerotor pump including the evaluation of the
   micro-movements of the external gear", sec. 2 (``../shared/paper``).
"""
from __future__ import annotations

import math

import numpy as np

from gerotor_twin.bearing.geometry import BearingGeometry
from gerotor_twin.errors import InputError, check_range

__all__ = [
    "ocvirk_load", "ocvirk_load_components", "ocvirk_attitude_angle",
    "ocvirk_eccentricity", "ocvirk_equilibrium", "pi_film_integrals",
    "short_bearing_force", "squeeze_load_factor", "squeeze_approach_speed",
]


def _check_eps(eps: float) -> float:
    return check_range("eps", eps, 0.0, 1.0, hi_open=True)


def _load_scale(geometry: BearingGeometry, omega: float) -> float:
    """``mu |omega| R L^3 / c^2`` [N], the short-bearing load scale."""
    g = geometry
    return g.viscosity_pa_s * abs(omega) * g.radius_m * g.length_m ** 3 / g.clearance_m ** 2


def ocvirk_load_components(eps: float, geometry: BearingGeometry,
                           omega: float) -> tuple[float, float]:
    """Steady short-bearing film force along and across the line of centres.

    .. math::

        W_r = \\frac{\\mu\\omega R L^3}{c^2}\\frac{\\varepsilon^2}{(1-\\varepsilon^2)^2},\\qquad
        W_t = \\frac{\\mu\\omega R L^3}{c^2}\\frac{\\pi\\varepsilon}{4(1-\\varepsilon^2)^{3/2}}

    (Ocvirk [1]_, Hamrock [3]_ ch. "short-width journal bearings").

    Parameters
    ----------
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1.
    geometry : BearingGeometry
        Bearing [m, Pa s].
    omega : float
        Journal angular speed [rad/s].

    Returns
    -------
    tuple of float
        ``(W_r, W_t)`` [N]: load component along the line of centres and
        perpendicular to it (both >= 0).
    """
    eps = _check_eps(eps)
    s = _load_scale(geometry, omega)
    one = 1.0 - eps * eps
    return s * eps * eps / one ** 2, s * math.pi * eps / (4.0 * one ** 1.5)


def ocvirk_load(eps: float, geometry: BearingGeometry, omega: float) -> float:
    """Steady load carried by the short bearing at eccentricity ratio ``eps``.

    .. math::

        W = \\frac{\\mu\\omega R L^3}{4c^2}\\,
            \\frac{\\varepsilon}{(1-\\varepsilon^2)^2}\\,
            \\sqrt{16\\varepsilon^2 + \\pi^2(1-\\varepsilon^2)}

    Parameters
    ----------
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1.
    geometry : BearingGeometry
        Bearing [m, Pa s].
    omega : float
        Journal angular speed [rad/s].

    Returns
    -------
    float
        Load magnitude [N].
    """
    wr, wt = ocvirk_load_components(eps, geometry, omega)
    return math.hypot(wr, wt)


def ocvirk_attitude_angle(eps: float) -> float:
    """Steady attitude angle of the short bearing.

    .. math::

        \\tan\\phi = \\frac{\\pi\\sqrt{1-\\varepsilon^2}}{4\\varepsilon}

    Parameters
    ----------
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1.

    Returns
    -------
    float
        Angle [rad] from the load direction to the line of centres, in the
        sense of rotation (pi/2 at eps = 0, -> 0 as eps -> 1).
    """
    eps = _check_eps(eps)
    return math.atan2(math.pi * math.sqrt(1.0 - eps * eps), 4.0 * eps)


def ocvirk_eccentricity(load: float, geometry: BearingGeometry, omega: float) -> float:
    """Invert :func:`ocvirk_load`: eccentricity ratio that carries ``load``.

    Parameters
    ----------
    load : float
        Load magnitude [N], >= 0.
    geometry : BearingGeometry
        Bearing [m, Pa s].
    omega : float
        Journal angular speed [rad/s], != 0.

    Returns
    -------
    float
        Eccentricity ratio [-] in [0, 1).
    """
    load = check_range("load_n", load, 0.0, None, unit="N")
    omega = check_range("omega", omega, unit="rad/s")
    if omega == 0.0:
        raise InputError("omega", omega, "!= 0 rad/s", "no steady state without rotation")
    if load == 0.0:
        return 0.0
    s = _load_scale(geometry, omega)
    # W(eps) is monotonic; bisect on u = -log(1 - eps) so that eps -> 1 is resolved.
    lo, hi = 0.0, 40.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        eps = -math.expm1(-mid)
        one = 1.0 - eps * eps
        w = s * eps / (4.0 * one * one) * math.sqrt(16.0 * eps * eps + math.pi ** 2 * one)
        if w < load:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-15 * max(1.0, hi):
            break
    return -math.expm1(-0.5 * (lo + hi))


def ocvirk_equilibrium(load: np.ndarray, geometry: BearingGeometry, omega: float) -> np.ndarray:
    """Steady journal-centre position under a constant load vector.

    Parameters
    ----------
    load : array_like, shape (2,)
        External load on the journal [N] in the housing frame.
    geometry : BearingGeometry
        Bearing [m, Pa s].
    omega : float
        Journal angular speed [rad/s], != 0 (counter-clockwise if > 0).

    Returns
    -------
    numpy.ndarray, shape (2,)
        Eccentricity vector [m]: magnitude ``eps c`` with ``eps`` from
        :func:`ocvirk_eccentricity`, direction the load direction rotated by
        the attitude angle in the sense of rotation.
    """
    f = np.asarray(load, dtype=float)
    w = math.hypot(f[0], f[1])
    eps = ocvirk_eccentricity(w, geometry, omega)
    if eps == 0.0:
        return np.zeros(2)
    ang = math.atan2(f[1], f[0]) + math.copysign(ocvirk_attitude_angle(eps), omega)
    return eps * geometry.clearance_m * np.array([math.cos(ang), math.sin(ang)])


def _sommerfeld_gamma(alpha: float, eps: float) -> float:
    """Sommerfeld variable: ``1 - eps cos(alpha) = (1 - eps^2) / (1 + eps cos(gamma))``."""
    beta = math.sqrt((1.0 + eps) / (1.0 - eps))
    return 2.0 * math.atan2(beta * math.sin(0.5 * alpha), math.cos(0.5 * alpha))


def _j_antiderivatives(gamma: float, eps: float) -> np.ndarray:
    """Antiderivatives (in the Sommerfeld variable) of the three pi-film integrands."""
    one = 1.0 - eps * eps
    j_cc = ((0.5 + eps * eps) * gamma + 0.25 * math.sin(2 * gamma) + 2 * eps * math.sin(gamma)) \
        / one ** 2.5
    j_sc = (0.5 * math.sin(gamma) ** 2 - eps * math.cos(gamma)) / one ** 2
    j_ss = (0.5 * gamma - 0.25 * math.sin(2 * gamma)) / one ** 1.5
    return np.array([j_cc, j_sc, j_ss])


def pi_film_integrals(eps: float, a: float, b: float) -> np.ndarray:
    """Booker-type film integrals over an arc of the film, analytically.

    .. math::

        J^{cc} = \\int_a^b\\frac{\\cos^2\\alpha\\,d\\alpha}{(1-\\varepsilon\\cos\\alpha)^3},\\quad
        J^{sc} = \\int_a^b\\frac{\\sin\\alpha\\cos\\alpha\\,d\\alpha}
                        {(1-\\varepsilon\\cos\\alpha)^3},\\quad
        J^{ss} = \\int_a^b\\frac{\\sin^2\\alpha\\,d\\alpha}{(1-\\varepsilon\\cos\\alpha)^3}

    evaluated with the Sommerfeld substitution, which turns each integrand
    into a trigonometric polynomial of degree 2 (Booker [2]_, Hamrock [3]_).

    Parameters
    ----------
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1.
    a, b : float
        Arc limits [rad] measured from the line of centres (minimum film at 0),
        ``a <= b <= a + 2 pi``.

    Returns
    -------
    numpy.ndarray, shape (3,)
        ``(J^cc, J^sc, J^ss)`` [-].
    """
    eps = _check_eps(eps)
    if not b >= a:
        raise InputError("b", b, f">= a = {a}")
    # shift a into [-pi, pi) and split at +pi where the Sommerfeld map wraps
    shift = math.floor((a + math.pi) / (2 * math.pi)) * 2 * math.pi
    a, b = a - shift, b - shift
    total = np.zeros(3)
    lo = a
    while lo < b:
        hi = min(b, math.pi)
        total += _j_antiderivatives(_sommerfeld_gamma(hi, eps), eps) \
            - _j_antiderivatives(_sommerfeld_gamma(lo, eps), eps)
        lo, b = -math.pi, b - 2 * math.pi
    return total


def short_bearing_force(e: np.ndarray, e_dot: np.ndarray, omega: float,
                        geometry: BearingGeometry) -> np.ndarray:
    """Film force on the journal of a short pi-film bearing, analytic.

    The pressure of Eq. (4) of [4]_ integrated over its positive region
    (Eq. (5), area element ``R d(theta) dz``) in closed form:

    .. math::

        \\mathbf F = -\\frac{\\mu R L^3}{c^3}
        \\begin{pmatrix} J^{cc} & J^{sc}\\\\ J^{sc} & J^{ss}\\end{pmatrix}\\mathbf v ,
        \\qquad \\mathbf v = \\dot{\\mathbf e} - \\tfrac{\\omega}{2}\\mathbf k\\times\\mathbf e

    with the matrix written in the frame of the line of centres and the
    integrals taken over the half circle ``|alpha - alpha_v| < pi/2`` centred
    on the direction ``alpha_v`` of ``v``.

    Parameters
    ----------
    e : array_like, shape (2,)
        Journal-centre displacement [m], ``|e| < c``.
    e_dot : array_like, shape (2,)
        Its time derivative [m/s].
    omega : float
        Journal angular speed [rad/s].
    geometry : BearingGeometry
        Bearing [m, Pa s].

    Returns
    -------
    numpy.ndarray, shape (2,)
        Hydrodynamic force on the journal [N], housing frame.
    """
    g = geometry
    e = np.asarray(e, dtype=float)
    e_dot = np.asarray(e_dot, dtype=float)
    eps = _check_eps(math.hypot(e[0], e[1]) / g.clearance_m)
    phi = math.atan2(e[1], e[0])
    v = e_dot - 0.5 * omega * np.array([-e[1], e[0]])
    if not np.any(v):
        return np.zeros(2)
    cp, sp = math.cos(phi), math.sin(phi)
    rot = np.array([[cp, -sp], [sp, cp]])           # line-of-centres frame -> housing frame
    v_loc = rot.T @ v
    alpha_v = math.atan2(v_loc[1], v_loc[0])
    j_cc, j_sc, j_ss = pi_film_integrals(eps, alpha_v - 0.5 * math.pi, alpha_v + 0.5 * math.pi)
    scale = g.viscosity_pa_s * g.radius_m * g.length_m ** 3 / g.clearance_m ** 3
    f_loc = -scale * np.array([[j_cc, j_sc], [j_sc, j_ss]]) @ v_loc
    return rot @ f_loc


def squeeze_load_factor(eps: float) -> float:
    """Dimensionless pure-squeeze load of the short pi-film journal bearing.

    For a journal approaching the wall along the line of centres with
    ``omega = 0``, the film force is ``W = (mu R L^3 / c^3) I(eps) de/dt`` with

    .. math::

        I(\\varepsilon) = J^{cc}\\Big|_{-\\pi/2}^{\\pi/2}
        = \\frac{(1 + 2\\varepsilon^2)\\,(\\pi/2 + \\arcsin\\varepsilon)
                 + 3\\varepsilon\\sqrt{1-\\varepsilon^2}}
                {(1-\\varepsilon^2)^{5/2}}

    (the full-film value is ``pi (1 + 2 eps^2) / (1 - eps^2)^{5/2}``,
    Hamrock [3]_ "squeeze film journal bearing").

    Parameters
    ----------
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1.

    Returns
    -------
    float
        ``I(eps)`` [-] (``pi / 2`` at eps = 0).
    """
    eps = _check_eps(eps)
    one = 1.0 - eps * eps
    return ((1.0 + 2.0 * eps * eps) * (0.5 * math.pi + math.asin(eps))
            + 3.0 * eps * math.sqrt(one)) / one ** 2.5


def squeeze_approach_speed(eps: float, load: float, geometry: BearingGeometry) -> float:
    """Pure-squeeze approach speed under a constant load, no rotation.

    .. math::

        \\dot e = \\frac{W c^3}{\\mu R L^3\\, I(\\varepsilon)}

    with :math:`I` from :func:`squeeze_load_factor`; the journal moves along
    the load line (towards the load) when ``e`` is on that line.

    Parameters
    ----------
    eps : float
        Eccentricity ratio [-], 0 <= eps < 1, measured along the load.
    load : float
        Load magnitude [N], >= 0.
    geometry : BearingGeometry
        Bearing [m, Pa s].

    Returns
    -------
    float
        Speed of the journal centre towards the load [m/s].
    """
    load = check_range("load_n", load, 0.0, None, unit="N")
    g = geometry
    return load * g.clearance_m ** 3 / (g.viscosity_pa_s * g.radius_m * g.length_m ** 3
                                        * squeeze_load_factor(eps))
