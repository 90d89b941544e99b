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
