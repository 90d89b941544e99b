"""The pump family in ``config/pumps/``, ports that follow the gear set, and relief grooves (notches).

Tiers: closed form (displacement, sealing points at the dead centres, notch area by hand), golden (the
default pump's hand-written port degrees), behaviour (every family file loads, spans what the family
promises, no chamber ever open to both kidneys), bad input (every notch / timing key named).
Tables are built at 512 points here (``build_tables``, not cached): ≈ 1–2 s per pump.
"""
import math
import re
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import yaml

from gerotor_twin.config import default_config_path, load_config, parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.geometry.chambers import chamber_polygon, ideal
from gerotor_twin.geometry.ports import (Notch, Port, closing_cut, dead_centres, geometry_port_angles,
                                         notch_area, open_area, port_timing, sealing_lands)
from gerotor_twin.geometry.tables import AD, AS, V, build_tables

FAMILY_DIR = Path(__file__).resolve().parent.parent / "config" / "pumps"
FAMILY = sorted(FAMILY_DIR.glob("*.yaml"))
IDS = [f.stem for f in FAMILY]
TABLE_POINTS = 512


@pytest.fixture(scope="module")
def configs():
    return {f.stem: load_config(f) for f in FAMILY}


@pytest.fixture(scope="module")
def tables(configs):
    return {k: build_tables(c.gears, c.suction_port, c.delivery_port, TABLE_POINTS) for k, c in configs.items()}


def test_family_has_at_least_eight_files():
    assert len(FAMILY) >= 8


@pytest.mark.parametrize("path", FAMILY, ids=IDS)
def test_family_member_loads_and_keeps_the_default_oil_laws_and_numerics(path):
    """Behaviour: the file passes every config and gear-set check (load_config runs the non-undercut,
    ring and root checks of geometry/gerotor.py) and differs from the default only in the pump."""
    cfg = load_config(path)
    ref = load_config(default_config_path()).to_dict()
    d = cfg.to_dict()
    for section in ("fluid", "fluid_model", "mixture", "oil", "orifice", "leakage", "boundary", "numerics",
                    "micro_motion"):
        assert d[section] == ref[section], section
    g = cfg.gears
    assert g.offset < g.min_convex_curvature_radius()                      # not undercut
    assert g.lobe_centre_radius > g.chambers * g.eccentricity


@pytest.mark.parametrize("path", FAMILY, ids=IDS)
def test_displacement_closed_form_matches_header_and_polygons(path, configs, tables):
    """Closed form: q of the pitch-point formula equals the value the header states (to its 4 figures)
    and (N−1)·(V_max − V_min) of the polygon volumes (each shaft turn takes N−1 chamber cycles)."""
    cfg, tab = configs[path.stem], tables[path.stem]
    q = cfg.gears.displacement_closed_form()
    m = re.search(r"Displacement ([0-9.]+) cm³/rev", path.read_text())
    assert m, "the header states the displacement"
    stated = float(m.group(1))
    assert q * 1e6 == pytest.approx(stated, abs=0.006 if stated < 10 else 0.06)
    swing = (cfg.gears.chambers - 1) * (tab.data[V].max() - tab.data[V].min())
    assert swing == pytest.approx(q, rel=2e-4)


def test_family_spans_what_users_build(configs):
    """Behaviour: chambers 4 … 13, ≤ 6 and ≥ 55 cm³/rev, a new pump (10 µm tip / 15 µm lateral), the
    default's clearances, an engine-oil pump to ≥ 6000 rpm, a slow pump (≤ 1000 rpm or rated from
    300 rpm), delivery 2 … 30 bar, a gear set with a relief groove, tight and large eccentricity."""
    cs = list(configs.values())
    assert {4, 5, 6, 7, 8, 9, 10, 11, 13} <= {c.gears.chambers for c in cs}
    q = [c.gears.displacement_closed_form() * 1e6 for c in cs]
    assert min(q) <= 6.0 and max(q) >= 55.0
    assert any(c.clearances.tooth_tip_m <= 10e-6 and c.clearances.lateral_m <= 15e-6 for c in cs)
    assert any(c.clearances.tooth_tip_m >= 31.4e-6 and c.clearances.lateral_m >= 134.8e-6 for c in cs)
    assert max(c.range.max_speed_rpm for c in cs) >= 6000
    assert any(c.range.max_speed_rpm <= 1000 or c.range.min_speed_rpm == 300 for c in cs)
    bars = [c.range.max_delivery_bar for c in cs]
    assert min(bars) <= 2.0 and max(bars) >= 30.0
    assert any(p.opening_notch or p.closing_notch for c in cs for p in (c.suction_port, c.delivery_port))
    lam = [c.gears.lobe_centre_radius / (c.gears.chambers * c.gears.eccentricity) for c in cs]
    assert min(lam) < 1.3 and max(lam) > 2.0                              # R/(N·e): large … tight e
    default = load_config(default_config_path())
    assert any(c.gears == replace(default.gears, tip_clearance=10e-6) for c in cs)


@pytest.mark.parametrize("path", FAMILY, ids=IDS)
def test_ports_follow_the_gear_set(path, configs):
    """Closed form: the kidney edges are the polar angles of the two sealing points
    X_k = C_k + r (P − C_k)/|P − C_k| of the chamber at each dead centre (outer-gear angle φ = −π/N and
    π − π/N), computed here from R, e, r, N alone, moved by a relief groove only where it is longer
    than the room the dead-centre chamber leaves on its circle (and by at most its length); never the
    default's degrees; every sealing margin of port_timing ≥ 0."""
    cfg = configs[path.stem]
    g = cfg.gears
    N, R, e, r = g.chambers, g.lobe_centre_radius, g.eccentricity, g.lobe_radius
    P = np.array([-(N - 1) * e, 0.0])

    def seal_angles(phi):
        out = []
        for k in (0, 1):
            a = phi + 2 * math.pi * k / N
            C = np.array([e + R * math.cos(a), R * math.sin(a)])
            X = C + r * (P - C) / np.linalg.norm(P - C)
            out.append(math.atan2(X[1], X[0]))
        return out
    mx = seal_angles(-math.pi / N)                       # ± the half land at θ = 0
    mn = [a % (2 * math.pi) for a in seal_angles(math.pi - math.pi / N)]
    d_open, s_close = max(mx), 2 * math.pi + min(mx)
    d_close, s_open = min(mn), max(mn)
    s, d = cfg.suction_port, cfg.delivery_port
    for edge, hand, notch, into_port in ((d.start, d_open, d.opening_notch, +1), (d.end, d_close, d.closing_notch, -1),
                                         (s.start, s_open, s.opening_notch, +1), (s.end, s_close, s.closing_notch, -1)):
        if notch is None:
            assert edge == pytest.approx(hand, abs=1e-9)
        else:                                  # moved into the port by at most the groove's length
            assert -1e-9 <= into_port * (edge - hand) <= notch.length + 1e-9
    if g.chambers != 7:
        got = [math.degrees(v) for v in (s.start, s.end, d.start, d.end)]
        assert max(abs(a - b) for a, b in zip(got, (199.70, 334.28, 25.72, 160.30))) > 1.0
    margins = port_timing(g, s, d)
    assert all(v >= -1e-9 for v in margins.values()), margins


def test_default_gear_set_reproduces_the_hand_written_degrees():
    """Golden: applied to the default gear set, the lands from the geometry give the kidney angles
    written by hand in config/pump.yaml (199.70, 334.28, 25.72, 160.30 deg) within 0.011 deg."""
    cfg = load_config(default_config_path())
    a = geometry_port_angles(cfg.gears)
    got = [math.degrees(v) for v in (*a["suction"], *a["delivery"])]
    assert got == pytest.approx([199.70, 334.28, 25.72, 160.30], abs=0.011)
    lands = sealing_lands(cfg.gears)
    assert math.degrees(lands.max_land) == pytest.approx(51.43, abs=0.01)
    assert math.degrees(lands.min_land) == pytest.approx(39.38, abs=0.01)


@pytest.mark.parametrize("path", FAMILY, ids=IDS)
def test_no_chamber_is_ever_open_to_both_ports(path, configs, tables):
    """Behaviour: over a chamber period (512 samples, and every 0.05° within ±1.5° of both dead centres)
    no chamber has open area to both kidneys with ray closing edges (≤ 1e-15 m², round-off).  With the suction kidney's
    chamber-shaped closing edge the inner tooth flank uncovers a sliver of the cut just after the
    maximum-volume dead centre (geometry/ports.py): bounded here by 1e-3 of the largest suction area
    (measured ≤ 4.7e-4, the 4-chamber pump) and found only within 60° after that dead centre."""
    cfg, tab = configs[path.stem], tables[path.stem]
    both = np.minimum(tab.data[AS], tab.data[AD])
    assert both.max() <= 1e-3 * tab.data[AS].max()
    if both.max() > 0:
        tmax = dead_centres(ideal(cfg.gears))[0]
        where = (tab.angles()[both > 0] - tmax) % tab.period
        assert np.all(where < math.radians(60.0))
    g = ideal(cfg.gears)
    ray = replace(cfg.suction_port, closing_edge="ray")
    cuts = closing_cut(g, ray), closing_cut(g, cfg.delivery_port)
    for t0 in dead_centres(g):
        for t in t0 + np.radians(np.arange(-1.5, 1.5001, 0.05)):
            poly = chamber_polygon(g, t, 0)
            a_s = open_area(g, t, ray, poly=poly, cut=cuts[0])
            a_d = open_area(g, t, cfg.delivery_port, poly=poly, cut=cuts[1])
            assert min(a_s, a_d) <= 1e-15, (math.degrees(t - t0), a_s, a_d)   # round-off of areas ≈ 1e-4 m²
    tab_ray = build_tables(cfg.gears, ray, cfg.delivery_port, TABLE_POINTS)
    assert np.minimum(tab_ray.data[AS], tab_ray.data[AD]).max() == 0.0


# ----------------------------------------------------------------- relief grooves
def _sector(r_in, r_out, a0, a1, n=400):
    """An annular sector polygon [m] (the 'chamber' of the hand computations)."""
    a = np.linspace(a0, a1, n)
    return np.vstack([np.column_stack([r_out * np.cos(a), r_out * np.sin(a)]),
                      np.column_stack([r_in * np.cos(a[::-1]), r_in * np.sin(a[::-1])])])


@pytest.mark.parametrize("shape,cover_deg,expected", [
    # groove: r_g = 30 mm, 10° long (L = 5.236 mm) from the kidney edge at 40° back to its tip at 30°,
    # w = 1.5 mm, d = 0.8 mm.  Chamber covering the groove from its tip to 30° + cover_deg:
    ("tapered", 4.0, 1.5e-3 * 0.8e-3 * 0.4),            # section at 34°: w·d·(4/10) = 4.8e-7 < w·s = 3.14e-6
    ("rectangular", 4.0, 1.5e-3 * 0.8e-3),              # w·d = 1.2e-6 < w·s
    ("rectangular", 0.5, 1.5e-3 * 30e-3 * math.radians(0.5)),   # w·s = 3.93e-7 < w·d
    ("tapered", 0.0, 0.0),                              # not reached
])
def test_notch_area_closed_form(shape, cover_deg, expected):
    """Closed form: A = min(w·s, A_g(η)) by hand for an annular-sector chamber over the groove."""
    n = Notch(length=math.radians(10.0), width=1.5e-3, depth=0.8e-3, radius=30e-3, shape=shape)
    edge, tip = math.radians(40.0), math.radians(30.0)
    lead = 30.0 + cover_deg
    poly = _sector(25e-3, 35e-3, math.radians(lead - 20.0), math.radians(lead))
    assert notch_area(poly, n, edge, tip) == pytest.approx(expected, rel=1e-9, abs=1e-18)


def test_notch_area_when_the_chamber_reaches_the_kidney_and_leaves_the_tip():
    """Closed form: a chamber spanning 35°…45° over a groove from 30° (tip) to 40° (kidney) covers
    s = r·5° ending at the kidney (η = 0): min(w·s, w·d) for both shapes; one inside the kidney only
    (41°…50°) covers nothing."""
    for shape in ("tapered", "rectangular"):
        n = Notch(length=math.radians(10.0), width=1.5e-3, depth=0.3e-3, radius=30e-3, shape=shape)
        poly = _sector(25e-3, 35e-3, math.radians(35.0), math.radians(45.0))
        ws = 1.5e-3 * 30e-3 * math.radians(5.0)
        assert notch_area(poly, n, math.radians(40.0), math.radians(30.0)) == pytest.approx(
            min(ws, 1.5e-3 * 0.3e-3), rel=1e-9)
        far = _sector(25e-3, 35e-3, math.radians(41.0), math.radians(50.0))
        assert notch_area(far, n, math.radians(40.0), math.radians(30.0)) == 0.0


def test_notched_pump_opens_progressively_before_the_kidney():
    """Behaviour (06, delivery opening notch): after the maximum-volume dead centre the delivery area
    is first the groove's alone, grows monotonically from 0, and equals the kidney's own area plus
    notch_area; the un-notched kidney at the same edge opens later / less."""
    cfg = load_config(FAMILY_DIR / "06_car_engine_oil_notched.yaml")
    g = ideal(cfg.gears)
    d = cfg.delivery_port
    plain = replace(d, opening_notch=None)
    tmax = dead_centres(g)[0]
    prev = -1.0
    grew_before_kidney = False
    for deg in np.arange(0.0, 12.0, 0.5):
        t = tmax + math.radians(deg)
        poly = chamber_polygon(g, t, 0)
        a = open_area(g, t, d, poly=poly)
        a0 = open_area(g, t, plain, poly=poly)
        assert a == pytest.approx(a0 + notch_area(poly, d.opening_notch, d.start, d.start - d.opening_notch.length),
                                  rel=1e-12, abs=1e-20)
        assert a >= prev - 1e-15
        grew_before_kidney |= (a > 0 and a0 < 0.05 * a)
        prev = a
    assert grew_before_kidney
    assert open_area(g, tmax, d) == 0.0


def test_notch_enters_the_table_and_its_cache_key(monkeypatch, tmp_path):
    """Behaviour: a groove changes the AD column, and two grooves differing only in depth are cached
    under two different keys (the Port, grooves included, is part of the key)."""
    from gerotor_twin.geometry import tables as tmod
    monkeypatch.setenv("GEROTOR_TWIN_CACHE", str(tmp_path))
    cfg = load_config(FAMILY_DIR / "06_car_engine_oil_notched.yaml")
    d = cfg.delivery_port
    t1 = tmod.cached_tables(cfg.gears, cfg.suction_port, d, 256)
    t2 = tmod.cached_tables(cfg.gears, cfg.suction_port, replace(d, opening_notch=replace(d.opening_notch,
                                                                                            depth=0.4e-3)), 256)
    assert len(list(tmp_path.glob("tables_*.npz"))) == 2
    assert not np.array_equal(t1.data[AD], t2.data[AD])
    assert np.array_equal(t1.data[AS], t2.data[AS])


def test_notched_config_round_trips_through_to_dict():
    """Behaviour: to_dict() writes the resolved kidneys and grooves explicitly; they parse back equal."""
    for name in ("06_car_engine_oil_notched.yaml", "08_transmission_relief_groove.yaml"):
        cfg = load_config(FAMILY_DIR / name)
        back = parse_config(cfg.to_dict())
        for a, b in ((cfg.suction_port, back.suction_port), (cfg.delivery_port, back.delivery_port)):
            assert a.start == pytest.approx(b.start, abs=1e-12) and a.end == pytest.approx(b.end, abs=1e-12)
            for k in ("opening_notch", "closing_notch"):
                na, nb = getattr(a, k), getattr(b, k)
                assert (na is None) == (nb is None)
                if na is not None:
                    assert (na.width, na.depth, na.radius, na.shape) == (nb.width, nb.depth, nb.radius, nb.shape)
                    assert na.length == pytest.approx(nb.length, abs=1e-12)


def _raw_notched():
    return yaml.safe_load((FAMILY_DIR / "06_car_engine_oil_notched.yaml").read_text())


@pytest.mark.parametrize("mutate,field", [
    (lambda r: r["ports"].update(timing="auto"), "ports.timing"),
    (lambda r: r["ports"]["delivery"].update(start_deg=25.0), "ports.delivery.start_deg"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(length_deg=0.0), "ports.delivery.opening_notch.length_deg"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(length_deg=45.0), "ports.delivery.opening_notch.length_deg"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(width_m=-1e-3), "ports.delivery.opening_notch.width_m"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(depth_m=float("nan")),
     "ports.delivery.opening_notch.depth_m"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(shape="round"), "ports.delivery.opening_notch.shape"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(radius_m=0.1), "ports.delivery.opening_notch.radius_m"),
    (lambda r: r["ports"]["delivery"]["opening_notch"].update(colour="red"), "ports.delivery.opening_notch.colour"),
    (lambda r: r["ports"]["delivery"].update(opening_notch=3), "ports.delivery.opening_notch"),
    (lambda r: r["ports"]["delivery"].update(bevel=1), "ports.delivery.bevel"),
    (lambda r: r["ports"]["suction"].update(closing_notch={"length_deg": 3, "width_m": 1e-3, "depth_m": 1e-4}),
     "ports.suction.closing_notch"),
    (lambda r: r["range"].update(min_speed_rpm=9000.0), "range.min_speed_rpm"),
])
def test_bad_port_and_notch_input_names_the_field(mutate, field):
    r = _raw_notched()
    mutate(r)
    with pytest.raises(InputError) as ei:
        parse_config(r)
    assert ei.value.field == field
    assert "allowed" in str(ei.value)


def test_explicit_degrees_with_a_groove_extend_the_kidney_onto_the_land():
    """Behaviour: with explicit degrees the groove runs from the written edge onto the land; a groove
    whose tip would pass the dead centre is refused."""
    r = yaml.safe_load(default_config_path().read_text())
    r["ports"]["delivery"]["opening_notch"] = {"length_deg": 5.0, "width_m": 1e-3, "depth_m": 0.5e-3}
    cfg = parse_config(r)
    assert math.degrees(cfg.delivery_port.start) == pytest.approx(25.72)
    assert isinstance(cfg.delivery_port, Port) and cfg.delivery_port.opening_notch.shape == "tapered"
    assert "delivery_opening_notch_margin" in port_timing(cfg.gears, cfg.suction_port, cfg.delivery_port)
    r["ports"]["delivery"]["opening_notch"]["length_deg"] = 26.0
    with pytest.raises(InputError, match="ports.delivery.opening_notch.length_deg"):
        parse_config(r)
