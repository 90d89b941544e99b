"""Gerotor profiles: outer gear with N circular-arc lobes, conjugate inner gear.

Frames and conventions (used throughout the package)
----------------------------------------------------
* Fixed (housing) frame: origin at the inner-gear centre O1; the nominal
  outer-gear centre O2 lies at (e, 0).  Angles are counter-clockwise (CCW).
* Both gears turn CCW.  Shaft (inner gear) angle θ; the outer gear turns at
  (N−1)/N of the shaft speed, so its angle is φ = θ (N−1)/N.
* Lobe k of the outer gear (k = 0 … N−1) has its arc centre at
  C_k = O2 + R (cos(φ + 2πk/N), sin(φ + 2πk/N)).
* Chamber j lies between lobe j and lobe j+1 (indices mod N); the tooth-tip
  gap k sits at lobe k, between chamber k−1 and chamber k.
* The pitch point P = (−(N−1) e, 0) is the instantaneous centre of the
  relative motion; deep mesh (minimum chamber volume) is on the −x side,
  tip-to-tip (maximum volume) on the +x side.  Chambers shrink on the upper
  half (delivery, y > 0) and grow on the lower half (suction, y < 0).

The inner gear is the envelope of the lobes: in the inner-gear frame the lobe
centres run on the epitrochoid

.. math::
    T(u) = R\\,(\\cos u, \\sin u) + e\\,(\\cos N u, \\sin N u),

and the inner profile is its inward offset by ρ = r + δ, where δ is the
design tooth-tip clearance (an equidistant profile modification).  At the
nominal centre distance every lobe centre lies on T, so every tooth-tip gap
is exactly δ before the inner gear is turned into contact (sec. 3.7 of [1]).

References
----------
.. [1] The paper, ``../shared/paper/gerotor-micromotion-paper.md``.
.. [2] J. Colbourne, "The geometry of trochoid envelopes and their
   application in rotary pumps", Mech. Mach. Theory 9 (1974) 421–435.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError

__all__ = ["GerotorGeometry"]


@dataclass(frozen=True)
class GerotorGeometry:
    """Design parameters of a gerotor gear set (all lengths in [m]).

    Parameters
    ----------
    chambers : int
        N, number of outer-gear lobes (= chambers); the inner gear has N−1 teeth [-].
    eccentricity : float
        e, nominal centre distance O1O2 [m].
    lobe_centre_radius : float
        R, radius of the lobe-arc centres about O2 [m].
    lobe_radius : float
        r, radius of the lobe arcs [m].
    outer_root_radius : float
        Re, radius of the outer-gear root circle between lobes [m].
    outer_radius : float
        G, outside radius of the outer gear (journal radius) [m].
    inner_hole_radius : float
        Ri, radius of the inner gear's shaft hole (drain side) [m].
    width : float
        b = L, axial width of both gears [m].
    tip_clearance : float
        δ, equidistant tooth-tip clearance of the inner profile [m].
    """

    chambers: int
    eccentricity: float
    lobe_centre_radius: float
    lobe_radius: float
    outer_root_radius: float
    outer_radius: float
    inner_hole_radius: float
    width: float
    tip_clearance: float = 0.0

    # ------------------------------------------------------------------ checks
    def __post_init__(self):
        N, e, R, r = self.chambers, self.eccentricity, self.lobe_centre_radius, self.lobe_radius
        if int(N) != N or N < 4 or N > 15:
            raise InputError("gears.chambers", N, "integer in [4, 15]")
        for name in ("eccentricity", "lobe_centre_radius", "lobe_radius", "outer_root_radius",
                     "outer_radius", "inner_hole_radius", "width"):
            v = getattr(self, name)
            if not (isinstance(v, (int, float)) and math.isfinite(v) and v > 0):
                raise InputError(f"gears.{name}_m", v, "(0, inf) m")
        if not (math.isfinite(self.tip_clearance) and 0 <= self.tip_clearance < 0.5e-3):
            raise InputError("clearances.tooth_tip_m", self.tip_clearance, "[0, 0.0005) m")
        if R <= N * e:
            raise InputError("gears.lobe_centre_radius_m", R, f"({N * e:g}, inf) m",
                             "R must exceed N·e, otherwise the trochoid loops (undercut)")
        if r >= R * math.sin(math.pi / N):
            raise InputError("gears.lobe_radius_m", r, f"(0, {R * math.sin(math.pi / N):g}) m",
                             "neighbouring lobes would intersect")
        rho_min = self.min_convex_curvature_radius()
        rho = r + self.tip_clearance
        if rho >= rho_min:
            raise InputError("gears.lobe_radius_m", r, f"(0, {rho_min - self.tip_clearance:g}) m",
                             f"undercut: lobe radius + tip clearance {rho:g} m exceeds the "
                             f"trochoid's minimum convex radius of curvature {rho_min:g} m")
        tip_from_o2 = R - r + 2 * e
        if not (tip_from_o2 < self.outer_root_radius <= R + 0.5 * r):
            raise InputError("gears.outer_root_radius_m", self.outer_root_radius,
                             f"({tip_from_o2:g}, {R + 0.5 * r:g}] m",
                             "the inner tooth tips must clear the outer root circle")
        if self.outer_radius <= self.outer_root_radius + 1e-3:
            raise InputError("gears.outer_radius_m", self.outer_radius,
                             f"({self.outer_root_radius + 1e-3:g}, inf) m", "outer gear ring too thin")
        if self.inner_hole_radius >= self.inner_root_radius - 1e-3:
            raise InputError("gears.inner_hole_radius_m", self.inner_hole_radius,
                             f"(0, {self.inner_root_radius - 1e-3:g}) m", "inner gear ring too thin")

    # -------------------------------------------------------------- derived
    @property
    def offset(self) -> float:
        """ρ = r + δ, offset of the inner profile from the trochoid [m]."""
        return self.lobe_radius + self.tip_clearance

    @property
    def inner_tip_radius(self) -> float:
        """Inner-gear tip radius about O1 [m]."""
        return self.lobe_centre_radius + self.eccentricity - self.offset

    @property
    def inner_root_radius(self) -> float:
        """Inner-gear root radius about O1 [m] (r_i_inf in [1])."""
        return self.lobe_centre_radius - self.eccentricity - self.offset

    @property
    def pitch_point(self) -> np.ndarray:
        """Pitch point P in the fixed frame [m]."""
        return np.array([-(self.chambers - 1) * self.eccentricity, 0.0])

    @property
    def outer_centre(self) -> np.ndarray:
        """Nominal outer-gear centre O2 in the fixed frame [m]."""
        return np.array([self.eccentricity, 0.0])

    @property
    def chamber_period(self) -> float:
        """Shaft-angle period of one chamber's geometry, 2πN/(N−1) [rad]."""
        N = self.chambers
        return 2 * math.pi * N / (N - 1)

    @property
    def chamber_shift(self) -> float:
        """Shaft-angle lead of chamber j+1's geometry over chamber j, 2π/(N−1) [rad]."""
        return 2 * math.pi / (self.chambers - 1)

    # ------------------------------------------------------------ trochoid
    def trochoid(self, u):
        """Epitrochoid T(u) in the inner-gear frame, returns (x, y) [m]."""
        R, e, N = self.lobe_centre_radius, self.eccentricity, self.chambers
        u = np.asarray(u, dtype=float)
        return R * np.cos(u) + e * np.cos(N * u), R * np.sin(u) + e * np.sin(N * u)

    def trochoid_d1(self, u):
        """dT/du [m/rad]."""
        R, e, N = self.lobe_centre_radius, self.eccentricity, self.chambers
        u = np.asarray(u, dtype=float)
        return -R * np.sin(u) - N * e * np.sin(N * u), R * np.cos(u) + N * e * np.cos(N * u)

    def trochoid_d2(self, u):
        """d²T/du² [m/rad²]."""
        R, e, N = self.lobe_centre_radius, self.eccentricity, self.chambers
        u = np.asarray(u, dtype=float)
        return -R * np.cos(u) - N * N * e * np.cos(N * u), -R * np.sin(u) - N * N * e * np.sin(N * u)

    def trochoid_curvature(self, u):
        """Signed curvature of T (positive where convex outward) [1/m].

        .. math:: κ = \\frac{R^2 + N^3 e^2 + R N e (N+1) \\cos((N-1)u)}{|T'|^3}
        """
        R, e, N = self.lobe_centre_radius, self.eccentricity, self.chambers
        c = np.cos((N - 1) * np.asarray(u, dtype=float))
        speed2 = R * R + N * N * e * e + 2 * R * N * e * c
        return (R * R + N ** 3 * e * e + R * N * e * (N + 1) * c) / speed2 ** 1.5

    def min_convex_curvature_radius(self) -> float:
        """Smallest radius of curvature of T where it is convex [m] (undercut limit)."""
        N = self.chambers
        u = np.linspace(0.0, 2 * math.pi / (N - 1), 4001)
        k = self.trochoid_curvature(u)
        kmax = float(np.max(k))
        return math.inf if kmax <= 0 else 1.0 / kmax

    def trochoid_normal(self, u):
        """Outward unit normal of T, (nx, ny) [-]."""
        dx, dy = self.trochoid_d1(u)
        s = np.hypot(dx, dy)
        return dy / s, -dx / s

    def inner_profile(self, u):
        """Inner-gear profile Γ(u) = T(u) − ρ n(u), inner-gear frame (x, y) [m]."""
        x, y = self.trochoid(u)
        nx, ny = self.trochoid_normal(u)
        rho = self.offset
        return x - rho * nx, y - rho * ny

    # ------------------------------------------------------ fixed frame
    def outer_angle(self, theta):
        """Outer-gear angle φ = θ (N−1)/N [rad] for shaft angle θ [rad]."""
        return np.asarray(theta, dtype=float) * (self.chambers - 1) / self.chambers

    def lobe_centres(self, theta, displacement=(0.0, 0.0)):
        """Lobe-arc centres C_k in the fixed frame, shape (N, 2) [m]."""
        N, R = self.chambers, self.lobe_centre_radius
        a = float(self.outer_angle(theta)) + 2 * math.pi * np.arange(N) / N
        ox = self.eccentricity + displacement[0]
        oy = displacement[1]
        return np.column_stack([ox + R * np.cos(a), oy + R * np.sin(a)])

    def lobe_parameter(self, theta, k):
        """Trochoid parameter u_k = (2πk − θ)/N of lobe k's centre (nominal) [rad]."""
        return (2 * math.pi * np.asarray(k) - np.asarray(theta, dtype=float)) / self.chambers

    def displacement_closed_form(self) -> float:
        """Displacement per shaft revolution from the pitch-point closed form [m³/rev].

        The chamber between sealing points A and B changes area at
        dA/dθ = (|PB|² − |PA|²)/(2N) for the chamber from A to B (swept-area rule, pitch point P,
        since ω₁·O1P = ω₂·O2P).  With |PX_k| = s_k − r,
        s_k² = R² + N²e² + 2RNe cos ψ_k, integrating over the half period and
        summing the N chambers gives

        .. math::
            q = \\frac{b}{2}\\left[8RNe\\sin\\frac{\\pi}{N}
                 - 2r\\,(S_0 - S_\\pi)\\right],

        with S₀ = 4(R+Ne) E(π/(2N) | m),
        S_π = 2(R+Ne) [E(π/2 + π/(2N) | m) − E(π/2 − π/(2N) | m)],
        m = 4RNe/(R+Ne)², E the incomplete elliptic integral of the second kind.
        Valid for the ideal (δ = 0) conjugate profiles.
        """
        from scipy.special import ellipeinc

        R, e, N, r, b = (self.lobe_centre_radius, self.eccentricity, self.chambers,
                         self.lobe_radius, self.width)
        m = 4 * R * N * e / (R + N * e) ** 2
        q4 = math.pi / (2 * N)
        s0 = 4 * (R + N * e) * ellipeinc(q4, m)
        spi = 2 * (R + N * e) * (ellipeinc(math.pi / 2 + q4, m) - ellipeinc(math.pi / 2 - q4, m))
        return 0.5 * b * (8 * R * N * e * math.sin(math.pi / N) - 2 * r * (s0 - spi))
