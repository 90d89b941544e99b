"""Tooth-tip gaps of the displaced gear set (sec. 3.1 and 3.7 of [1]) — exact geometry.

For shaft angle θ, outer-gear centre displacement **e** = (e_x, e_y) from its
nominal position and a small extra rotation γ of the inner gear, lobe k's
centre seen from the inner gear is

.. math:: Q_k = \\mathrm{Rot}(-(θ+γ))\\,(C_k(θ) + \\mathbf e).

Its signed distance d_k to the epitrochoid T (positive outside) gives the
minimum gap height between lobe k and the inner profile (offset ρ = r + δ):

.. math:: h_k = δ + d_k.

The equivalent length le_k is the distance between the two points of the
inner profile where the gap height is h* = h_k (1 + dh) (sec. 3.1 of [1]);
the relative speed of the inner surface with respect to the outer one at the
minimum gap, along the gap from chamber k−1 to chamber k, is
v_r = (ω/N) (X_k − P)·n_k (rolling about the pitch point P).

These functions are the truth; :mod:`.tables` expands them to second order in
(e_x, e_y, γ) for the hot loop, and the tests compare the two.

Choice of dh: for a gap between two cylinders, h(s) ≈ h₀ + s²/(2R_rel), the
exact Poiseuille conductance is that of a slot of length (3π/8)√(2R_rel h₀),
while the h* rule gives 2√(2R_rel h₀ dh); they agree for dh = (3π/16)² ≈ 0.347,
our default (config ``leakage.tip_dh``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from .gerotor import GerotorGeometry

__all__ = ["GapState", "exact_gaps", "DH_CYLINDER"]

DH_CYLINDER = (3 * math.pi / 16) ** 2  #: dh that makes le exact for cylinder–cylinder gaps [-]


@dataclass(frozen=True)
class GapState:
    """Tooth-tip gaps of all N lobes at one configuration (arrays of shape (N,))."""
    h: np.ndarray          #: minimum gap height [m] (negative = overlap)
    u: np.ndarray          #: trochoid parameter of the closest point [rad]
    point: np.ndarray      #: (N, 2) minimum-gap point on the inner profile, fixed frame [m]
    normal: np.ndarray     #: (N, 2) unit normal from the inner gear towards the lobe centre, fixed frame
    le: np.ndarray         #: equivalent length [m] (0 where h <= 0)
    vr_per_omega: np.ndarray  #: v_r / ω_shaft [m/rad]


def _closest_parameter(g: GerotorGeometry, qx, qy, u0, iters=8):
    u = np.array(u0, dtype=float)
    for _ in range(iters):
        tx, ty = g.trochoid(u)
        dx, dy = g.trochoid_d1(u)
        ddx, ddy = g.trochoid_d2(u)
        rx, ry = tx - qx, ty - qy
        f = rx * dx + ry * dy
        fp = dx * dx + dy * dy + rx * ddx + ry * ddy
        u = u - f / fp
    return u


def _equivalent_length(g, qx, qy, u_star, h_min, dh, r):
    """Distance between the profile points where the gap is h*(1+dh) (exact root finding)."""
    le = np.zeros_like(h_min)
    ok = h_min > 0
    if not np.any(ok):
        return le
    target = h_min * (1.0 + dh)

    def gap_at(u, k):
        x, y = g.inner_profile(u)
        return np.hypot(x - qx[k], y - qy[k]) - r

    pts = []
    for side in (-1.0, 1.0):
        # bracket: walk out until the gap exceeds the target, then bisect
        k = np.where(ok)[0]
        lo = u_star[k].copy()
        step = np.full(k.shape, 1e-4)
        hi = lo + side * step
        for _ in range(60):
            need = gap_at(hi, k) < target[k]
            if not np.any(need):
                break
            lo = np.where(need, hi, lo)
            step = np.where(need, step * 2.0, step)
            hi = np.where(need, hi + side * step, hi)
        for _ in range(60):
            mid = 0.5 * (lo + hi)
            below = gap_at(mid, k) < target[k]
            lo = np.where(below, mid, lo)
            hi = np.where(below, hi, mid)
        pts.append(np.column_stack(g.inner_profile(0.5 * (lo + hi))))
    le[ok] = np.linalg.norm(pts[1] - pts[0], axis=1)
    return le


def exact_gaps(g: GerotorGeometry, theta: float, displacement=(0.0, 0.0), inner_rotation: float = 0.0,
               dh: float = DH_CYLINDER, with_le: bool = True) -> GapState:
    """Exact tooth-tip gaps of every lobe (see module docstring).

    Parameters
    ----------
    g : GerotorGeometry
        Gear set (with its tooth-tip clearance δ).
    theta : float
        Shaft (inner-gear) angle [rad].
    displacement : (float, float)
        Outer-gear centre displacement from nominal, fixed frame [m].
    inner_rotation : float
        Extra CCW rotation γ of the inner gear [rad].
    dh : float
        Relative gap increase defining the equivalent length [-].
    with_le : bool
        Compute the equivalent lengths (slower).
    """
    N, r = g.chambers, g.lobe_radius
    C = g.lobe_centres(theta, displacement)
    a = -(theta + inner_rotation)
    ca, sa = math.cos(a), math.sin(a)
    qx = ca * C[:, 0] - sa * C[:, 1]
    qy = sa * C[:, 0] + ca * C[:, 1]
    u = _closest_parameter(g, qx, qy, g.lobe_parameter(theta, np.arange(N)))
    tx, ty = g.trochoid(u)
    nx, ny = g.trochoid_normal(u)
    d = (qx - tx) * nx + (qy - ty) * ny
    h = g.tip_clearance + d
    # back to the fixed frame
    b = theta + inner_rotation
    cb, sb = math.cos(b), math.sin(b)
    px, py = g.inner_profile(u)
    point = np.column_stack([cb * px - sb * py, sb * px + cb * py])
    normal = np.column_stack([cb * nx - sb * ny, sb * nx + cb * ny])
    P = g.pitch_point
    vr = np.einsum("ij,ij->i", point - P[None, :], normal) / N
    le = _equivalent_length(g, qx, qy, u, h, dh, r) if with_le else np.full(N, np.nan)
    return GapState(h=h, u=u, point=point, normal=normal, le=le, vr_per_omega=vr)
