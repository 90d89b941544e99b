"""Tables over the shaft angle for the hot loop — the same functions, sampled.

Everything the right-hand side needs per chamber (V, dV/dθ, port areas,
force projections) and per tooth-tip gap is a periodic function of the shaft
angle; chamber j (lobe k) at angle θ equals chamber 0 (lobe 0) at
θ + j·2π/(N−1), so one set of columns over one chamber period
Θ = 2πN/(N−1) serves all of them.

Gap columns hold the second-order expansion of the exact gap
h(θ; e_x, e_y, γ) (:func:`.gaps.exact_gaps`) about the nominal position,
where h = δ exactly:

.. math::
    h ≈ δ + \\mathbf g·\\mathbf z + \\tfrac12 \\mathbf z^T \\mathbf H \\mathbf z,
    \\quad \\mathbf z = (e_x, e_y, γ),

with g and H from central differences of the exact function.  Over the
reachable displacements (|e| ≤ c ≈ 0.1 mm) the remainder is O(|z|³/ρ²),
below 0.3 µm (measured: 0.23 µm at |e| = c, |γ| = 2 mrad); the tests check
the tables against the exact geometry.

The equivalent length uses the osculating-circle form
le = 2√(2 h dh / κ_rel), κ_rel = 1/r + κ_Γ (κ_Γ the curvature of the inner
profile, κ_T/(1 − ρκ_T) for the offset of the trochoid), checked against the
exact root-finding definition in the tests.
"""
from __future__ import annotations

import functools
import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from .._jit import njit
from .chambers import chamber_dA_dtheta_closed_form, chamber_polygon, contact_points, ideal, polygon_area
from .gerotor import GerotorGeometry
from .ports import Port, closing_cut, open_area

__all__ = ["GeometryTables", "build_tables", "interp", "COLUMNS"]

COLUMNS = ("V", "DV", "AS", "AD", "FX", "FY", "TQ",
           "GX", "GY", "GG", "HXX", "HXY", "HYY", "HXG", "HYG", "HGG",
           "KREL", "VR", "ARM", "PX", "PY", "DFX", "DFY")
(V, DV, AS, AD, FX, FY, TQ, GX, GY, GG, HXX, HXY, HYY, HXG, HYG, HGG,
 KREL, VR, ARM, PX, PY, DFX, DFY) = range(len(COLUMNS))
TABLE_VERSION = 4


@dataclass(frozen=True)
class GeometryTables:
    """Sampled geometry of chamber 0 / lobe 0 over one chamber period.

    Attributes
    ----------
    data : ndarray (len(COLUMNS), M)
        Columns (see ``COLUMNS``): V [m³], DV = dV/dθ [m³/rad], AS/AD open area to
        suction/delivery [m²], FX/FY pressure force per unit pressure [m²] (eq. 24),
        TQ torque about O2 per unit pressure [m³] (eq. 25), GX/GY/GG gap gradient
        [-, -, m/rad], H** gap Hessian, KREL relative curvature [1/m], VR = v_r/ω
        [m/rad], ARM lever of the contact normal about O2 [m], PX/PY gap point [m],
        DFX/DFY = d(FX, FY)/dθ [m²/rad].  FX, FY are also ∂V/∂e, the first-order change
        of the chamber volume with the outer-gear displacement (virtual work: p dV = F·de),
        so DFX, DFY are ∂(dV/dθ)/∂e (:mod:`gerotor_twin.model.volumes`).
    period : float
        Θ = 2πN/(N−1) [rad].
    shift : float
        2π/(N−1) [rad], lead of chamber j+1 over chamber j.
    """
    data: np.ndarray
    period: float
    shift: float
    chambers: int
    tip_clearance: float

    @property
    def size(self) -> int:
        return self.data.shape[1]

    def angles(self) -> np.ndarray:
        """Table abscissae [rad]."""
        return np.arange(self.size) * self.period / self.size

    def column(self, name: str, theta, j: int = 0):
        """Interpolated column ``name`` for chamber/lobe j at shaft angle(s) θ."""
        c = COLUMNS.index(name)
        th = np.atleast_1d(np.asarray(theta, dtype=float))
        out = np.array([interp(self.data, c, t + j * self.shift, self.period) for t in th])
        return out if np.ndim(theta) else float(out[0])


@njit
def interp(data, col, theta, period):
    """Periodic linear interpolation of column ``col`` at angle θ [rad]."""
    m = data.shape[1]
    x = (theta % period) / period * m
    i = int(math.floor(x))
    f = x - i
    i0 = i % m
    i1 = (i + 1) % m
    return data[col, i0] * (1.0 - f) + data[col, i1] * f


def _lobe0_gap(g: GerotorGeometry, theta, ex, ey, gamma):
    """Signed distance + δ of lobe 0 for arrays of θ (vectorised exact gap)."""
    N, R = g.chambers, g.lobe_centre_radius
    phi = theta * (N - 1) / N
    cx = g.eccentricity + ex + R * np.cos(phi)
    cy = ey + R * np.sin(phi)
    a = -(theta + gamma)
    qx = np.cos(a) * cx - np.sin(a) * cy
    qy = np.sin(a) * cx + np.cos(a) * cy
    u = -theta / N
    for _ in range(10):
        tx, ty = g.trochoid(u)
        dx, dy = g.trochoid_d1(u)
        ddx, ddy = g.trochoid_d2(u)
        rx, ry = tx - qx, ty - qy
        u = u - (rx * dx + ry * dy) / (dx * dx + dy * dy + rx * ddx + ry * ddy)
    tx, ty = g.trochoid(u)
    nx, ny = g.trochoid_normal(u)
    return g.tip_clearance + (qx - tx) * nx + (qy - ty) * ny, u


def _gap_columns(g: GerotorGeometry, th):
    se, sg = 2e-6, 2e-6 / g.lobe_centre_radius
    steps = np.array([se, se, sg])

    def h(z):
        return _lobe0_gap(g, th, z[0], z[1], z[2])[0]

    z0 = np.zeros(3)
    h0 = h(z0)
    grad = np.zeros((3, th.size))
    hess = np.zeros((3, 3, th.size))
    for a in range(3):
        ea = np.zeros(3)
        ea[a] = steps[a]
        hp, hm = h(ea), h(-ea)
        grad[a] = (hp - hm) / (2 * steps[a])
        hess[a, a] = (hp - 2 * h0 + hm) / steps[a] ** 2
        for b in range(a + 1, 3):
            eb = np.zeros(3)
            eb[b] = steps[b]
            hab = (h(ea + eb) - h(ea - eb) - h(-ea + eb) + h(-ea - eb)) / (4 * steps[a] * steps[b])
            hess[a, b] = hess[b, a] = hab
    _, u = _lobe0_gap(g, th, 0.0, 0.0, 0.0)
    kt = g.trochoid_curvature(u)
    krel = 1.0 / g.lobe_radius + kt / (1.0 - g.offset * kt)
    # gap point (inner profile) and normal in the fixed frame
    px, py = g.inner_profile(u)
    nx, ny = g.trochoid_normal(u)
    c, s = np.cos(th), np.sin(th)
    Px, Py = c * px - s * py, s * px + c * py
    Nx, Ny = c * nx - s * ny, s * nx + c * ny
    P = g.pitch_point
    vr = ((Px - P[0]) * Nx + (Py - P[1]) * Ny) / g.chambers
    O2 = g.outer_centre
    arm = (Px - O2[0]) * Ny - (Py - O2[1]) * Nx
    return h0, grad, hess, krel, vr, arm, Px, Py


def build_tables(g: GerotorGeometry, suction: Port, delivery: Port, size: int = 2048,
                 progress=None) -> GeometryTables:
    """Sample every column over one chamber period (``size`` points)."""
    th = np.arange(size) * g.chamber_period / size
    data = np.zeros((len(COLUMNS), size))
    gi = ideal(g)
    b = g.width
    data[DV] = b * chamber_dA_dtheta_closed_form(gi, th, 0)
    cuts = closing_cut(gi, suction), closing_cut(gi, delivery)
    for i, t in enumerate(th):
        poly = chamber_polygon(gi, t, 0)
        data[V, i] = b * abs(polygon_area(poly))
        data[AS, i] = open_area(gi, t, suction, poly=poly, cut=cuts[0])
        data[AD, i] = open_area(gi, t, delivery, poly=poly, cut=cuts[1])
        X, _ = contact_points(gi, t)
        a, c = X[0], X[1]
        lx, ly = a[0] - c[0], c[1] - a[1]                 # Eq. (24) projections
        m = 0.5 * (a + c) - gi.outer_centre               # chord midpoint -> arms
        data[FX, i], data[FY, i] = b * ly, b * lx
        data[TQ, i] = b * (ly * (-m[1]) + lx * m[0])      # Eq. (25)
        if progress is not None and i % 256 == 0:
            progress(i, size)
    step = g.chamber_period / size                        # periodic central differences, O(step²)
    data[DFX] = (np.roll(data[FX], -1) - np.roll(data[FX], 1)) / (2 * step)
    data[DFY] = (np.roll(data[FY], -1) - np.roll(data[FY], 1)) / (2 * step)
    h0, grad, hess, krel, vr, arm, Px, Py = _gap_columns(g, th)
    data[GX], data[GY], data[GG] = grad
    data[HXX], data[HXY], data[HYY] = hess[0, 0], hess[0, 1], hess[1, 1]
    data[HXG], data[HYG], data[HGG] = hess[0, 2], hess[1, 2], hess[2, 2]
    data[KREL], data[VR], data[ARM], data[PX], data[PY] = krel, vr, arm, Px, Py
    return GeometryTables(data=data, period=g.chamber_period, shift=g.chamber_shift,
                          chambers=g.chambers, tip_clearance=g.tip_clearance)


def _cache_dir() -> Path:
    base = os.environ.get("GEROTOR_TWIN_CACHE") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.expanduser("~/.cache")), "gerotor_twin")
    return Path(base)


@functools.lru_cache(maxsize=1)
def geometry_source_digest() -> str:
    """SHA-256 of the geometry package's sources (every ``*.py`` beside this module).

    Part of the cache key of :func:`cached_tables`: a table built by other code (an older release, a
    work in progress) is never read back, whether or not :data:`TABLE_VERSION` was raised.  (A
    prototype's table, cached under the same inputs, once fed a day of runs on the dev machine.)
    """
    h = hashlib.sha256()
    here = Path(__file__).resolve().parent
    for f in sorted(here.glob("*.py")):
        h.update(f.name.encode())
        h.update(f.read_bytes())
    return h.hexdigest()


def cached_tables(g: GerotorGeometry, suction: Port, delivery: Port, size: int = 2048,
                  progress=None) -> GeometryTables:
    """:func:`build_tables`, memoised on disk by a hash of the inputs and of the code that builds them
    (:func:`geometry_source_digest`)."""
    key = json.dumps({"g": asdict(g), "s": asdict(suction), "d": asdict(delivery), "n": size,
                      "v": TABLE_VERSION, "src": geometry_source_digest()}, sort_keys=True)
    digest = hashlib.sha256(key.encode()).hexdigest()[:20]
    path = _cache_dir() / f"tables_{digest}.npz"
    if path.exists():
        try:
            z = np.load(path)
            return GeometryTables(data=z["data"], period=g.chamber_period, shift=g.chamber_shift,
                                  chambers=g.chambers, tip_clearance=g.tip_clearance)
        except (OSError, ValueError, KeyError):
            pass
    t = build_tables(g, suction, delivery, size, progress)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(f".{os.getpid()}.tmp.npz")    # one per process (parallel builders)
        np.savez(tmp, data=t.data)
        os.replace(tmp, path)
    except OSError:
        pass
    return t
