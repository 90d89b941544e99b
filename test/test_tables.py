"""Tables over the shaft angle vs the exact geometry they sample (consistency tests).

The hot loop reads tables; these tests hold them to the exact functions:
volumes (polygons), port areas, dV/dθ (closed form), and the second-order gap
expansion against exact signed distances for displaced / rotated gears.
"""
import math

import numpy as np
import pytest

from gerotor_twin.geometry.chambers import chamber_area
from gerotor_twin.geometry.gaps import exact_gaps
from gerotor_twin.geometry.ports import open_area
from gerotor_twin.model import contact as C

RNG = np.random.default_rng(7)


def test_volume_and_port_tables_match_exact(fixed_model):
    m = fixed_model
    g = m.geometry
    for t in RNG.uniform(0, 2 * math.pi, 12):
        j = int(RNG.integers(g.chambers))
        v = g.width * chamber_area(g, t + 0.0, j)
        assert m.tables.column("V", t, j) == pytest.approx(v, rel=2e-5)
        for port, col in ((m.config.suction_port, "AS"), (m.config.delivery_port, "AD")):
            a = open_area(g, t, port, j)
            assert abs(m.tables.column(col, t, j) - a) < 2e-3 * 3e-4 + 1e-3 * a


def test_gap_expansion_matches_exact_geometry(fixed_model):
    """Second-order expansion vs exact gaps for |e| up to the housing clearance c."""
    m = fixed_model
    g = m.geometry
    c = m.config.clearances.housing_radial_m
    worst = 0.0
    for _ in range(25):
        t = RNG.uniform(0, 2 * math.pi)
        r, a = RNG.uniform(0, c), RNG.uniform(0, 2 * math.pi)
        ex, ey = r * math.cos(a), r * math.sin(a)
        gam = RNG.uniform(-2e-3, 2e-3)
        exact = exact_gaps(g, t, (ex, ey), gam, with_le=False).h
        coef = np.empty(9)
        for k in range(g.chambers):
            C.gap_coefficients(m.kernel.tab, t, k, coef)
            approx = C.gap_value(coef, g.tip_clearance, ex, ey, gam)
            worst = max(worst, abs(approx - exact[k]))
    # stated tolerance: 0.3 µm (1 % of the 30 µm tip clearance) for |e| <= c and |γ| <= 2 mrad;
    # the remainder is third order in (e, γ)
    assert worst < 0.3e-6


def test_equivalent_length_formula_matches_exact_definition(fixed_model):
    m = fixed_model
    g = m.geometry
    for t in (0.3, 1.9, 4.4):
        s = exact_gaps(g, t, (0.0, 0.0), 0.0, dh=m.config.tip_dh)
        for k in range(g.chambers):
            krel = m.tables.column("KREL", t, k)
            le = 2 * math.sqrt(2 * s.h[k] * m.config.tip_dh / krel)
            assert le == pytest.approx(s.le[k], rel=0.01)


def test_contact_check_leaves_one_contact(fixed_model):
    """Sec. 3.7: after the overlap check exactly one gap is closed and none overlaps."""
    m = fixed_model
    g = m.geometry
    cmat = np.empty((g.chambers, 9))
    h = np.empty(g.chambers)
    for e in ((0.0, 0.0), (40e-6, -10e-6), (-5e-6, 3e-6)):
        ex, ey, gam, kc = C.contact(m.kernel.tab, g.chambers, g.tip_clearance, 0.7, e[0], e[1], h, cmat)
        assert h.min() >= 0 and h[kc] < 1e-10
        assert np.sum(h < 1e-9) == 1
        exact = exact_gaps(g, 0.7, (ex, ey), gam, with_le=False).h
        assert np.allclose(h, exact, atol=0.3e-6)


def test_table_cache_is_keyed_on_the_code_that_builds_it(monkeypatch, tmp_path, fixed_model):
    """Behaviour: a cached table is read back only by the same geometry code.  The first call writes one
    file, the second reads it (nothing new); with other geometry sources (the digest replaced) the cached
    file is not read: a second file is built, equal to the first (same code really ran)."""
    from gerotor_twin.geometry import tables as T
    m = fixed_model
    g, cfg = m.geometry, m.config
    monkeypatch.setenv("GEROTOR_TWIN_CACHE", str(tmp_path))
    size = 256                                       # small: two builds in well under a second each
    first = T.cached_tables(g, cfg.suction_port, cfg.delivery_port, size)
    files = sorted(tmp_path.glob("tables_*.npz"))
    assert len(files) == 1
    again = T.cached_tables(g, cfg.suction_port, cfg.delivery_port, size)
    assert sorted(tmp_path.glob("tables_*.npz")) == files and np.array_equal(again.data, first.data)
    monkeypatch.setattr(T, "geometry_source_digest", lambda: "other code")
    other = T.cached_tables(g, cfg.suction_port, cfg.delivery_port, size)
    assert len(list(tmp_path.glob("tables_*.npz"))) == 2
    assert np.array_equal(other.data, first.data)


def test_locate_wraps_every_angle_into_the_table():
    """Closed form: θ·scale mod m gives the row pair (i0, i0 + 1 mod m) and the weight f in [0, 1) for any angle,
    negative and many periods away; an angle whose wrap rounds up to m, and a non-finite one, read row 0."""
    from collections import namedtuple
    tab_t = namedtuple("Tab", "rows scale")
    m = 16
    tab = tab_t(np.zeros((m, 1)), m / (2 * math.pi))
    for theta in (0.0, 1.0, -1.0, 2 * math.pi - 1e-12, 37.3 * 2 * math.pi + 0.4, -5.5 * 2 * math.pi, 15.5 / tab.scale):
        x = (theta * tab.scale) % m                       # Python's float mod: 0 ≤ x < m
        i0, i1, f = C.locate(tab, theta)
        assert (i0, i1) == (int(x), (int(x) + 1) % m)
        assert f == pytest.approx(x - int(x), abs=1e-9)
    assert C.locate(tab, -1e-300)[:2] == (0, 1)           # wraps to m in floating point: row 0, weight 0
    assert C.locate(tab, -1e-300)[2] == 0.0
    assert C.locate(tab, 15.9999 / tab.scale)[:2] == (15, 0)
    assert C.locate(tab, math.nan)[:2] == (0, 1)          # no index outside the table
