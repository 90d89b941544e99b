"""Chambers of the ideal (conjugate, zero-clearance) gear set.

Chamber j is bounded by the inner profile between the sealing points of
lobes j and j+1 and by the outer profile (lobe j+1 arc, root arc, lobe j arc).
Volumes, force projections and ports are computed on the ideal geometry: the
design tooth-tip clearance δ (tens of µm) changes a chamber area by well under
1 % and its rate of change not at all to first order; δ enters the model only
through the tooth-tip gaps (:mod:`.gaps`).  The outer-gear micro-displacement
moves the outer contour rigidly (``chamber_polygon(..., displacement=e)``, closed at
the minimum-gap lines); to first order that changes V_j by the force projections
of eqs. 24–25 times **e** (:mod:`gerotor_twin.model.volumes`).

Force projections and arms (eqs. 24–25 of [1])
----------------------------------------------
Uniform pressure p on the outer-gear contour of chamber j, from the sealing
point X_{j+1} to X_j, gives a force that depends only on the end points:

.. math::
    \\mathbf F_j = p_j L\\,(l_{y,j},\\; l_{x,j}),\\quad
    l_{y,j} = y_{j+1} - y_j,\\quad l_{x,j} = x_j - x_{j+1},

and a torque about O2 of p_j L (|X_j−O2|² − |X_{j+1}−O2|²)/2, which equals
p_j L (l_y b_y + l_x b_x) (eq. 25, with p_j for the printed p_i of eq. 24)
when the arms are those of the chord midpoint m: b_x = m_x, b_y = −m_y.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from .gerotor import GerotorGeometry
from .overlap import cyclic_next

__all__ = ["ideal", "contact_points", "chamber_polygon", "chamber_area", "polygon_area",
           "chamber_dA_dtheta_closed_form", "force_projections", "ChamberSample"]


def ideal(g: GerotorGeometry) -> GerotorGeometry:
    """The same gear set with zero tooth-tip clearance (conjugate profiles)."""
    return g if g.tip_clearance == 0 else replace(g, tip_clearance=0.0)


def _rot(theta, x, y):
    c, s = math.cos(theta), math.sin(theta)
    return c * x - s * y, s * x + c * y


def contact_points(g: GerotorGeometry, theta: float):
    """Sealing points of every lobe at shaft angle θ, fixed frame.

    Returns
    -------
    on_lobe : ndarray (N, 2)
        X_k = C_k + r (P − C_k)/|P − C_k|, the point of lobe k nearest the pitch point [m].
    on_inner : ndarray (N, 2)
        Γ(u_k) rotated by θ, the matching point of the inner profile [m]
        (coincides with ``on_lobe`` for δ = 0).
    """
    N, r = g.chambers, g.lobe_radius
    C = g.lobe_centres(theta)
    P = g.pitch_point
    d = P[None, :] - C
    X = C + r * d / np.linalg.norm(d, axis=1)[:, None]
    u = g.lobe_parameter(theta, np.arange(N))
    gx, gy = g.inner_profile(u)
    ix, iy = _rot(theta, gx, gy)
    return X, np.column_stack([ix, iy])


def _unwrap_to(a, ref):
    """Angle a shifted by 2π multiples into (ref − π, ref + π]."""
    return ref + (a - ref + math.pi) % (2 * math.pi) - math.pi


def _seals(gi: GerotorGeometry, theta: float, j: int, displacement):
    """Inner-profile parameters of the two seals of chamber j, their points on the inner profile
    and on the lobes (fixed frame) [rad, m, m]: the sealing points for the centred gear, the
    minimum-gap points (:func:`.gaps.exact_gaps`, negative gap = overlap) for a displaced one."""
    N = gi.chambers
    jn = (j + 1) % N
    if displacement[0] == 0.0 and displacement[1] == 0.0:
        X, _ = contact_points(gi, theta)
        u0 = float(gi.lobe_parameter(theta, j))
        return (u0, u0 + 2 * math.pi / N), (X[j], X[jn]), (X[j], X[jn])
    from .gaps import exact_gaps
    gs = exact_gaps(gi, theta, displacement, with_le=False)
    lobe = gs.point + gs.h[:, None] * gs.normal      # the lobe circle's point nearest the inner gear
    u0 = float(gs.u[j])
    u1 = u0 + (float(gs.u[jn]) - u0) % (2 * math.pi)
    return (u0, u1), (gs.point[j], gs.point[jn]), (lobe[j], lobe[jn])


def chamber_polygon(g: GerotorGeometry, theta: float, j: int, n_inner: int = 400,
                    n_arc: int = 80, displacement=(0.0, 0.0)) -> np.ndarray:
    """Closed polygon (K, 2) [m] of chamber j at shaft angle θ (ideal geometry).

    Order: inner profile from lobe j to lobe j+1 (CCW about O1), then the
    outer profile back (lobe j+1 arc, root arc, lobe j arc): the polygon is
    clockwise.  ``displacement`` [m] moves the outer gear (lobes and root circle)
    rigidly; the chamber then ends at the minimum-gap lines of its two lobes
    (the seal segment from the inner profile to the lobe, of length |gap|).
    """
    gi = ideal(g)
    N, R, r, Re = gi.chambers, gi.lobe_centre_radius, gi.lobe_radius, gi.outer_root_radius
    jn = (j + 1) % N
    (u0, u1), (I0, I1), (L0, L1) = _seals(gi, theta, j, displacement)
    X = {j: L0, jn: L1}
    C = gi.lobe_centres(theta, displacement)
    O2 = gi.outer_centre + np.asarray(displacement, float)
    # inner profile between the two seals
    u = np.linspace(u0, u1, n_inner)
    gx, gy = gi.inner_profile(u)
    ix, iy = _rot(theta, gx, gy)
    inner = np.column_stack([ix, iy])
    inner[0], inner[-1] = I0, I1               # exact seal points
    if not _same_point(L1, I1):
        inner = np.vstack([inner, L1])         # seal segment to the displaced lobe
    # lobe/root junctions: circle (C_k, r) ∩ circle (O2, Re)
    alpha = math.acos((Re * Re + R * R - r * r) / (2 * Re * R))
    phi = float(gi.outer_angle(theta))
    a_j = phi + 2 * math.pi * j / N
    a_n = a_j + 2 * math.pi / N

    def lobe_arc(k, a_k, X_k, a_junction):
        Ck = C[k]
        J = O2 + Re * np.array([math.cos(a_junction), math.sin(a_junction)])
        ref = a_k + math.pi                     # inward direction at the lobe centre
        t0 = _unwrap_to(math.atan2(X_k[1] - Ck[1], X_k[0] - Ck[0]), ref)
        t1 = _unwrap_to(math.atan2(J[1] - Ck[1], J[0] - Ck[0]), ref)
        t = np.linspace(t0, t1, n_arc)
        return np.column_stack([Ck[0] + r * np.cos(t), Ck[1] + r * np.sin(t)])

    arc_next = lobe_arc(jn, a_n, X[jn], a_n - alpha)          # from X_{j+1} to its CW junction
    tr = np.linspace(a_n - alpha, a_j + alpha, n_arc)
    root = np.column_stack([O2[0] + Re * np.cos(tr), O2[1] + Re * np.sin(tr)])
    arc_this = lobe_arc(j, a_j, X[j], a_j + alpha)[::-1]      # from its CCW junction to X_j
    poly = np.vstack([inner, arc_next[1:], root[1:-1], arc_this[:-1]])
    return poly if _same_point(L0, I0) else np.vstack([poly, L0])


def _same_point(a, b) -> bool:
    """Whether two points (2,) [m] coincide within 1e-15 m in each coordinate (NaN: no); what
    ``np.allclose(a, b, rtol=0, atol=1e-15)`` tests, without its ≈ 50 µs of set-up (two calls per chamber outline,
    4096 outlines per geometry table)."""
    return abs(float(a[0]) - float(b[0])) <= 1e-15 and abs(float(a[1]) - float(b[1])) <= 1e-15


def polygon_area(poly: np.ndarray) -> float:
    """Signed shoelace area of a closed polygon (K, 2) [m²] (CCW positive)."""
    x, y = poly[:, 0], poly[:, 1]
    return 0.5 * float(np.dot(x, cyclic_next(y)) - np.dot(y, cyclic_next(x)))


def chamber_area(g: GerotorGeometry, theta: float, j: int = 0, **kw) -> float:
    """Area of chamber j at shaft angle θ [m²] (polygon, ideal geometry)."""
    return abs(polygon_area(chamber_polygon(g, theta, j, **kw)))


def chamber_dA_dtheta_closed_form(g: GerotorGeometry, theta, j: int = 0):
    """dA_j/dθ from the pitch-point swept-area rule [m²/rad].

    .. math::
        \\frac{dA_j}{d\\theta} = \\frac{|PX_{j+1}|^2 - |PX_j|^2}{2N},\\qquad
        |PX_k| = \\sqrt{R^2 + N^2e^2 + 2RNe\\cos\\psi_k} - r,

    ψ_k = φ + 2πk/N the angle of lobe k about O2.  Exact for conjugate
    profiles (the rates ω₁ O1P = ω₂ O2P cancel the cross terms).
    """
    gi = ideal(g)
    N, R, e, r = gi.chambers, gi.lobe_centre_radius, gi.eccentricity, gi.lobe_radius
    phi = np.asarray(gi.outer_angle(theta))
    psi_j = phi + 2 * math.pi * j / N
    psi_n = psi_j + 2 * math.pi / N
    s_j = np.sqrt(R * R + N * N * e * e + 2 * R * N * e * np.cos(psi_j)) - r
    s_n = np.sqrt(R * R + N * N * e * e + 2 * R * N * e * np.cos(psi_n)) - r
    return (s_n ** 2 - s_j ** 2) / (2 * N)


@dataclass(frozen=True)
class ChamberSample:
    """Force projections and arms of chamber j at one angle (eqs. 24–25 of [1]), [m]."""
    lx: float
    ly: float
    bx: float
    by: float

    @property
    def torque_per_pressure_width(self) -> float:
        """Torque about O2 per unit pressure and width, l_y b_y + l_x b_x [m²]."""
        return self.ly * self.by + self.lx * self.bx


def force_projections(g: GerotorGeometry, theta: float, j: int = 0) -> ChamberSample:
    """l_x, l_y, b_x, b_y of chamber j at shaft angle θ (ideal geometry) [m]."""
    gi = ideal(g)
    N = gi.chambers
    X, _ = contact_points(gi, theta)
    a, b = X[j], X[(j + 1) % N]
    O2 = gi.outer_centre
    m = 0.5 * (a + b) - O2
    return ChamberSample(lx=float(a[0] - b[0]), ly=float(b[1] - a[1]), bx=float(m[0]), by=float(-m[1]))
