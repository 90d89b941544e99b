"""Suction and delivery ports of the valve plate.

A port is a kidney covering the whole radial band of the chambers between two
rays from the inner-gear centre O1 (angles in the fixed frame, CCW from the
+x axis, i.e. from O1 towards the nominal outer-gear centre).  The open area
between chamber j and a port is the part of the chamber polygon inside the
port's angular range; a port edge passing over a chamber opens or closes it
progressively.  The defaults leave a sealing land a little wider than a
chamber at the two dead centres, so no chamber ever sees both ports.

Closing edge
------------
``closing_edge: ray`` (the form without the key; ``config/pump.yaml`` sets ``chamber``) ends the port
at the ray ``end``.  A chamber near a dead centre is a lens pointed at both seals, so its area past a
ray falls to 0 like a cusp: 0.2° before the suction dead centre the default pump's chamber sees
3.8e-11 m² of port, and it is sealed while still growing, under-filled (docs/fluid.md).  Valve plates
are therefore cut with the closing edge following the outline of the chamber at the dead centre it
moves into (e.g. [1, 2]): ``closing_edge: chamber`` adds to the kidney the part of the wedge from
``end`` to that chamber's centroid angle which the chamber at the dead centre does not cover.  The
open area then falls linearly to 0 exactly at the dead centre.  After it only the inner tooth flank,
which turns faster than the outer gear, uncovers a sliver of the cut (≤ 2.2e-8 m² over the first 2°,
0.3 % of the area 1° before the dead centre, default pump; geometry, not round-off: it stays with
polygons 4× finer).  The extension lies inside the outer root circle (a chamber never reaches past
it), so the lateral lands of :mod:`.lateral` keep their angles.  The area is the exact polygon
intersection of :mod:`.overlap`.

Only the suction kidney takes it.  At the minimum-volume dead centre the chamber is a wide lens
(2 × 2.6e-5 m² in the default pump) whose trailing part sweeps back over the cut as it grows
again (6.6e-6 m² open 5° after it), so a delivery kidney cut that way would not close.

References
----------
[1] Manring, N. D., Fales, R. C., *Hydraulic Control Systems*, 2nd ed., Wiley, 2019 (port-plate
    timing of positive-displacement pumps).
[2] Rundo, M., "Models for flow rate simulation in gear pumps: a review", Energies 10(9), 1261, 2017
    (port timing and relief grooves of gerotor port plates).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .chambers import chamber_dA_dtheta_closed_form, chamber_polygon, ideal, polygon_area
from .overlap import intersection_area

__all__ = ["Port", "CLOSING_EDGES", "clip_half_plane", "open_area", "closing_cut", "dead_centres"]

CLOSING_EDGES = ("ray", "chamber")


@dataclass(frozen=True)
class Port:
    """Angular extent of a port about O1.

    Parameters
    ----------
    name : str
        ``"suction"`` or ``"delivery"``.
    start : float
        Start angle [rad] (CCW).
    end : float
        End angle [rad], ``start < end``, span < π.
    closing_edge : str
        ``"ray"`` (the edge at ``end`` is the ray) or ``"chamber"`` (it follows the chamber outline at
        the next dead centre; see the module docstring).
    """
    name: str
    start: float
    end: float
    closing_edge: str = "ray"

    def __post_init__(self):
        if self.closing_edge not in CLOSING_EDGES:
            raise InputError(f"ports.{self.name}.closing_edge", self.closing_edge, " | ".join(CLOSING_EDGES))
        if self.closing_edge == "chamber" and self.name != "suction":
            raise InputError(f"ports.{self.name}.closing_edge", self.closing_edge, "ray",
                             "only the suction kidney can follow a chamber (see geometry/ports.py)")
        span = self.end - self.start
        if not (0 < span < math.pi):
            raise InputError(f"ports.{self.name}.end_deg", math.degrees(self.end),
                             f"({math.degrees(self.start):g}, {math.degrees(self.start + math.pi):g}) deg",
                             "a port spans more than 0 and less than 180 degrees")


def clip_half_plane(poly: np.ndarray, normal: np.ndarray) -> np.ndarray:
    """Sutherland–Hodgman clip of a polygon to the half-plane ``normal · x >= 0``.

    Works for a non-convex subject polygon (the area of the result is exact;
    degenerate zero-width bridges may remain).
    """
    if len(poly) == 0:
        return poly
    d = poly @ normal
    nxt = np.roll(poly, -1, axis=0)
    dn = np.roll(d, -1)
    keep = d >= 0
    cross = keep != (dn >= 0)
    t = np.where(cross, d / np.where(cross, d - dn, 1.0), 0.0)
    inter = poly + t[:, None] * (nxt - poly)
    pts = np.stack([poly, inter], axis=1).reshape(-1, 2)     # per edge: its start if kept, then the crossing
    mask = np.stack([keep, cross], axis=1).reshape(-1)
    return pts[mask] if mask.any() else np.zeros((0, 2))


def _wedge_area(poly: np.ndarray, a0: float, a1: float) -> float:
    c = _wedge_polygon(poly, a0, a1)                 # CCW of the ray at a0, CW of the ray at a1
    return abs(polygon_area(c)) if len(c) >= 3 else 0.0


def dead_centres(g) -> tuple[float, float]:
    """Shaft angles [rad] in [0, 2πN/(N−1)) where chamber 0 has its maximum and its minimum volume:
    the zeros of the closed-form dA/dθ (:func:`.chambers.chamber_dA_dtheta_closed_form`)."""
    from scipy.optimize import brentq
    period = g.chamber_period
    th = np.linspace(0.0, period, 721)
    rate = chamber_dA_dtheta_closed_form(g, th, 0)
    found = {}
    for i in np.nonzero(np.sign(rate[:-1]) != np.sign(rate[1:]))[0]:
        root = brentq(lambda t: float(chamber_dA_dtheta_closed_form(g, t, 0)), th[i], th[i + 1], xtol=1e-14)
        found["max" if rate[i] > 0 else "min"] = root % period
    return found["max"], found["min"]


def _angle_of(poly: np.ndarray) -> float:
    """Angle [rad] about O1 of a polygon's area centroid, in [0, 2π)."""
    x, y = poly[:, 0], poly[:, 1]
    xn, yn = np.roll(x, -1), np.roll(y, -1)
    c = x * yn - xn * y
    sign = math.copysign(1.0, float(np.sum(c)))          # either orientation
    return math.atan2(sign * float(np.sum((y + yn) * c)), sign * float(np.sum((x + xn) * c))) % (2 * math.pi)


def closing_cut(g, port: Port) -> tuple[float, np.ndarray | None]:
    """The kidney's far angle [rad] and the cut polygon of ``closing_edge: chamber``.

    Returns ``(port.end, None)`` for a ray edge.  For a chamber edge: the centroid angle a_c of the
    chamber at the first dead centre after ``end`` and the part of that chamber inside the wedge
    (end, a_c) [m]; the port is the wedge (start, a_c) minus the cut.
    """
    if port.closing_edge == "ray":
        return port.end, None
    gi = ideal(g)
    best = None
    for theta in dead_centres(gi):
        poly = chamber_polygon(gi, theta, 0)
        a_c = _angle_of(poly)
        ahead = (a_c - port.end) % (2 * math.pi)
        if best is None or ahead < best[0]:
            best = (ahead, poly)
    ahead, poly = best
    if not 0.0 < ahead < math.pi - (port.end - port.start):
        raise InputError(f"ports.{port.name}.end_deg", math.degrees(port.end),
                         f"before the dead-centre chamber's centroid at {math.degrees(port.end + ahead):.2f} deg",
                         "closing_edge: chamber needs the ray at end before the chamber at the dead centre")
    far = port.end + ahead
    cut = _wedge_polygon(poly, port.end, far)
    return far, cut


def _wedge_polygon(poly: np.ndarray, a0: float, a1: float) -> np.ndarray:
    left = np.array([-math.sin(a0), math.cos(a0)])
    right = np.array([math.sin(a1), -math.cos(a1)])
    return clip_half_plane(clip_half_plane(poly, left), right)


def open_area(g, theta: float, port: Port, j: int = 0, poly: np.ndarray | None = None,
              cut: tuple[float, np.ndarray | None] | None = None) -> float:
    """Open area between chamber j and ``port`` at shaft angle θ [m²].

    ``cut`` is :func:`closing_cut` of the port (computed when not given; pass it when sampling many
    angles).
    """
    if poly is None:
        poly = chamber_polygon(g, theta, j)
    far, piece = closing_cut(g, port) if cut is None else cut
    area = _wedge_area(poly, port.start, far)
    if piece is None or len(piece) < 3 or area == 0.0:
        return area
    return max(area - intersection_area(poly, piece), 0.0)
