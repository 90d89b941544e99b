"""Lateral-gap geometry (fig. 6 of [1]): the faces of the gears against the housing.

Three leakage paths cross the lateral gaps (axial clearance h_lat on each of
the two faces); all three are independent of the outer-gear micro-motion, as
in [1] (sec. 4):

* between neighbouring chambers across the land of an outer lobe: an annular
  sector about O2 of angular extent ``chi_lobe`` between radii R − r and Re
  (circumferential Poiseuille flow, sec. 3.2);
* suction ↔ delivery across the outer-gear ring face: two sectors about O2,
  ``chi1`` (tip-to-tip side) and ``chi2`` (deep-mesh side), between Re and G
  (sec. 3.3);
* delivery → drain across the inner-gear face: a sector about O1 of angular
  extent ``chi3`` (the delivery kidney) from the inner root radius down to
  the shaft hole Ri (radial Poiseuille flow, sec. 3.4).

The Couette terms of the lobe lands cancel exactly in every chamber's balance
(each chamber receives from its leading land what it gives to its trailing
one when the lands are equal), so they are not carried.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

from .gerotor import GerotorGeometry
from .ports import Port

__all__ = ["LateralGeometry", "lateral_geometry"]


@dataclass(frozen=True)
class LateralGeometry:
    """Angular extents [rad] and radii [m] of the lateral leakage paths."""
    chi_lobe: float
    lobe_r_in: float
    lobe_r_out: float
    chi1: float
    chi2: float
    ring_r_in: float
    ring_r_out: float
    chi3: float
    drain_r_in: float
    drain_r_out: float


def lateral_geometry(g: GerotorGeometry, suction: Port, delivery: Port) -> LateralGeometry:
    """Lateral-gap geometry of a gear set with the given ports."""
    R, r, Re = g.lobe_centre_radius, g.lobe_radius, g.outer_root_radius
    alpha = math.acos((Re * Re + R * R - r * r) / (2 * Re * R))   # lobe/root junction half-angle about O2
    chi1 = (delivery.start + 2 * math.pi - suction.end) % (2 * math.pi)   # land around +x
    chi2 = (suction.start - delivery.end) % (2 * math.pi)                 # land around −x
    return LateralGeometry(
        chi_lobe=2 * alpha, lobe_r_in=R - r, lobe_r_out=Re,
        chi1=chi1, chi2=chi2, ring_r_in=Re, ring_r_out=g.outer_radius,
        chi3=delivery.end - delivery.start, drain_r_in=g.inner_hole_radius,
        drain_r_out=g.inner_root_radius,
    )
