"""The HTML report: self-contained, every figure present, JSON metrics, rendered by headless Chromium."""
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
from report_helpers import T0, write_bench, write_twin

FIG_IDS = ("fig-operating", "fig-flow", "fig-eta-map", "fig-waveform", "fig-trajectory", "fig-gaps")


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
    out, _, _ = report
    page = out.read_text()
    for fid in FIG_IDS:
        assert re.search(rf'id="{fid}" alt="[^"]*" src="data:image/png;base64,[A-Za-z0-9+/=]{{200,}}"', page), fid
    assert "src=\"http" not in page and "<link" not in page
    assert page.count("<table class='metrics'>") == 2        # one metrics table per twin


def test_json_metrics(report):
    _, res, _ = report
    assert len(res["plateaus"]) == 2 and res["figures_drawn"] == 6
    a, b = res["twins"]
    assert (a["label"], b["label"]) == ("A", "B")
    assert a["overall"]["flow_error_m3s"]["bias"] == pytest.approx(1e-5, rel=0.03)
    assert b["overall"]["flow_error_m3s"]["bias"] == pytest.approx(-2e-5, rel=0.03)
    assert set(a["plateaus"][0]) >= {"rpm", "bar", "flow_measured_m3s", "flow_predicted_m3s", "eta_measured",
                                      "eta_predicted", "flow_error_m3s", "eta_error"}


def test_missing_optional_topic_drops_only_its_figure(tmp_path):
    b = write_bench(tmp_path / "b.mcap")
    t = write_twin(tmp_path / "t.mcap", waveforms=False)
    res = build_report(b, [t], tmp_path / "r.html")
    page = (tmp_path / "r.html").read_text()
    assert res["figures_drawn"] == 5 and 'id="fig-waveform-missing"' in page
    assert "/twin/chamber_waveform" in page


def test_gap_profile_is_physical(tmp_path):
    cfg = load_config()
    tw = load_twin(write_twin(tmp_path / "t.mcap"), T0)
    ang = np.radians(np.arange(0, 360, 5.0))
    h = gap_profile(tw, Plateau(1, 0, 1, 1.0, 5.0, 1000, 10), cfg, ang)
    assert h.shape == (ang.size, cfg.gears.chambers)
    assert np.all(h >= 0) and np.all(h.min(axis=1) < 1e-7)       # one lobe in contact at every angle
    assert h.max() < 2 * cfg.gears.eccentricity


CHECK_JS = """<script>
window.addEventListener('load', () => {
  const imgs = [...document.querySelectorAll('img.report-figure')];
  const ok = imgs.filter(i => i.complete && i.naturalWidth > 100 && i.naturalHeight > 100);
  document.body.setAttribute('data-figures', imgs.length + '/' + ok.length);
});
</script></body>"""


def _chromium():
    return shutil.which("chromium") or shutil.which("chromium-browser")


@pytest.mark.skipif(_chromium() is None, reason="Debian package chromium not installed (make test installs it)")
def test_headless_chromium_renders_every_figure(report):
    out, _, d = report
    probe = d / "probe.html"
    probe.write_text(out.read_text().replace("</body>", CHECK_JS))
    cmd = [_chromium(), "--headless", "--no-sandbox", "--disable-gpu", "--disable-dev-shm-usage",
           "--virtual-time-budget=5000", "--dump-dom", probe.as_uri()]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    m = re.search(r'data-figures="(\d+)/(\d+)"', r.stdout)
    assert m, r.stderr[-2000:]
    assert m.group(1) == m.group(2) == str(len(FIG_IDS))
