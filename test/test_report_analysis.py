"""Report analysis: time grid, plateau detection and error metrics on files with known content."""
import math

import numpy as np
import pytest

from gerotor_twin.report.analysis import binned, compare, error_stats, find_plateaus, make_grid, revolution_phase
from gerotor_twin.report.data import load_bench, load_twin, overlap
from report_helpers import DISP, write_bench, write_twin


@pytest.fixture(scope="module")
def loaded(tmp_path_factory):
    d = tmp_path_factory.mktemp("an")
    b = load_bench(write_bench(d / "b.mcap"))
    tw = load_twin(write_twin(d / "t.mcap", offset_m3s=1e-5), b.t0_ns)
    grid = make_grid(b, overlap(b, [tw]))
    return b, tw, grid


def test_binned_means_and_gaps():
    edges = np.array([0.0, 1.0, 2.0, 3.0])
    v = binned(np.array([0.2, 0.4, 2.5]), np.array([1.0, 3.0, 6.0]), edges)
    assert v.tolist() == [2.0, 4.0, 6.0]                       # empty middle bin interpolated


def test_plateaus_found_at_the_steps(loaded):
    _, _, grid = loaded
    ps = find_plateaus(grid)
    assert len(ps) == 2
    assert ps[0].rpm == pytest.approx(1000, abs=1e-6) and ps[0].bar == pytest.approx(10, abs=1e-6)
    assert ps[1].rpm == pytest.approx(2000, abs=1e-6) and ps[1].bar == pytest.approx(20, abs=1e-6)
    assert 0.9 < ps[0].t0 < 1.3 and ps[0].t1 < 6.0                # settle time dropped, step excluded
    assert ps[1].t0 > 6.0 + 1.0


def test_metrics_recover_a_known_offset(loaded):
    _, tw, grid = loaded
    ps = find_plateaus(grid)
    c = compare(grid, ps, tw, DISP)
    for row in c["plateaus"]:
        fe = row["flow_error_m3s"]
        assert fe["bias"] == pytest.approx(1e-5, rel=0.02)
        assert fe["rmse"] == pytest.approx(1e-5, rel=0.02)
        assert fe["max_abs"] == pytest.approx(1e-5, rel=0.05)
        qth = row["flow_measured_m3s"] / row["eta_measured"]
        assert row["eta_predicted"] - row["eta_measured"] == pytest.approx(1e-5 / qth, rel=0.05)
    assert c["overall"]["flow_error_m3s"]["n"] == sum(p.i1 - p.i0 for p in ps)


def test_error_stats():
    s = error_stats(np.array([1.0, -3.0, np.nan]))
    assert s == {"bias": -1.0, "rmse": math.sqrt(5.0), "max_abs": 3.0, "n": 2}
    assert error_stats(np.array([np.nan]))["bias"] is None


def test_revolution_phase(loaded):
    _, tw, _ = loaded
    ts = tw.summary[0]
    mid = 0.5 * (ts[10] + ts[11])
    ph = revolution_phase(tw, DISP, np.array([ts[10], mid, ts[0] - 1.0]))
    assert ph[0] == pytest.approx(0.0, abs=1e-9) and ph[1] == pytest.approx(math.pi, rel=1e-6)
    assert math.isnan(ph[2])
