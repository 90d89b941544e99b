"""Interactive part of the report: decimation, panel data, vendored uPlot, CSV downloads."""
import csv
import hashlib
import io
import re
import urllib.parse
from importlib import resources

import numpy as np
import pytest

from gerotor_twin.report.build import build_report
from gerotor_twin.report.interactive import UPLOT_VERSION, assets, panel_data
from gerotor_twin.report.panels import Band, Interval, TimeSeries, Trace, envelope, plateau_steps
from gerotor_twin.report.tables import csv_data_uri
from report_helpers import DISP, write_bench, write_twin

LPM = 6e4


def test_envelope_keeps_every_extreme():
    """Closed form: 10 000 samples, 100 points -> 50 buckets of 200 samples; each bucket's min/max
    are those of its samples, so a one-sample spike survives."""
    t = np.arange(10_000) * 0.01
    y = np.sin(t)
    y[4321] = 7.0
    d = envelope(t, y, 100)
    assert d.t.size == 50 and d.per_point == 200
    edges = np.linspace(t[0], t[-1], 51)
    k = np.clip(np.searchsorted(edges, t, side="right") - 1, 0, 49)
    for b in range(50):
        assert d.lo[b] == y[k == b].min() and d.hi[b] == y[k == b].max()
    assert d.hi.max() == 7.0


def test_short_trace_unchanged_and_gaps_kept():
    """Behaviour: a trace within the budget is drawn as is; NaN stays a gap."""
    t = np.arange(10.0)
    y = np.where(t == 5, np.nan, t)
    d = envelope(t, y, 100)
    assert not d.decimated and np.array_equal(d.lo, y, equal_nan=True)
    p = panel_data(TimeSeries("x", "h", "y [m]", (Trace("a", t, y),)), 100)
    assert p["series"][0]["y"][5] is None and p["series"][0]["y"][4] == 4.0


def test_panel_data_budget_and_bands():
    """Behaviour: a long trace becomes a max and a min series with a fill between them, within the
    point budget; a tolerance band becomes two series and a fill."""
    t = np.linspace(0, 100, 50_001)
    band_t, hi = plateau_steps([type("P", (), {"t0": 1.0, "t1": 2.0})()], [1.0])
    panel = TimeSeries("x", "h", "q [L/min]", (Trace("raw", t, np.cos(t)),), bands=(Band("tol", band_t, -hi, hi),),
                       intervals=(Interval(3.0, 4.5, "alarm", "red"),))
    p = panel_data(panel, 1000)
    labels = [s["label"] for s in p["series"]]
    assert labels == ["raw, max", "raw, min", "tol, upper", "tol, lower"]
    assert [b[:2] for b in p["bands"]] == [[1, 2], [3, 4]]
    assert all(len(s["x"]) <= 1000 for s in p["series"])
    assert p["series"][3]["y"] == [-1.0, -1.0, None] and "50001 samples" in p["decimation"][0]
    assert p["intervals"] == [[3.0, 4.5, "alarm", "red"]]


def test_vendored_uplot_is_the_recorded_release():
    """Golden: the vendored files are byte-identical to the npm release recorded in VENDORED.md."""
    root = resources.files("gerotor_twin.report").joinpath("vendor/uplot")
    notes = root.joinpath("VENDORED.md").read_text()
    assert f"| version | {UPLOT_VERSION} |" in notes
    for name in ("uPlot.iife.min.js", "uPlot.min.css"):
        digest = hashlib.sha256(root.joinpath(name).read_bytes()).hexdigest()
        assert f"`dist/{name}` (sha256 `{digest}`)" in notes, name
    css, js = assets()
    assert js.startswith(f"/* uPlot {UPLOT_VERSION}") and "Permission is hereby granted" in js
    assert "</script" not in js and "gerotorReport" in js and ".uplot" in css


def test_csv_data_uri_round_trip():
    """Behaviour: every character survives the data: URI (percent, hash, quotes, non-ASCII, newlines)."""
    text = 'a [%],b ±,"c, d"\n1,#2,x/y\n'
    uri = csv_data_uri(text)
    assert uri.startswith("data:text/csv;charset=utf-8,") and "\n" not in uri and "#" not in uri
    assert urllib.parse.unquote(uri.split(",", 1)[1]) == text


@pytest.fixture(scope="module")
def csvs(tmp_path_factory):
    d = tmp_path_factory.mktemp("csv")
    b = write_bench(d / "bench.mcap")
    t = write_twin(d / "twin.mcap", offset_m3s=1e-5)
    res = build_report(b, [t], d / "r.html", labels=["A"], csv_dir=d / "out")
    page = (d / "r.html").read_text()
    links = dict(re.findall(r'class="csv-link" download="([^"]+)" href="([^"]+)"', page))
    return res, d / "out", links


def _read(text):
    return list(csv.DictReader(io.StringIO(text)))


def test_aligned_csv_holds_the_grid(csvs):
    """Closed form: the twin is 1e-5 m³/s = 0.6 L/min above the meter; inside plateaus the error
    column says so, equals predicted − measured, and rows carry their plateau number."""
    res, out, links = csvs
    assert set(res["downloads"]) == set(links) == {p.name for p in out.iterdir()}
    text = (out / "r_aligned.csv").read_text()
    assert urllib.parse.unquote(links["r_aligned.csv"].split(",", 1)[1]) == text
    rows = _read(text)
    assert list(rows[0])[:3] == ["time [s]", "plateau", "speed [rpm]"]
    inside = [r for r in rows if r["plateau"] != "0"]
    assert {r["plateau"] for r in inside} == {"1", "2"}
    n_bins = sum(p["i1"] - p["i0"] for p in res["plateaus"])
    assert len(inside) == n_bins
    for r in inside:
        err = float(r["flow error A [L/min]"])
        assert err == pytest.approx(1e-5 * LPM, rel=1e-3)
        assert float(r["flow predicted A [L/min]"]) - float(r["flow measured [L/min]"]) == pytest.approx(err, abs=1e-4)
    p1 = [r for r in inside if r["plateau"] == "1"]
    qth = DISP * 1000 / 60 * LPM
    assert float(p1[0]["volumetric efficiency measured [%]"]) == pytest.approx(95.0, abs=0.01)
    assert float(p1[0]["volumetric efficiency predicted A [%]"]) == pytest.approx(95 + 0.6 / qth * 100, abs=0.01)


def test_plateau_csv_matches_the_metrics(csvs):
    """Behaviour: the per-plateau CSV repeats the JSON metrics in display units, with the verdict."""
    res, out, _ = csvs
    rows = _read((out / "r_plateaus_a.csv").read_text())
    assert [r["plateau"] for r in rows] == ["1", "2"]
    for r, m, v in zip(rows, res["twins"][0]["plateaus"], res["verdicts"][0]):
        assert float(r["flow bias [L/min]"]) == pytest.approx(m["flow_error_m3s"]["bias"] * LPM, abs=1e-3)
        assert float(r["flow tolerance ± [L/min]"]) == pytest.approx(v["flow_tol_m3s"] * LPM, abs=1e-3)
        assert r["verdict"].startswith(v["verdict"].upper()) and r["reason"] == "; ".join(v["reasons"])
