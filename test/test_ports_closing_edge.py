"""Suction kidney whose closing edge follows the chamber at maximum volume (``ports.suction.closing_edge``).

Closed form where stated; the rest is behaviour of the exact polygon clip on the default gear set.
"""
import math
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gerotor_twin.config import load_config, parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.geometry.chambers import chamber_dA_dtheta_closed_form, chamber_polygon, ideal, polygon_area
from gerotor_twin.geometry.ports import Port, closing_cut, dead_centres, open_area

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def setup(cfg):
    g = ideal(cfg.gears)
    ray = replace(cfg.suction_port, closing_edge="ray")
    cut = replace(cfg.suction_port, closing_edge="chamber")
    return g, ray, cut, closing_cut(g, cut), dead_centres(g)[0]


def _is_extremum(g, theta: float, maximum: bool) -> None:
    """The chamber's rate vanishes at θ and turns sign the right way (closed-form rate), and the polygon area
    of chamber 0 is the larger (maximum) or smaller (minimum) there than a quarter degree either side."""
    h = math.radians(0.25)
    scale = float(np.max(np.abs(chamber_dA_dtheta_closed_form(g, np.linspace(0, g.chamber_period, 97), 0))))
    rate = [float(chamber_dA_dtheta_closed_form(g, t, 0)) for t in (theta - h, theta, theta + h)]
    assert abs(rate[1]) < 1e-12 * scale, rate
    assert (rate[0] > 0 > rate[2]) if maximum else (rate[0] < 0 < rate[2]), rate
    area = [abs(polygon_area(chamber_polygon(g, t, 0))) for t in (theta - h, theta, theta + h)]
    assert (area[1] > max(area[0], area[2])) if maximum else (area[1] < min(area[0], area[2])), area


@pytest.mark.parametrize("pump", [None, *sorted(p.name for p in (ROOT / "config" / "pumps").glob("*.yaml"))])
def test_dead_centres_are_the_extrema_of_the_chamber_volume(pump):
    """Closed form (the rate of the pitch-point rule, and the polygon areas) on the default pump and every pump
    of the family (N = 4 … 13): at the first angle of :func:`dead_centres` chamber 0 has its maximum volume, at the
    second its minimum, each within one chamber period."""
    g = ideal(load_config(None if pump is None else ROOT / "config" / "pumps" / pump).gears)
    tmax, tmin = dead_centres(g)
    assert 0 <= tmax < g.chamber_period and 0 <= tmin < g.chamber_period
    _is_extremum(g, tmax, True)
    _is_extremum(g, tmin, False)


def _five_chambers(cfg, eccentricity_m):
    """The default gear set with five chambers at ``eccentricity_m`` [m], ports from the geometry."""
    raw = cfg.to_dict()
    raw["gears"].update(chambers=5, eccentricity_m=eccentricity_m)
    raw["ports"] = {"timing": "geometry", "suction": {"closing_edge": "chamber"}, "delivery": {}}
    return parse_config(raw, source="five chambers")


@pytest.mark.parametrize("eccentricity_m", [3.5e-3, 4.0e-3])
def test_dead_centres_closed_form_where_the_rate_vanishes_on_a_sample(cfg, eccentricity_m):
    """Closed form (as above) for N = 5, whose dead centres (45° before the period's end, 180°) lie on samples of a
    721-point grid over the period of 450°, where dA/dθ comes out exactly 0.0: both dead centres were once taken
    for the maximum, which made a valid gear set's geometric kidneys invalid (a suction port spanning 325°,
    refused by the config's check).  The kidneys from the geometry span less than 180° each."""
    c = _five_chambers(cfg, eccentricity_m)
    g = ideal(c.gears)
    tmax, tmin = dead_centres(g)
    assert tmax == pytest.approx(g.chamber_period - math.radians(45), abs=1e-12)
    assert tmin == pytest.approx(math.pi, abs=1e-12)
    _is_extremum(g, tmax, True)
    _is_extremum(g, tmin, False)
    for port in (c.suction_port, c.delivery_port):
        assert 0.0 < port.end - port.start < math.pi, port


def test_a_land_or_groove_that_bridges_the_kidneys_is_named_when_loaded(cfg):
    """Behaviour: kidney angles written for the default seven-chamber set, kept on a five-chamber one (a user's first
    try), leave the chamber at each dead centre open to both kidneys; the config loads and says so in one note per
    land with the shortfall (18.87° at the maximum-volume dead centre, 26.09° at the minimum, from the
    geometry's own port_timing); a relief groove whose tip runs past the dead-centre chamber is named too; the
    default pump, whose lands are the chamber's width, and the same five-chamber set with ``timing: geometry``
    load without such a note."""
    raw = cfg.to_dict()
    raw["gears"].update(chambers=5, eccentricity_m=4.0e-3)
    notes = [n for n in parse_config(raw, source="five").notes if n.startswith("ports")]
    assert len(notes) == 2, notes
    assert "maximum-volume dead centre is 18.87 deg narrower" in notes[0]
    assert "minimum-volume dead centre is 26.09 deg narrower" in notes[1]
    grooved = cfg.to_dict()
    grooved["ports"]["delivery"]["opening_notch"] = {"length_deg": 10.0, "width_m": 1e-3, "depth_m": 1e-3}
    assert [n.split(":")[0] for n in parse_config(grooved, source="groove").notes] == ["ports.delivery.opening_notch"]
    assert not [n for n in cfg.notes if n.startswith("ports")]
    assert not [n for n in _five_chambers(cfg, 4.0e-3).notes if n.startswith("ports")]


def test_chamber_edge_closes_exactly_at_the_dead_centre_and_linearly_before(setup):
    """Behaviour: the open area is 0 at the maximum-volume dead centre (the chamber then fills the cut),
    and falls linearly to it (twice the angle, twice the area), where the ray edge closes like a cusp."""
    g, ray, cut, c, tmax = setup

    def area(port, deg, cc=None):
        t = tmax + math.radians(deg)
        return open_area(g, t, port, poly=chamber_polygon(g, t, 0), cut=cc)

    assert area(cut, 0.0, c) <= 1e-14                               # of ≈ 1.4e-4 m² at the cut
    for d in (0.05, 0.5, 1.0):
        assert area(cut, -2 * d, c) / area(cut, -d, c) == pytest.approx(2.0, rel=0.02), d
    assert area(ray, -1.0) < 1e-3 * area(cut, -1.0, c)              # measured 5.0e-9 against 8.4e-6 m²


def test_chamber_edge_only_adds_area_and_not_before_the_ray(setup):
    """Behaviour: the chamber-cut kidney contains the ray kidney, so it never opens less; the two are the
    same until a chamber reaches the old ray."""
    g, ray, cut, c, tmax = setup
    more = 0
    for t in np.linspace(0, g.chamber_period, 240, endpoint=False):
        poly = chamber_polygon(g, t, 0)
        a_ray, a_cut = open_area(g, t, ray, poly=poly), open_area(g, t, cut, poly=poly, cut=c)
        assert a_cut >= a_ray - 1e-15
        more += a_cut > a_ray + 1e-12
    assert 0 < more < 240 // 3


def test_chamber_edge_after_the_dead_centre_opens_only_a_sliver(setup):
    """Behaviour: past the dead centre the inner tooth flank, turning faster than the outer gear, uncovers
    a sliver of the cut (measured ≤ 2.2e-8 m²); bound: 1 % of the area 1° before the dead centre."""
    g, ray, cut, c, tmax = setup
    before = open_area(g, tmax - math.radians(1.0), cut, poly=chamber_polygon(g, tmax - math.radians(1.0), 0), cut=c)
    after = [open_area(g, t, cut, poly=chamber_polygon(g, t, 0), cut=c)
             for t in tmax + np.radians(np.linspace(0.05, 10.0, 40))]
    assert max(after) < 0.01 * before


@pytest.mark.parametrize("name,edge", [("suction", "arc"), ("delivery", "chamber")])
def test_closing_edge_rejects_bad_values(cfg, name, edge):
    raw = cfg.to_dict()
    raw["ports"][name]["closing_edge"] = edge
    with pytest.raises(InputError, match=f"ports.{name}.closing_edge"):
        parse_config(raw)


def test_closing_edge_round_trips_and_defaults_to_ray(cfg):
    raw = cfg.to_dict()
    assert parse_config(raw).suction_port == cfg.suction_port
    del raw["ports"]["suction"]["closing_edge"]
    assert parse_config(raw).suction_port.closing_edge == "ray"
    assert Port("suction", 3.5, 5.8).closing_edge == "ray"


def test_dead_centre_outlines_are_shared_by_one_gear_set_at_any_clearance(cfg):
    """Behaviour: the dead-centre chamber outlines every parse checks the port timing with are those of the ideal
    gear set, so a config parsed again with another tooth-tip clearance (what a calibration does thousands of
    times) reuses the same read-only arrays, and another gear set (five chambers) gets its own."""
    from gerotor_twin.geometry.ports import _dead_centre_polygons
    tighter = cfg.to_dict()
    tighter["clearances"]["tooth_tip_m"] *= 0.5
    g2 = parse_config(tighter, source="tighter").gears
    assert g2.tip_clearance != cfg.gears.tip_clearance
    a, b = _dead_centre_polygons(cfg.gears), _dead_centre_polygons(g2)
    assert a[True] is b[True] and a[False] is b[False]
    assert not a[True].flags.writeable
    five = _dead_centre_polygons(_five_chambers(cfg, 4.0e-3).gears)
    assert not np.array_equal(five[True], a[True])
