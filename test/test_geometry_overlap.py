"""Exact intersection area of two simple polygons (:mod:`gerotor_twin.geometry.overlap`), closed form tier."""
import math

import numpy as np
import pytest

from gerotor_twin.geometry.overlap import intersection_area


def square(x, y, s):
    return np.array([[x, y], [x + s, y], [x + s, y + s], [x, y + s]], float)


L_SHAPE = np.array([[0, 0], [3, 0], [3, 1], [1, 1], [1, 3], [0, 3]], float)   # non-convex, area 5


@pytest.mark.parametrize("a,b,area", [
    (square(0, 0, 2), square(1, 1, 2), 1.0),          # corner overlap
    (square(0, 0, 2), square(0, 0, 2), 4.0),          # identical: every edge shared
    (square(0, 0, 2), square(2, 0, 2), 0.0),          # touching along an edge
    (square(0, 0, 2), square(2, 2, 2), 0.0),          # touching at a vertex
    (square(0, 0, 2), square(5, 5, 1), 0.0),          # apart
    (square(0, 0, 2), square(0, 0, 1), 1.0),          # nested, two shared edges
    (square(0, 0, 2), square(1, 0, 2), 2.0),          # collinear edges partly shared
    (square(0, 0, 4), square(1, 1, 1), 1.0),          # strictly inside
    (L_SHAPE, square(0.5, 0.5, 2), 1.75),             # non-convex: 2 × 0.5 + 0.5 × 1.5
    (L_SHAPE, square(1.5, 1.5, 1), 0.0),              # in the notch of the L
    (L_SHAPE, L_SHAPE, 5.0),
])
def test_intersection_area_closed_forms(a, b, area):
    for x, y in ((a, b), (b, a), (a[::-1], b), (a, np.roll(b[::-1], 1, axis=0))):   # symmetric, any orientation
        assert intersection_area(x, y) == pytest.approx(area, abs=1e-12)


def test_intersection_area_of_two_circles_is_the_lens():
    """Two unit circles at distance d: lens 2 r² acos(d/2r) − (d/2)√(4r² − d²); the polygons (n = 4000) lose
    at most the circle's discretisation deficit, ≈ 2π³/(3n²) ≈ 1.3e-6 relative."""
    t = np.linspace(0, 2 * np.pi, 4000, endpoint=False)
    c = np.column_stack([np.cos(t), np.sin(t)])
    for d in (0.3, 1.0, 1.7):
        lens = 2 * math.acos(d / 2) - d / 2 * math.sqrt(4 - d * d)
        assert intersection_area(c, c + [d, 0.0]) == pytest.approx(lens, rel=3e-6)


def test_intersection_area_of_a_sliver_is_linear_in_the_offset():
    """Closed form: a square slid by ε along a shared edge's normal keeps a 2 × ε strip, down to ε = 1e-9."""
    for eps in (1e-3, 1e-6, 1e-9):
        assert intersection_area(square(0, 0, 2), square(0, 2 - eps, 2)) == pytest.approx(2 * eps, rel=1e-6)


def test_clip_half_plane_closed_forms():
    """Closed form: Sutherland–Hodgman against a half-plane n·x ≥ 0 keeps the exact area, convex or not."""
    from gerotor_twin.geometry.chambers import polygon_area
    from gerotor_twin.geometry.ports import clip_half_plane

    def area(poly, normal):
        return abs(polygon_area(clip_half_plane(poly, np.asarray(normal, float))))

    assert area(square(0, 0, 2), [1.0, -1.0]) == pytest.approx(2.0, abs=1e-15)        # x ≥ y: half
    assert area(L_SHAPE, [0.0, 1.0]) == pytest.approx(5.0, abs=1e-15)                  # y ≥ 0: all of it
    assert area(L_SHAPE - [0.0, 0.5], [0.0, -1.0]) == pytest.approx(1.5, abs=1e-15)    # below y = 0.5: 3 × 0.5
    assert area(L_SHAPE - [0.0, 2.0], [0.0, 1.0]) == pytest.approx(1.0, abs=1e-15)     # the arm above y = 2
    assert area(L_SHAPE - [0.5, 0.0], [-1.0, 0.0]) == pytest.approx(1.5, abs=1e-15)    # left of x = 0.5: 0.5 × 3
    assert area(square(0, 0, 1), [-1.0, 0.0]) == 0.0                                   # touches x = 0 only


def _dense_crossing_test(m, poly):
    """The textbook crossing-number test over every (point, edge) pair [Haines 1994], the reference below."""
    a, b = poly, np.roll(poly, -1, axis=0)
    ya, yb = a[:, 1][None, :], b[:, 1][None, :]
    crosses = (ya > m[:, 1:2]) != (yb > m[:, 1:2])
    with np.errstate(divide="ignore", invalid="ignore"):
        xint = a[:, 0][None, :] + (m[:, 1:2] - ya) * ((b[:, 0] - a[:, 0]) / (b[:, 1] - a[:, 1]))[None, :]
    return (np.count_nonzero(crosses & (m[:, 0:1] < xint), axis=1) % 2) == 1


def test_points_inside():
    """Closed form: points of the L-shape's arms and notch, and points on the level of its vertices (the
    ties of the sorted sweep), are in or out as drawn; against the dense crossing-number test over every
    pair, the same answer point for point on a star polygon with level edges and 4000 random points, many
    on the vertices' y (behaviour: the pairs the sweep leaves out never cross)."""
    from gerotor_twin.geometry.overlap import points_inside
    pts = np.array([[0.5, 2.5], [2.5, 0.5], [2.0, 2.0], [0.5, 0.5], [-0.5, 1.0], [0.5, 1.0], [2.0, 1.0],
                    [0.5, 3.0], [0.5, 0.0], [3.5, 0.5]])
    assert points_inside(pts, L_SHAPE).tolist() == [True, True, False, True, False, True, False, False, True,
                                                    False]
    rng = np.random.default_rng(5)
    k = np.arange(40)
    r = np.where(k % 2 == 0, 1.0, 0.45)
    star = np.column_stack([r * np.cos(k * np.pi / 20), r * np.sin(k * np.pi / 20)])
    star = np.vstack([star[:10], [star[9, 0] - 0.3, star[9, 1]], star[10:]])           # a level edge
    m = rng.uniform(-1.1, 1.1, (4000, 2))
    m[::3, 1] = rng.choice(star[:, 1], len(m[::3]))                                     # on a vertex's y
    assert np.array_equal(points_inside(m, star), _dense_crossing_test(m, star))
    assert points_inside(np.zeros((0, 2)), star).shape == (0,)


def test_overlapping_boxes():
    """Behaviour: the box pairs the sorted sweep finds are ``np.nonzero`` of the dense test over every pair, in
    the same order: boxes of every width (points, a long edge's box, zero-width vertical edges), touching boxes
    included, and no boxes at all."""
    from gerotor_twin.geometry.overlap import _overlapping_boxes

    def dense(lo_p, hi_p, lo_q, hi_q):
        return np.nonzero((lo_p[:, None, 0] <= hi_q[None, :, 0]) & (lo_q[None, :, 0] <= hi_p[:, None, 0])
                          & (lo_p[:, None, 1] <= hi_q[None, :, 1]) & (lo_q[None, :, 1] <= hi_p[:, None, 1]))

    rng = np.random.default_rng(11)
    for n_p, n_q in ((300, 200), (7, 500), (1, 1)):
        boxes = []
        for n in (n_p, n_q):
            lo = rng.uniform(0, 10, (n, 2))
            size = rng.exponential(0.2, (n, 2)) * rng.choice([0.0, 1.0, 30.0], (n, 2), p=[0.2, 0.7, 0.1])
            lo[::5] = np.round(lo[::5])                                        # shared coordinates: touching
            boxes += [lo, lo + np.round(size, 1)]
        i, k = _overlapping_boxes(*boxes)
        ref_i, ref_k = dense(*boxes)
        assert np.array_equal(i, ref_i) and np.array_equal(k, ref_k)
        assert len(i) > 0 or n_p == 1
    empty = np.zeros((0, 2))
    assert len(_overlapping_boxes(empty, empty, boxes[2], boxes[3])[0]) == 0
    assert len(_overlapping_boxes(boxes[0], boxes[1], empty, empty)[0]) == 0


def test_cyclic_next():
    """Behaviour: a polygon's next vertices are numpy's roll by −1 along the first axis, element for element, for
    vertex arrays (K, 2), coordinate arrays (K,), one vertex and none."""
    from gerotor_twin.geometry.overlap import cyclic_next
    for a in (L_SHAPE, L_SHAPE[:, 1], L_SHAPE[:1], np.zeros((0, 2))):
        assert np.array_equal(cyclic_next(a), np.roll(a, -1, axis=0)) and cyclic_next(a).shape == a.shape
