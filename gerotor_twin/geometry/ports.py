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

Ports from the gear set (``ports.timing: geometry``)
--------------------------------------------------
:func:`sealing_lands` measures the chamber at each dead centre as seen from O1: its angular extent
(the smallest and largest polar angle of its outline).  :func:`geometry_port_angles` puts the kidney
edges exactly there, so the sealing land at each dead centre is as wide as the chamber that sits on
it: a chamber leaves one port at the instant it reaches the other, never sees both, and is never
trapped longer than that instant.  In the gear sets of this package the extent ends at the two
sealing points (the outline is widest there); the function does not assume it.  Applied to the
default gear set it gives 25.715°, 160.311°, 199.689° and 334.285°, within 0.011° of the degrees
written in ``config/pump.yaml`` (25.72, 160.30, 199.70, 334.28).  A relief groove at an edge
(below) reaches back onto the land, its tip no further than the dead-centre chamber reaches on the
groove's circle; a longer groove moves the kidney edge into the port.  :func:`port_timing` states
the margins of any pair of kidneys (explicit degrees too).

Relief groove / silencing notch
-------------------------------
A :class:`Notch` is a narrow groove milled into the port plate at a kidney edge, running along the
circle of radius ``radius`` about O1 for the angle ``length`` away from the kidney (into the land):
width w, depth d at the kidney, constant (``rectangular``) or falling linearly to 0 at the tip
(``tapered``, the common V-/wedge-ended silencing groove).  A chamber that covers part of it is
joined to the kidney through two sections in series: the groove's mouth under the chamber, w·s
(s = arc length of the groove covered by the chamber), and the groove's cross-section where the flow
leaves the chamber towards the kidney, A_g(η) (η = arc distance from the kidney edge of the covered
point nearest the kidney: w·d, or w·d·(1 − η/L) when tapered, L = radius·length).  The notch adds

.. math:: A_{notch} = \\min\\left(w\\,s,\\; A_g(\\eta)\\right)

to the open area of the chamber (the smaller section governs, the usual lumped-parameter treatment
of relief grooves [2]; the throttling length of the groove is neglected).  So the area grows
progressively from 0 as the chamber's edge runs in from the tip (tapered: linearly with the edge's
position; rectangular: as w·s until s reaches d, then w·d) before the kidney proper opens, and a
closing-edge groove lets the area fall to 0 the same way after the kidney has closed.  The covered
arc is the exact intersection of the groove's centreline circle with the chamber polygon
(:func:`arc_coverage`), so the area is exact for the polygon and continuous in the shaft angle.
The groove lies on the land, inside the band of the chambers; it changes neither the lateral lands
of :mod:`.lateral` (kidney to kidney) nor the chamber volumes.

References
----------
[1] Manring, N. D., Fales, R. C., *Hydraulic Control Systems*, 2nd ed., Wiley, 2019 (port-plate
    timing of positive-displacement pumps).
[2] Rundo, M., "Models for flow rate simulation in gear pumps: a review", Energies 10(9), 1261, 2017
    (port timing and relief grooves of gerotor port plates).
"""
from __future__ import annotations

import functools
import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .chambers import chamber_polygon, ideal, polygon_area
from .overlap import cyclic_next, intersection_area, points_inside

__all__ = ["Port", "Notch", "CLOSING_EDGES", "NOTCH_SHAPES", "clip_half_plane", "open_area", "closing_cut",
           "dead_centres", "SealingLands", "sealing_lands", "dead_centre_reach", "geometry_port_angles",
           "port_timing", "arc_coverage", "notch_area", "notch_span"]

CLOSING_EDGES = ("ray", "chamber")
NOTCH_SHAPES = ("tapered", "rectangular")


@dataclass(frozen=True)
class Notch:
    """A relief groove (silencing notch) at one kidney edge (see the module docstring).

    Parameters
    ----------
    length : float
        Angular length about O1 from the kidney edge to the groove's tip [rad].
    width : float
        w, width of the groove (radially) [m].
    depth : float
        d, depth of the groove at the kidney edge [m].
    radius : float
        Radius of the groove's centreline about O1 [m].
    shape : str
        ``"tapered"`` (depth falls linearly to 0 at the tip) or ``"rectangular"`` (constant depth).
    """
    length: float
    width: float
    depth: float
    radius: float
    shape: str = "tapered"

    def section(self, eta: float) -> float:
        """Cross-section of the groove at arc distance η [m] from the kidney edge [m²]."""
        if self.shape == "rectangular":
            return self.width * self.depth
        return self.width * self.depth * max(0.0, 1.0 - eta / (self.radius * self.length))


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
    opening_notch, closing_notch : Notch or None
        Relief groove extending the kidney before ``start`` (the edge a chamber reaches first) or
        after ``end`` (the edge it leaves last).
    """
    name: str
    start: float
    end: float
    closing_edge: str = "ray"
    opening_notch: Notch | None = None
    closing_notch: Notch | None = None

    def __post_init__(self):
        if self.closing_notch is not None and self.closing_edge == "chamber":
            raise InputError(f"ports.{self.name}.closing_notch", "a groove", "none with closing_edge: chamber",
                             "the chamber-shaped closing edge already shapes the end of the kidney")
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
    dn = cyclic_next(d)
    keep = d >= 0
    cross = keep != (dn >= 0)
    if not cross.any():                      # wholly on one side of the line (most calls)
        return poly.copy() if keep[0] else np.zeros((0, 2))
    nxt = cyclic_next(poly)
    t = np.where(cross, d / np.where(cross, d - dn, 1.0), 0.0)
    inter = poly + t[:, None] * (nxt - poly)
    pts = np.stack([poly, inter], axis=1).reshape(-1, 2)     # per edge: its start if kept, then the crossing
    mask = np.stack([keep, cross], axis=1).reshape(-1)
    return pts[mask]                         # not empty: a crossing keeps its point


def _wedge_area(poly: np.ndarray, a0: float, a1: float) -> float:
    c = _wedge_polygon(poly, a0, a1)                 # CCW of the ray at a0, CW of the ray at a1
    return abs(polygon_area(c)) if len(c) >= 3 else 0.0


def dead_centres(g) -> tuple[float, float]:
    r"""Shaft angles [rad] in [0, 2πN/(N−1)) where chamber 0 has its maximum and its minimum volume.

    The zeros of the closed-form rate (:func:`.chambers.chamber_dA_dtheta_closed_form`),
    dA₀/dθ ∝ |PX₁|² − |PX₀|² with |PX_k| a function of cos ψ_k, ψ_k = φ + 2πk/N: the rate
    vanishes where cos ψ₀ = cos ψ₁, the two lobes of chamber 0 symmetric about the line of centres O1O2,

    .. math::
        \varphi_\max = -\frac{\pi}{N},\qquad \varphi_\min = \pi - \frac{\pi}{N},\qquad
        \theta = \varphi\,\frac{N}{N-1} \bmod \frac{2\pi N}{N-1}.

    At φ_max the lobes sit either side of ψ = 0, where |PX| is largest; as φ grows |PX₁| falls and |PX₀|
    rises, so the rate turns from + to −: the maximum.  Exact for every gear set (no clearance enters).
    """
    n = g.chambers
    to_shaft = n / (n - 1)                   # θ = φ N/(N−1)
    period = g.chamber_period
    return (-math.pi / n * to_shaft) % period, ((math.pi - math.pi / n) * to_shaft) % period


def _angle_of(poly: np.ndarray) -> float:
    """Angle [rad] about O1 of a polygon's area centroid, in [0, 2π)."""
    x, y = poly[:, 0], poly[:, 1]
    xn, yn = cyclic_next(x), cyclic_next(y)
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
    """Open area between chamber j and ``port`` at shaft angle θ [m²], relief grooves included.

    ``cut`` is :func:`closing_cut` of the port (computed when not given; pass it when sampling many
    angles).
    """
    if poly is None:
        poly = chamber_polygon(g, theta, j)
    far, piece = closing_cut(g, port) if cut is None else cut
    area = _wedge_area(poly, port.start, far)
    if piece is not None and len(piece) >= 3 and area > 0.0:
        area = max(area - intersection_area(poly, piece), 0.0)
    for notch, edge in ((port.opening_notch, "opening"), (port.closing_notch, "closing")):
        if notch is not None:
            area += notch_area(poly, notch, *notch_span(port, edge))
    return area


def notch_span(port: Port, edge: str) -> tuple[float, float]:
    """Angles [rad] of the kidney edge a groove starts from and of its tip (``edge``: opening | closing)."""
    if edge == "opening":
        return port.start, port.start - port.opening_notch.length
    return port.end, port.end + port.closing_notch.length


def arc_coverage(poly: np.ndarray, radius: float, a0: float, a1: float) -> list[tuple[float, float]]:
    """Parts of the arc of ``radius`` [m] about O1 from angle ``a0`` to ``a1`` [rad] (a0 < a1, span < 2π)
    inside the polygon, as angle intervals [rad].

    Exact for the polygon: the arc is split where it crosses a polygon edge (a quadratic per edge) and
    each piece is inside or outside as a whole.
    """
    p = poly
    q = cyclic_next(poly)
    d = q - p
    a = np.einsum("ij,ij->i", d, d)
    b = 2 * np.einsum("ij,ij->i", p, d)
    c = np.einsum("ij,ij->i", p, p) - radius * radius
    disc = b * b - 4 * a * c
    ok = (disc >= 0) & (a > 0)
    sq = np.sqrt(np.where(ok, disc, 0.0))
    cuts = [a0, a1]
    mid = 0.5 * (a0 + a1)
    for t in ((-b - sq) / np.where(ok, 2 * a, 1.0), (-b + sq) / np.where(ok, 2 * a, 1.0)):
        hit = ok & (t >= 0) & (t <= 1)
        pts = p[hit] + t[hit, None] * d[hit]
        ang = mid + (np.arctan2(pts[:, 1], pts[:, 0]) - mid + math.pi) % (2 * math.pi) - math.pi
        cuts.extend(ang[(ang > a0) & (ang < a1)].tolist())
    cuts = np.unique(np.asarray(cuts))
    centres = 0.5 * (cuts[:-1] + cuts[1:])
    inside = points_inside(radius * np.column_stack([np.cos(centres), np.sin(centres)]), poly)
    return [(float(cuts[i]), float(cuts[i + 1])) for i in np.nonzero(inside)[0]]


def notch_area(poly: np.ndarray, notch: Notch, edge_angle: float, tip_angle: float) -> float:
    """Open area [m²] a relief groove adds between a chamber (polygon [m]) and its kidney.

    min(w·s, A_g(η)): s the groove's arc length covered by the chamber, η the arc distance from the
    kidney edge (``edge_angle`` [rad]) of the covered point nearest it; the groove runs to
    ``tip_angle`` [rad] (module docstring).
    """
    lo, hi = min(edge_angle, tip_angle), max(edge_angle, tip_angle)
    pieces = arc_coverage(poly, notch.radius, lo, hi)
    if not pieces:
        return 0.0
    s = notch.radius * sum(b - a for a, b in pieces)
    near = min(min(abs(a - edge_angle), abs(b - edge_angle)) for a, b in pieces)
    return min(notch.width * s, notch.section(notch.radius * near))


@dataclass(frozen=True)
class SealingLands:
    """The chambers at the two dead centres as seen from O1 (:func:`sealing_lands`).

    Angles [rad] in the fixed frame: the chamber at maximum volume spans (``max_lo``, ``max_hi``) about
    0 (``max_lo`` < 0), the one at minimum volume (``min_lo``, ``min_hi``) about π; ``max_radius``,
    ``min_radius`` [m] are the radii of their area centroids (the default radius of a relief groove
    at an edge facing that dead centre).
    """
    max_lo: float
    max_hi: float
    min_lo: float
    min_hi: float
    max_radius: float
    min_radius: float

    @property
    def max_land(self) -> float:
        """Angular width of the chamber at the maximum-volume dead centre [rad]."""
        return self.max_hi - self.max_lo

    @property
    def min_land(self) -> float:
        """Angular width of the chamber at the minimum-volume dead centre [rad]."""
        return self.min_hi - self.min_lo


#: The dead centre each kidney edge faces: True for the maximum-volume one (near angle 0)
FACES_MAX = {("delivery", "opening"): True, ("delivery", "closing"): False,
             ("suction", "opening"): False, ("suction", "closing"): True}


def _dead_centre_polygons(g) -> dict[bool, np.ndarray]:
    """Chamber 0's outline at the maximum- (True) and minimum-volume (False) dead centre of the ideal gear set
    (read-only arrays, shared)."""
    return _ideal_dead_centre_polygons(ideal(g))


@functools.lru_cache(maxsize=16)
def _ideal_dead_centre_polygons(gi) -> dict[bool, np.ndarray]:
    """:func:`_dead_centre_polygons` of an ideal gear set, kept: a config's every parse checks its port timing
    with them (:func:`port_timing`), and a calibration parses the same gear set with other clearances thousands of
    times (≈ 0.7 ms of a 1.1-ms parse each time)."""
    tmax, tmin = dead_centres(gi)
    out = {True: chamber_polygon(gi, tmax, 0), False: chamber_polygon(gi, tmin, 0)}
    for poly in out.values():
        poly.setflags(write=False)
    return out


def _centroid(poly: np.ndarray) -> np.ndarray:
    x, y = poly[:, 0], poly[:, 1]
    xn, yn = cyclic_next(x), cyclic_next(y)
    c = x * yn - xn * y
    a = 3.0 * float(np.sum(c))
    return np.array([float(np.sum((x + xn) * c)) / a, float(np.sum((y + yn) * c)) / a])


def sealing_lands(g) -> SealingLands:
    """Angular extent about O1 of the chamber at each dead centre (ideal gear set, polygon outline).

    The smallest and largest polar angle of chamber 0's outline at the shaft angles of
    :func:`dead_centres`, unwrapped about the dead centre's direction (0 or π).
    """
    polys = _dead_centre_polygons(g)
    out = {}
    for at_max, centre in ((True, 0.0), (False, math.pi)):
        poly = polys[at_max]
        ang = centre + (np.arctan2(poly[:, 1], poly[:, 0]) - centre + math.pi) % (2 * math.pi) - math.pi
        out[at_max] = (float(ang.min()), float(ang.max()), float(np.hypot(*_centroid(poly))))
    (mx_lo, mx_hi, mx_r), (mn_lo, mn_hi, mn_r) = out[True], out[False]
    return SealingLands(mx_lo, mx_hi, mn_lo, mn_hi, mx_r, mn_r)


def dead_centre_reach(g, port: str, edge: str, radius: float) -> float:
    """How far along the circle of ``radius`` [m] about O1 the chamber at the dead centre faced by this
    kidney edge reaches towards it [rad] (``port``: suction | delivery, ``edge``: opening | closing).

    A relief groove on that circle whose tip stays behind this angle is never reached by a chamber
    still open to the other kidney.  Raises :class:`InputError` if the chamber does not cross the
    circle.
    """
    at_max = FACES_MAX[(port, edge)]
    centre = 0.0 if at_max else math.pi
    pieces = arc_coverage(_dead_centre_polygons(g)[at_max], radius, centre - math.pi + 1e-9, centre + math.pi - 1e-9)
    if not pieces:
        raise InputError(f"ports.{port}.{edge}_notch.radius_m", radius,
                         "a radius the chamber at the dead centre crosses",
                         "a groove there would never meet a chamber")
    towards_positive = (port, edge) in (("delivery", "opening"), ("suction", "opening"))
    reach = max(b for _, b in pieces) if towards_positive else min(a for a, _ in pieces)
    return reach % (2 * math.pi) if port == "suction" else reach


def geometry_port_angles(g, notches: dict | None = None) -> dict[str, tuple[float, float]]:
    """Kidney angles [rad] that follow the gear set (``ports.timing: geometry``).

    Each sealing land is the chamber's extent at its dead centre (:func:`sealing_lands`): the delivery
    kidney runs from the maximum-volume chamber's leading extreme to the minimum-volume chamber's
    trailing one, the suction kidney from the minimum-volume chamber's leading extreme to the
    maximum-volume chamber's trailing one (+2π).  A relief groove of angular length L on the circle of
    radius r_g runs back from the kidney edge onto the land; its tip may come as far as the dead-centre
    chamber reaches on that circle (:func:`dead_centre_reach`).  If L is longer than that room, the
    kidney edge moves into the port by the difference, so the tip still sits there.

    Parameters
    ----------
    g : GerotorGeometry
        The gear set.
    notches : dict, optional
        ``{(port, edge): Notch}``, port ``"suction"`` | ``"delivery"``, edge ``"opening"`` | ``"closing"``.

    Returns
    -------
    dict
        ``{"suction": (start, end), "delivery": (start, end)}`` [rad].
    """
    lands = sealing_lands(g)
    edges = {("delivery", "opening"): lands.max_hi, ("delivery", "closing"): lands.min_lo,
             ("suction", "opening"): lands.min_hi, ("suction", "closing"): 2 * math.pi + lands.max_lo}
    for key, n in (notches or {}).items():
        if n is None:
            continue
        reach = dead_centre_reach(g, *key, n.radius)
        if key[0] == "suction" and key[1] == "closing":
            reach += 2 * math.pi
        sign = 1.0 if key[1] == "opening" else -1.0          # opening edges move CCW, closing edges CW
        room = sign * (edges[key] - reach)
        edges[key] += sign * max(0.0, n.length - room)
    return {"delivery": (edges[("delivery", "opening")], edges[("delivery", "closing")]),
            "suction": (edges[("suction", "opening")], edges[("suction", "closing")])}


def port_timing(g, suction: Port, delivery: Port) -> dict:
    """Sealing margins of a pair of kidneys on a gear set [rad] (negative: a chamber sees both ports).

    ``land_margin_max`` / ``land_margin_min``: land width minus the dead-centre chamber's angular
    extent (:func:`sealing_lands`) at the maximum- / minimum-volume dead centre; and for every relief
    groove, ``<port>_<edge>_notch_margin``: how far its tip stays behind the dead-centre chamber's reach
    on its circle (:func:`dead_centre_reach`).
    """
    lands = sealing_lands(g)
    out = {"land_margin_max": (delivery.start - (suction.end - 2 * math.pi)) - lands.max_land,
           "land_margin_min": (suction.start - delivery.end) - lands.min_land}
    for port in (suction, delivery):
        for edge in ("opening", "closing"):
            n = getattr(port, f"{edge}_notch")
            if n is None:
                continue
            kidney_edge, tip = notch_span(port, edge)
            reach = dead_centre_reach(g, port.name, edge, n.radius)
            if port.name == "suction" and edge == "closing" and reach < math.pi:
                reach += 2 * math.pi
            out[f"{port.name}_{edge}_notch_margin"] = (tip - reach) if edge == "opening" else (reach - tip)
    return out
