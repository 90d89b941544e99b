"""Exact area of the intersection of two simple polygons, convex or not.

The boundary of A ∩ B is made of the parts of ∂A inside B and the parts of ∂B inside A, so by Green's
theorem [1]

.. math::
    |A \\cap B| = \\tfrac12 \\oint_{\\partial A \\,\\cap\\, B} (x\\,dy - y\\,dx)
               + \\tfrac12 \\oint_{\\partial B \\,\\cap\\, A} (x\\,dy - y\\,dx),

both polygons counter-clockwise.  Every edge is split where it crosses (or starts or stops running along)
an edge of the other polygon; each piece lies wholly inside, outside or on the other boundary, which its
midpoint decides.  A piece of ∂A lying on ∂B with the same direction belongs to ∂(A ∩ B) once (counted
with A); with the opposite direction the two polygons only touch there, and it is dropped.  So
identical polygons, shared edges and touching polygons come out exact, which a chamber and the port edge
cut to its own outline need (:mod:`.ports`).

Only the area is built, never the intersection polygon, so no Greiner–Hormann bookkeeping of entry
and exit vertices (and its degenerate cases) is needed.

References
----------
[1] Green's theorem for polygons (the shoelace formula): B. Braden, "The surveyor's area formula",
    The College Mathematics Journal 17(4), 326–337, 1986.
[2] Haines, E., "Point in polygon strategies", in *Graphics Gems IV*, Academic Press, 1994, 24–46.
"""
from __future__ import annotations

import numpy as np

__all__ = ["intersection_area"]

_REL_TOL = 1e-12   # "on the other boundary": distance below this × the bounding-box diagonal


def _ccw(poly: np.ndarray) -> np.ndarray:
    """The polygon (K, 2) counter-clockwise, without repeated consecutive vertices."""
    p = np.asarray(poly, dtype=float)
    keep = np.any(p != np.roll(p, 1, axis=0), axis=1)
    p = p[keep] if keep.any() else p[:1]
    x, y = p[:, 0], p[:, 1]
    signed = np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))
    return p[::-1] if signed < 0 else p


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _split_parameters(p0, d, q0, e, tol):
    """(edge index, t) pairs, t ∈ [0, 1] along the edges p0 + t d, where an edge q0 + s e of the other
    polygon crosses, or where a collinear edge of the other polygon starts or stops along it.  Only the
    edge pairs whose bounding boxes overlap are tested."""
    lo_p, hi_p = np.minimum(p0, p0 + d) - tol, np.maximum(p0, p0 + d) + tol
    lo_q, hi_q = np.minimum(q0, q0 + e), np.maximum(q0, q0 + e)
    near = ((lo_p[:, None, 0] <= hi_q[None, :, 0]) & (lo_q[None, :, 0] <= hi_p[:, None, 0])
            & (lo_p[:, None, 1] <= hi_q[None, :, 1]) & (lo_q[None, :, 1] <= hi_p[:, None, 1]))
    i, k = np.nonzero(near)
    di, ek = d[i], e[k]
    r = q0[k] - p0[i]
    den = _cross(di, ek)
    ld, le = np.linalg.norm(di, axis=1), np.linalg.norm(ek, axis=1)
    parallel = np.abs(den) <= 1e-12 * ld * le
    with np.errstate(divide="ignore", invalid="ignore"):
        t = _cross(r, ek) / den
        s = _cross(r, di) / den
    hit = ~parallel & (t >= 0) & (t <= 1) & (s >= -1e-12) & (s <= 1 + 1e-12)
    coll = parallel & (np.abs(_cross(di, r)) / ld <= tol)      # collinear: the other edge's ends
    t0 = np.einsum("mj,mj->m", r, di) / (ld * ld)
    t1 = t0 + np.einsum("mj,mj->m", ek, di) / (ld * ld)
    idx = np.concatenate([i[hit], i[coll], i[coll]])
    ts = np.concatenate([t[hit], t0[coll], t1[coll]])
    ok = (ts >= 0.0) & (ts <= 1.0)
    return idx[ok], ts[ok], np.unique(i[coll])


def _inside(m, poly):
    """Crossing-number test of the points m (M, 2) against a polygon (K, 2) [2]."""
    a, b = poly, np.roll(poly, -1, axis=0)
    ya, yb = a[:, 1][None, :], b[:, 1][None, :]
    crosses = (ya > m[:, 1:2]) != (yb > m[:, 1:2])
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = a[:, 0][None, :] + (m[:, 1:2] - ya) * ((b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1]))[None, :]
    return (np.count_nonzero(crosses & (m[:, 0:1] < xint), axis=1) % 2) == 1


def _on_boundary(m, poly, tol):
    """Points m (M, 2) within ``tol`` of an edge of the polygon, and that edge's direction."""
    a = poly
    e = np.roll(poly, -1, axis=0) - a
    w = m[:, None, :] - a[None, :, :]
    s = np.clip(np.einsum("mkj,kj->mk", w, e) / np.einsum("kj,kj->k", e, e), 0.0, 1.0)
    dist2 = np.sum((w - s[..., None] * e[None, :, :]) ** 2, axis=2)
    nearest = np.argmin(dist2, axis=1)
    return dist2[np.arange(len(m)), nearest] <= tol * tol, e[nearest]


def _inside_pieces(p, other, tol, keep_same_direction):
    """½ Σ (x dy − y dx) over the pieces of ∂p inside ``other`` (and, if ``keep_same_direction``,
    the pieces on ∂other running the same way).  Edges of p outside the other's bounding box are
    outside it and are skipped."""
    d = np.roll(p, -1, axis=0) - p
    lo, hi = other.min(axis=0) - tol, other.max(axis=0) + tol
    cand = np.nonzero(np.all((np.minimum(p, p + d) <= hi) & (np.maximum(p, p + d) >= lo), axis=1))[0]
    if len(cand) == 0:
        return 0.0
    idx, ts, collinear = _split_parameters(p[cand], d[cand], other, np.roll(other, -1, axis=0) - other, tol)
    n = len(cand)
    edge = np.concatenate([np.arange(n), np.arange(n), idx])
    t = np.concatenate([np.zeros(n), np.ones(n), ts])
    order = np.lexsort((t, edge))
    edge, t = edge[order], t[order]
    piece = (edge[:-1] == edge[1:]) & (t[1:] > t[:-1])
    e0, ta, tb = edge[:-1][piece], t[:-1][piece], t[1:][piece]
    base, dir_ = p[cand][e0], d[cand][e0]
    s, f = base + ta[:, None] * dir_, base + tb[:, None] * dir_
    mid = 0.5 * (s + f)
    use = _inside(mid, other)
    shared = np.nonzero(np.isin(e0, collinear))[0]     # only pieces of edges running along the other's
    if len(shared):
        on, tangent = _on_boundary(mid[shared], other, tol)
        same = np.einsum("mj,mj->m", (f - s)[shared], tangent) > 0
        use[shared] = np.where(on, same & keep_same_direction, use[shared])
    return 0.5 * float(np.sum(_cross(s[use], f[use])))


def intersection_area(a: np.ndarray, b: np.ndarray) -> float:
    """Area of the intersection of two simple polygons [m²] (or the square of their unit).

    Parameters
    ----------
    a, b : ndarray (K, 2)
        Vertices of two simple (non self-intersecting) polygons, either orientation, not closed
        (the last vertex is joined to the first) [m].

    Returns
    -------
    float
        |A ∩ B| ≥ 0 [m²].

    Notes
    -----
    Exact up to round-off for any two simple polygons, including shared edges, identical polygons and
    polygons that only touch (see the module docstring).  Edges closer than 1e-12 × the bounding-box
    diagonal count as shared, so an overlap strip narrower than that is lost.  Cost O(K_a K_b) in time
    and memory.
    """
    a, b = _ccw(a), _ccw(b)
    if len(a) < 3 or len(b) < 3:
        return 0.0
    lo = np.minimum(a.min(axis=0), b.min(axis=0))
    hi = np.maximum(a.max(axis=0), b.max(axis=0))
    tol = _REL_TOL * float(np.linalg.norm(hi - lo))
    area = _inside_pieces(a, b, tol, True) + _inside_pieces(b, a, tol, False)
    return max(area, 0.0)
