"""Suction and delivery ports of the valve plate.

A port is a kidney covering the whole radial band of the chambers between two
rays from the inner-gear centre O1 (angles in the fixed frame, CCW from the
+x axis, i.e. from O1 towards the nominal outer-gear centre).  The open area
between chamber j and a port is the part of the chamber polygon inside the
port's angular range; a port edge passing over a chamber opens or closes it
progressively.  The defaults leave a sealing land a little wider than a
chamber at the two dead centres, so no chamber ever sees both ports.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..errors import InputError
from .chambers import chamber_polygon, polygon_area

__all__ = ["Port", "clip_half_plane", "open_area"]


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
    """
    name: str
    start: float
    end: float

    def __post_init__(self):
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
    out = []
    for p, q, dp, dq in zip(poly, nxt, d, dn):
        if dp >= 0:
            out.append(p)
        if (dp >= 0) != (dq >= 0):
            t = dp / (dp - dq)
            out.append(p + t * (q - p))
    return np.array(out) if out else np.zeros((0, 2))


def _wedge_area(poly: np.ndarray, a0: float, a1: float) -> float:
    left = np.array([-math.sin(a0), math.cos(a0)])   # keep CCW of the ray at a0
    right = np.array([math.sin(a1), -math.cos(a1)])  # keep CW of the ray at a1
    c = clip_half_plane(clip_half_plane(poly, left), right)
    return abs(polygon_area(c)) if len(c) >= 3 else 0.0


def open_area(g, theta: float, port: Port, j: int = 0, poly: np.ndarray | None = None) -> float:
    """Open area between chamber j and ``port`` at shaft angle θ [m²]."""
    if poly is None:
        poly = chamber_polygon(g, theta, j)
    return _wedge_area(poly, port.start, port.end)
