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

__all__ = ["intersection_area", "points_inside", "cyclic_next"]

_REL_TOL = 1e-12   # "on the other boundary": distance below this × the bounding-box diagonal


def cyclic_next(a: np.ndarray) -> np.ndarray:
    """Element i + 1 at i along the first axis, the first at the last: a polygon's next vertices (the same array as
    ``np.roll(a, -1, axis=0)``, without its general index arithmetic, which costs more than the copy on a
    polygon's few hundred vertices)."""
    return np.concatenate((a[1:], a[:1]))


def _ccw(poly: np.ndarray) -> np.ndarray:
    """The polygon (K, 2) counter-clockwise, without repeated consecutive vertices."""
    p = np.asarray(poly, dtype=float)
    keep = np.any(p != np.concatenate((p[-1:], p[:-1])), axis=1)   # vs the previous vertex
    p = p[keep] if keep.any() else p[:1]
    x, y = p[:, 0], p[:, 1]
    signed = np.dot(x, cyclic_next(y)) - np.dot(y, cyclic_next(x))
    return p[::-1] if signed < 0 else p


def _cross(a, b):
    return a[..., 0] * b[..., 1] - a[..., 1] * b[..., 0]


def _overlapping_boxes(lo_p, hi_p, lo_q, hi_q):
    """The pairs (i, k) of boxes [lo_p[i], hi_p[i]] and [lo_q[k], hi_q[k]] (closed, in x and y) that overlap, in
    row-major order: ``np.nonzero`` of the dense M × K test, without forming it.

    The boxes of q no wider in x than nine in ten of them (an edge's box: most are short) are sorted by their low
    x; such a box can overlap box i only if its low x lies within [lo_p[i] − w, hi_p[i]] (w: that width), so the
    candidates are the boxes whose low x lies in [lo_p[i] − 2 w, hi_p[i]] (room for round-off), one slice of the
    sorted boxes.  The wider tenth is tested against every box of p.  Every candidate then passes the dense
    test's four comparisons, so the pairs are the same.
    """
    width = hi_q[:, 0] - lo_q[:, 0]
    if len(width) == 0 or len(lo_p) == 0:
        return np.zeros(0, dtype=np.intp), np.zeros(0, dtype=np.intp)
    k9 = (9 * (len(width) - 1)) // 10
    w = float(np.partition(width, k9)[k9])       # about the 90th percentile: any w gives the same pairs
    narrow = np.nonzero(width <= w)[0]
    narrow = narrow[np.argsort(lo_q[narrow, 0], kind="stable")]
    first = np.searchsorted(lo_q[narrow, 0], lo_p[:, 0] - 2.0 * w, side="left")
    count = np.searchsorted(lo_q[narrow, 0], hi_p[:, 0], side="right") - first
    i = np.repeat(np.arange(len(lo_p)), count)
    k = narrow[np.repeat(first - (np.cumsum(count) - count), count) + np.arange(len(i))]
    wide = np.nonzero(width > w)[0]
    i = np.concatenate([i, np.repeat(np.arange(len(lo_p)), len(wide))])
    k = np.concatenate([k, np.tile(wide, len(lo_p))])
    near = ((lo_p[i, 0] <= hi_q[k, 0]) & (lo_q[k, 0] <= hi_p[i, 0])
            & (lo_p[i, 1] <= hi_q[k, 1]) & (lo_q[k, 1] <= hi_p[i, 1]))
    i, k = i[near], k[near]
    order = np.lexsort((k, i))
    return i[order], k[order]


def _split_parameters(p0, d, q0, e, tol):
    """(edge index, t) pairs, t ∈ [0, 1] along the edges p0 + t d, where an edge q0 + s e of the other
    polygon crosses, or where a collinear edge of the other polygon starts or stops along it.  Only the
    edge pairs whose bounding boxes overlap are tested."""
    lo_p, hi_p = np.minimum(p0, p0 + d) - tol, np.maximum(p0, p0 + d) + tol
    lo_q, hi_q = np.minimum(q0, q0 + e), np.maximum(q0, q0 + e)
    i, k = _overlapping_boxes(lo_p, hi_p, lo_q, hi_q)
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


def points_inside(m: np.ndarray, poly: np.ndarray) -> np.ndarray:
    """Even-odd (crossing-number) test of the points m (M, 2) against a closed polygon (K, 2) [2].

    A point is inside when a ray from it towards +x crosses the boundary an odd number of times; an edge
    counts when its ends straddle the point's y (one strictly above, the other not) and it crosses the
    ray's line to the right of the point, at x = x_a + (y − y_a) · ((x_b − x_a) / (y_b − y_a)).

    Only the (point, edge) pairs whose y straddles are formed: the points sorted by y, each edge's pairs
    are one slice of them (``searchsorted``), so the cost is O((M + K) log M) plus the pairs, not O(M K);
    each pair's crossing is the same floating-point expression as the dense M × K test, so the answer is
    the same bit for bit.
    """
    m = np.asarray(m, dtype=float).reshape(-1, 2)
    a = np.asarray(poly, dtype=float)
    b = cyclic_next(a)
    order = np.argsort(m[:, 1], kind="stable")
    ys = m[order, 1]
    lo, hi = np.minimum(a[:, 1], b[:, 1]), np.maximum(a[:, 1], b[:, 1])
    first = np.searchsorted(ys, lo, side="left")          # straddle: lo <= y < hi (never for a level edge)
    count = np.searchsorted(ys, hi, side="left") - first
    edge = np.repeat(np.arange(len(a)), count)
    start = np.repeat(np.cumsum(count) - count, count)
    pt = order[np.repeat(first, count) + np.arange(len(edge)) - start]
    with np.errstate(divide="ignore", invalid="ignore"):
        slope = (b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1])
    xint = a[edge, 0] + (m[pt, 1] - a[edge, 1]) * slope[edge]
    return np.bincount(pt[m[pt, 0] < xint], minlength=len(m)) % 2 == 1


def _on_boundary(m, poly, tol):
    """Points m (M, 2) within ``tol`` of an edge of the polygon, and that edge's direction."""
    a = poly
    e = cyclic_next(poly) - a
    w = m[:, None, :] - a[None, :, :]
    s = np.clip(np.einsum("mkj,kj->mk", w, e) / np.einsum("kj,kj->k", e, e), 0.0, 1.0)
    dist2 = np.sum((w - s[..., None] * e[None, :, :]) ** 2, axis=2)
    nearest = np.argmin(dist2, axis=1)
    return dist2[np.arange(len(m)), nearest] <= tol * tol, e[nearest]


def _inside_pieces(p, other, tol, keep_same_direction):
    """½ Σ (x dy − y dx) over the pieces of ∂p inside ``other`` (and, if ``keep_same_direction``,
    the pieces on ∂other running the same way).  Edges of p outside the other's bounding box are
    outside it and are skipped."""
    d = cyclic_next(p) - p
    lo, hi = other.min(axis=0) - tol, other.max(axis=0) + tol
    cand = np.nonzero(np.all((np.minimum(p, p + d) <= hi) & (np.maximum(p, p + d) >= lo), axis=1))[0]
    if len(cand) == 0:
        return 0.0
    idx, ts, collinear = _split_parameters(p[cand], d[cand], other, cyclic_next(other) - other, tol)
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
    use = points_inside(mid, other)
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
