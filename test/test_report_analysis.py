"""Report analysis: time grid, plateau detection and error metrics on files with known content."""
import math

import numpy as np
import pytest

from gerotor_twin.report.analysis import (Grid, Plateau, binned, compare, error_stats, find_plateaus, make_grid,
                                         read_through_lag, revolution_phase)
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


def test_read_through_lag_closed_form():
    """Closed form: a first-order lag (τ = 0.4 s) reading a step from 0 to 1, sampled at irregular instants, is
    1 − e^{−t/τ} at every sample (the input held over each interval is exact for a step); τ = 0 reads the
    series as it is."""
    t = np.concatenate([[0.0], np.cumsum(np.random.default_rng(1).uniform(0.005, 0.05, 200))])
    v = np.where(t > 0, 1.0, 0.0)
    assert read_through_lag(t, v, 0.4) == pytest.approx(1 - np.exp(-t / 0.4), abs=1e-12)
    assert read_through_lag(t, v, 0.0) is not None and np.array_equal(read_through_lag(t, v, 0.0), v)


def test_compare_reads_the_twin_through_the_flow_meter():
    """Behaviour (closed-form bench): the pump's flow steps from 1e-4 to 2e-4 m³/s at t = 2 s and the bench's
    meter (τ = 0.5 s) reads it as 2e-4 − 1e-4·e^{−(t−2)/τ} (bin means exact); the plateau from 2.5 s on starts
    while the meter is still e⁻¹ behind.  A twin that predicts the flow exactly (samples every 5 ms) is judged
    on the meter's lag without ``flow_sensor_tau_s`` (plateau bias 1e-4·τ(e⁻¹ − e^{−7.8})/3.4 s = +5.4e-6 m³/s,
    2.7 % of the flow) and right with it, but for binning the twin's samples, each the value at its interval's
    end: half a sample late, (5 ms / 2)·(y(end) − y(start))/T = 2.7e-8 m³/s at most (measured 1.2e-8)."""
    from types import SimpleNamespace
    tau, dt = 0.5, 0.1
    edges = np.arange(0.0, 6.0 + dt / 2, dt)
    a, b = np.maximum(edges[:-1], 2.0), np.maximum(edges[1:], 2.0)      # the lagged part of each bin after 2 s
    lag = np.where(b > a, -1e-4 * tau * (np.exp(-(a - 2) / tau) - np.exp(-(b - 2) / tau)) / dt, 0.0)
    after = (b - a) / dt                                                # share of the bin after the step
    q_meas = 1e-4 + 1e-4 * after + lag
    grid = Grid(t=0.5 * (edges[:-1] + edges[1:]), omega=np.full(60, 100.0), p_delivery=np.full(60, 2e6),
                q_meas=q_meas)
    ts = np.arange(0.005, 6.0, 0.005)
    q = np.where(ts > 2.0 + 1e-12, 2e-4, 1e-4)
    qth = np.full(ts.size, 2.5e-4)
    twin = SimpleNamespace(summary=(ts, np.column_stack([q, qth, qth - q, q / qth])), label="twin", path="t")
    plateau = [Plateau(1, 25, 59, 2.5, 5.9, 955.0, 19.0)]
    plain = compare(grid, plateau, twin, 2.5e-4 * 2 * math.pi / 100.0)["plateaus"][0]["flow_error_m3s"]["bias"]
    read = compare(grid, plateau, twin, 2.5e-4 * 2 * math.pi / 100.0, 0.5)["plateaus"][0]["flow_error_m3s"]["bias"]
    expect = 1e-4 * tau * (np.exp(-0.5 / tau) - np.exp(-3.9 / tau)) / 3.4
    assert plain == pytest.approx(expect, rel=0.02)
    assert abs(read) <= 0.005 / 2 * 1e-4 * (np.exp(-1.0) - np.exp(-7.8)) / 3.4


def test_meter_expansion_closed_form():
    """Closed form: with the paper's oil law (ln ρ/ρ₀ = (p − p_atm)/β above its switch band) a meter at atmospheric
    pressure reads the twin's flow × exp((p_d − p_atm)/β) per bin, β at the bin's plateau's oil temperature
    (80 °C on the plateau, the reference temperature outside it; to 1e-6, the law's switch band at p_atm)."""
    from gerotor_twin.config import load_config
    from gerotor_twin.report.analysis import meter_expansion
    cfg = load_config().with_fluid_model("paper")
    p_atm = cfg.fluid.atmospheric_pa
    pd = p_atm + np.array([5e5, 20e5, 20e5, 27e5])
    grid = Grid(t=np.arange(4) * 0.1, omega=np.full(4, 100.0), p_delivery=pd, q_meas=np.full(4, 5e-4))
    f = meter_expansion(grid, [Plateau(1, 1, 3, 0.1, 0.3, 1000.0, 20.0)], [80.0], cfg)
    beta = [cfg.oil.bulk_modulus(t) for t in (cfg.reference_temperature_k, 353.15, 353.15,
                                              cfg.reference_temperature_k)]
    assert f == pytest.approx(np.exp((pd - p_atm) / np.array(beta)), rel=1e-6)
    assert f[1] > f[0] > 1.0 and f[1] != pytest.approx(math.exp(20e5 / beta[0]), rel=1e-6)   # β of 80 °C, not 40
