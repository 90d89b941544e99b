"""Geometry — closed-form tests (tier 1) and table-vs-exact consistency.

References: the pitch-point swept-area closed form of the displacement
(elliptic integrals, :meth:`GerotorGeometry.displacement_closed_form`) is
independent of the polygons it is compared with; constant total area and
periodicity are exact properties of a gerotor.
"""
import math
from dataclasses import replace

import numpy as np
import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.geometry.chambers import (chamber_area, chamber_dA_dtheta_closed_form, chamber_polygon,
                                            contact_points, force_projections, polygon_area)
from gerotor_twin.geometry.gaps import exact_gaps
from gerotor_twin.geometry.gerotor import GerotorGeometry

G0 = GerotorGeometry(7, 3.5e-3, 40e-3, 9e-3, 40e-3, 50.775e-3, 12e-3, 17.2e-3, 0.0)


def test_displacement_polygons_vs_closed_form():
    for g in (G0, GerotorGeometry(5, 4e-3, 30e-3, 8e-3, 32e-3, 45e-3, 8e-3, 12e-3, 0.0),
              GerotorGeometry(9, 2.5e-3, 40e-3, 8e-3, 40e-3, 50e-3, 12e-3, 20e-3, 0.0)):
        th = np.linspace(0, g.chamber_period, 361)
        a = np.array([chamber_area(g, t) for t in th])
        # extremes are at the dead centres (chamber symmetric about the line of centres)
        amax = chamber_area(g, g.chamber_period - math.pi / (g.chambers - 1))
        amin = chamber_area(g, math.pi)
        assert amax >= a.max() - 1e-12 and amin <= a.min() + 1e-12
        q_poly = (g.chambers - 1) * g.width * (amax - amin)
        assert q_poly == pytest.approx(g.displacement_closed_form(), rel=1e-3)


def test_total_area_between_gears_is_constant():
    tot = [sum(chamber_area(G0, t, j) for j in range(G0.chambers)) for t in np.linspace(0, 1.3, 23)]
    assert np.ptp(tot) / np.mean(tot) < 1e-5


def test_volume_periodic_and_chambers_shifted():
    T = G0.chamber_period
    for t in (0.1, 1.7, 4.0):
        assert chamber_area(G0, t + T) == pytest.approx(chamber_area(G0, t), rel=1e-9)
        assert chamber_area(G0, t, 2) == pytest.approx(chamber_area(G0, t + 2 * G0.chamber_shift), rel=1e-9)


def test_dV_integrates_to_volume_swing():
    th = np.linspace(math.pi, G0.chamber_period - math.pi / 6, 4001)   # min -> max volume
    dA = chamber_dA_dtheta_closed_form(G0, th)
    integral = np.trapezoid(dA, th)
    swing = chamber_area(G0, th[-1]) - chamber_area(G0, th[0])
    assert integral == pytest.approx(swing, rel=2e-4)


def test_contact_points_lie_on_both_profiles():
    for t in (0.2, 1.1, 3.3):
        X, on_inner = contact_points(G0, t)
        C = G0.lobe_centres(t)
        assert np.allclose(np.linalg.norm(X - C, axis=1), G0.lobe_radius, atol=1e-12)
        assert np.allclose(X, on_inner, atol=1e-9)
        # the nominal gaps of a clearance-free set are zero everywhere
        assert np.allclose(exact_gaps(G0, t, with_le=False).h, 0.0, atol=1e-10)


def test_force_projection_closed_form_matches_contour_integral():
    """Eq. (24)-(25): endpoint formulas vs a direct integral of n ds over the outer contour."""
    t = 0.9
    poly = chamber_polygon(G0, t, 0)
    n_inner = 400
    outer = poly[n_inner - 1:]
    outer = np.vstack([outer, poly[:1]])
    d = np.diff(outer, axis=0)
    n_ds = np.column_stack([-d[:, 1], d[:, 0]])           # left normal (into the outer gear, CW polygon)
    mid = 0.5 * (outer[1:] + outer[:-1]) - G0.outer_centre
    F = n_ds.sum(axis=0)
    torque = np.sum(mid[:, 0] * n_ds[:, 1] - mid[:, 1] * n_ds[:, 0])
    s = force_projections(G0, t, 0)
    assert F[0] == pytest.approx(s.ly, rel=1e-6)
    assert F[1] == pytest.approx(s.lx, rel=1e-6)
    assert torque == pytest.approx(s.torque_per_pressure_width, rel=1e-4)


def test_chamber_polygon_is_simple_and_clockwise():
    assert polygon_area(chamber_polygon(G0, 0.5, 3)) < 0


@pytest.mark.parametrize("field,kw", [
    ("gears.lobe_centre_radius_m", dict(lobe_centre_radius=20e-3)),   # R <= N e: loops
    ("gears.lobe_radius_m", dict(lobe_radius=17.5e-3)),               # lobes intersect
    ("gears.lobe_radius_m", dict(lobe_radius=12e-3, eccentricity=5e-3)),   # undercut
    ("gears.eccentricity_m", dict(eccentricity=-1e-3)),
    ("gears.width_m", dict(width=0.0)),
    ("gears.width_m", dict(width=float("nan"))),
    ("gears.chambers", dict(chambers=3)),
    ("gears.outer_root_radius_m", dict(outer_root_radius=35e-3)),
])
def test_bad_geometry_is_rejected(field, kw):
    with pytest.raises(InputError) as ei:
        replace(G0, **kw)
    assert ei.value.field == field
    assert "allowed" in str(ei.value)


def test_undercut_message_names_curvature():
    with pytest.raises(InputError, match="undercut"):
        replace(G0, lobe_radius=12e-3, eccentricity=5e-3)
