"""The HTML report: self-contained, every figure present, JSON metrics, rendered by headless Chromium."""
import csv
import html
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from gerotor_twin.cli import main
from gerotor_twin.config import load_config
from gerotor_twin.report.analysis import Plateau
from gerotor_twin.report.build import build_report
from gerotor_twin.report.data import load_twin
from gerotor_twin.report.figures import gap_profile
from gerotor_twin.io import messages as m
from report_helpers import T0, oil_c, write_bench, write_twin

FIG_IDS = ("fig-verdict", "fig-eta-map", "fig-waveform", "fig-trajectory", "fig-gaps")
TS_IDS = ("ts-speed", "ts-pressure", "ts-flow", "ts-residual", "ts-efficiency")


@pytest.fixture(scope="module")
def report(tmp_path_factory):
    d = tmp_path_factory.mktemp("rep")
    b = write_bench(d / "bench.mcap")
    t1 = write_twin(d / "twin_a.mcap", offset_m3s=1e-5)
    t2 = write_twin(d / "twin_b.mcap", offset_m3s=-2e-5)
    out = d / "report.html"
    rc = main(["report", "--bench", str(b), "--twin", str(t1), "--twin", str(t2), "--label", "A", "--label", "B",
               "-o", str(out), "--json", str(d / "m.json")])
    assert rc == 0
    return out, json.loads((d / "m.json").read_text()), d


def test_html_is_self_contained_with_every_figure(report):
    """Behaviour: every static figure embedded, every time plot's container and data present, nothing external."""
    out, _, _ = report
    page = out.read_text()
    for fid in FIG_IDS:
        assert re.search(rf'id="{fid}" alt="[^"]*" src="data:image/png;base64,[A-Za-z0-9+/=]{{200,}}"', page), fid
    for tid in TS_IDS:
        assert f'<div class="ts-panel" id="{tid}"></div>' in page, tid
    assert not re.search(r'(src|href)="(https?:)?//', page) and "<link" not in page
    assert "<script src" not in page and "@import" not in page
    assert page.count("<table class='metrics'") == 4        # summary, verdicts side by side, one plateau table per twin


def test_json_metrics(report):
    """Behaviour: metrics recovered from files with a known constant flow offset."""
    _, res, _ = report
    assert len(res["plateaus"]) == 2 and res["figures_drawn"] == len(FIG_IDS)
    assert res["interactive_plots"] == len(TS_IDS)
    a, b = res["twins"]
    assert (a["label"], b["label"]) == ("A", "B")
    assert a["overall"]["flow_error_m3s"]["bias"] == pytest.approx(1e-5, rel=0.03)
    assert b["overall"]["flow_error_m3s"]["bias"] == pytest.approx(-2e-5, rel=0.03)
    assert set(a["plateaus"][0]) >= {"rpm", "bar", "flow_measured_m3s", "flow_predicted_m3s", "eta_measured",
                                      "eta_predicted", "flow_error_m3s", "eta_error"}
    assert [v["verdict"] for vs in res["verdicts"] for v in vs] == ["fail"] * 4    # 0.6 / 1.2 L/min off


def test_missing_optional_topic_drops_only_its_figure(tmp_path):
    """Behaviour: a twin without waveforms loses that figure only, and the page says why."""
    b = write_bench(tmp_path / "b.mcap")
    t = write_twin(tmp_path / "t.mcap", waveforms=False)
    res = build_report(b, [t], tmp_path / "r.html")
    page = (tmp_path / "r.html").read_text()
    assert res["figures_drawn"] == len(FIG_IDS) - 1 and 'id="fig-waveform-missing"' in page
    assert "/twin/chamber_waveform" in page


def test_oil_temperature_beside_speed_and_pressure(tmp_path):
    """Behaviour (issue 13): with ``/bench/oil_temperature`` in the bench bag the report has the oil panel
    and every plateau row its mean oil temperature; the bench warms linearly (30 °C + 2 K/s), so a
    plateau's mean is the closed form 30 + (t0 + t1) °C.  Without the topic the panel is absent."""
    b = write_bench(tmp_path / "b.mcap", types={"/bench/oil_temperature": m.TEMPERATURE})
    t = write_twin(tmp_path / "t.mcap")
    res = build_report(b, [t], tmp_path / "r.html", json_path=tmp_path / "m.json")
    page = (tmp_path / "r.html").read_text()
    assert '<div class="ts-panel" id="ts-oil-temperature"></div>' in page and "oil [°C]" in page
    rows = json.loads((tmp_path / "m.json").read_text())["twins"][0]["plateaus"]
    assert rows
    for r in rows:
        assert r["oil_temperature_c"] == pytest.approx(0.5 * (oil_c(r["t0_s"]) + oil_c(r["t1_s"])), abs=0.05), r
    b0 = write_bench(tmp_path / "b0.mcap")
    build_report(b0, [t], tmp_path / "r0.html")
    assert 'id="ts-oil-temperature"' not in (tmp_path / "r0.html").read_text()


def test_gap_profile_is_physical(tmp_path):
    cfg = load_config()
    tw = load_twin(write_twin(tmp_path / "t.mcap"), T0)
    ang = np.radians(np.arange(0, 360, 5.0))
    h = gap_profile(tw, Plateau(1, 0, 1, 1.0, 5.0, 1000, 10), cfg, ang)
    assert h.shape == (ang.size, cfg.gears.chambers)
    assert np.all(h >= 0) and np.all(h.min(axis=1) < 1e-7)       # one lobe in contact at every angle
    assert h.max() < 2 * cfg.gears.eccentricity


# --- the page in a real browser -------------------------------------------------------------
# Injected first in <head>: records every error / console.error / console.warn from the page's
# own scripts, then (after load) inspects each plot: uPlot instance present, its series hold data,
# series pixels drawn (ink with series shown > ink with every series hidden), hover fills the
# legend, zooming one plot moves the others; lists CSV links and any non-data: resource load.
PROBE_JS = """<script>
window.__errors = [];
window.addEventListener('error', e => window.__errors.push('error: ' + e.message));
window.addEventListener('unhandledrejection', e => window.__errors.push('rejection: ' + e.reason));
for (const k of ['error', 'warn']) {
  const orig = console[k];
  console[k] = (...a) => { window.__errors.push(k + ': ' + a.join(' ')); orig.apply(console, a); };
}
function ink(u) {      // opaque pixels inside the plotting area (grid and shading are translucent)
  const b = u.bbox, d = u.ctx.getImageData(b.left, b.top, b.width, b.height).data;
  let n = 0; for (let k = 3; k < d.length; k += 4) if (d[k] > 128) n++; return n;
}
const tick = () => new Promise(r => setTimeout(r, 30));
window.addEventListener('load', () => setTimeout(async () => {
  const out = {errors: window.__errors, images: [], plots: [], links: [], resources: []};
  for (const i of document.querySelectorAll('img.report-figure'))
    out.images.push({id: i.id, ok: i.complete && i.naturalWidth > 100 && i.naturalHeight > 100,
                     natural: i.naturalWidth, shown: Math.round(i.getBoundingClientRect().width)});
  const R = window.gerotorReport || {plots: []};
  for (const el of document.querySelectorAll('.ts-panel')) {
    const u = R.plots.find(p => p.panelId === el.id);
    const rec = {id: el.id, plot: !!u, series: []};
    if (u) {
      for (let s = 1; s < u.series.length; s++)
        rec.series.push([u.series[s].label, u.data[s].filter(v => v != null).length]);
      rec.ink = ink(u);
      for (let s = 1; s < u.series.length; s++) u.setSeries(s, {show: false});
      await tick();
      rec.inkHidden = ink(u);
      for (let s = 1; s < u.series.length; s++) u.setSeries(s, {show: true});
      await tick();
      u.setCursor({left: u.bbox.width / 2 / devicePixelRatio, top: u.bbox.height / 2 / devicePixelRatio});
      rec.legend = [...el.querySelectorAll('.u-legend .u-value')].map(v => v.textContent);
      rec.fonts = u.axes.map(a => a.font[0]).concat(u.axes.map(a => a.labelFont[0]));
      const tol = u.series.findIndex(s => s.label === 'tolerance, upper'), pl = R.spec.plateaus;
      if (tol > 0 && pl.length > 1) {      // between two plateaus the band is a gap (null), not bridged
        const i = u.data[0].findIndex(x => x >= (pl[0][1] + pl[1][0]) / 2);
        rec.bandBetween = u.data[tol][i] === null ? 'gap' : String(u.data[tol][i]);
      }
    }
    out.plots.push(rec);
  }
  if (R.plots.length > 1) {
    const a = R.plots[0], b = R.plots[R.plots.length - 1];
    const m = (a.scales.x.min + a.scales.x.max) / 2;
    a.setScale('x', {min: m - 1, max: m + 1});
    await tick();
    out.zoomSync = [b.scales.x.min, b.scales.x.max, m - 1, m + 1];
  }
  for (const a of document.querySelectorAll('a.csv-link'))
    out.links.push({name: a.getAttribute('download'), href: a.getAttribute('href').slice(0, 30)});
  out.resources = performance.getEntriesByType('resource').map(e => e.name).filter(n => !n.startsWith('data:'));
  const pre = document.createElement('pre'); pre.id = 'probe-result';
  pre.textContent = JSON.stringify(out); document.body.appendChild(pre);
}, 300));
</script>"""


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


def run_probe(page_path, work_dir):
    """Load ``page_path`` with the probe in headless Chromium (1280 px wide); the probe's findings."""
    probe = work_dir / "probe.html"
    probe.write_text(page_path.read_text().replace("<head>", "<head>" + PROBE_JS, 1))
    cmd = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
           "--window-size=1280,2000", "--virtual-time-budget=10000", "--dump-dom", probe.as_uri()]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    m = re.search(r'<pre id="probe-result">(.*?)</pre>', r.stdout, re.S)
    assert m, r.stderr[-2000:]
    return json.loads(html.unescape(m.group(1)))


@pytest.mark.skipif(_chromium() is None, reason="Debian package chromium not installed (make test installs it)")
def test_headless_chromium_renders_every_plot(report):
    """Behaviour: in a real browser the page loads without errors, every static figure and every
    interactive plot renders with data, hover and linked zoom work, nothing is fetched."""
    out, _, d = report
    res = run_probe(out, d)
    assert res["errors"] == []
    assert [i["id"] for i in res["images"]] == list(FIG_IDS) and all(i["ok"] for i in res["images"])
    for i in res["images"]:                           # shown at natural size: text stays as drawn (>= 11 px)
        assert abs(i["shown"] - i["natural"]) <= 4, i
    assert [p["id"] for p in res["plots"]] == list(TS_IDS)
    for p in res["plots"]:
        assert p["plot"], p["id"]
        assert all(n > 0 for _, n in p["series"]), p
        assert p["ink"] > p["inkHidden"] + 200, p     # the series themselves were drawn
        assert any(v not in ("", "–") for v in p["legend"][1:]), p    # hover shows values
        assert all(int(re.search(r"(\d+)px", f).group(1)) >= 12 for f in p["fonts"]), p
    assert [p.get("bandBetween") for p in res["plots"]] == [None, None, "gap", "gap", "gap"]
    zmin, zmax, want_min, want_max = res["zoomSync"]
    assert zmin == pytest.approx(want_min) and zmax == pytest.approx(want_max)
    assert {a["name"] for a in res["links"]} == {"report_aligned.csv", "report_summary.csv", "report_plateaus_a.csv",
                                                 "report_plateaus_b.csv", "report_verdicts_side_by_side.csv"}
    assert all(a["href"].startswith("data:text/csv") for a in res["links"])
    assert res["resources"] == []


def test_a_new_plot_and_table_are_one_function_each(tmp_path, monkeypatch):
    """Behaviour: a block function added to ``layout.PAGE`` is on the page, its grid trace becomes a
    column of the aligned CSV, its table gets a CSV; in Chromium it draws (with a shaded interval)
    without an error."""
    from gerotor_twin.report import layout
    from gerotor_twin.report.panels import Column, Interval, Table, TimeSeries, Trace
    from gerotor_twin.units import rad_s_to_rpm

    def ts_extra(ctx):
        return TimeSeries("ts-extra", "Extra", "doubled speed [rpm]",
                          (Trace("2 × speed", ctx.grid.t, 2 * rad_s_to_rpm(ctx.grid.omega),
                                 csv="doubled speed [rpm]"),),
                          intervals=(Interval(2.0, 4.0, "alarm"),))

    def tab_extra(ctx):
        return Table("tab-extra", "Extra", (Column("k", "{:d}"), Column("v [-]")), ((1, 0.5), (2, 0.25)),
                     "extra.csv")

    monkeypatch.setattr(layout, "PAGE", layout.PAGE + [ts_extra, tab_extra])
    out = tmp_path / "r.html"
    res = build_report(write_bench(tmp_path / "b.mcap"), [write_twin(tmp_path / "t.mcap")], out,
                       csv_dir=tmp_path / "csv")
    assert res["interactive_plots"] == len(TS_IDS) + 1 and "extra.csv" in res["downloads"]
    assert (tmp_path / "csv" / "extra.csv").read_text() == "k,v [-]\n1,0.500\n2,0.250\n"
    rows = list(csv.DictReader(open(tmp_path / "csv" / "r_aligned.csv")))
    assert all(float(r["doubled speed [rpm]"]) == pytest.approx(2 * float(r["speed [rpm]"]), rel=1e-5) for r in rows)
    if _chromium():
        probe = run_probe(out, tmp_path)
        assert probe["errors"] == []
        extra = [p for p in probe["plots"] if p["id"] == "ts-extra"][0]
        assert extra["plot"] and extra["ink"] > extra["inkHidden"] + 200
