"""Report provenance: files (dates, hashes), pump config and calibration source, software, model."""
import datetime as dt
import hashlib
import html
import re
import subprocess
from pathlib import Path

import numpy as np
import pytest

from gerotor_twin import __version__
from gerotor_twin.io import McapLog, open_mcap
from gerotor_twin.io import messages as m
from gerotor_twin.io.mcap_log import twin_log_metadata
from gerotor_twin.report.build import build_report
from gerotor_twin.software import SOFTWARE_METADATA, software_identity
from report_helpers import DISP, T0, eta_true, profile, write_bench

PUMP_YAML = Path(__file__).resolve().parents[1] / "config" / "pump.yaml"


def _git_head():
    r = subprocess.run(["git", "-C", str(PUMP_YAML.parent), "rev-parse", "HEAD"], capture_output=True, text=True)
    return r.stdout.strip() if r.returncode == 0 else None


def write_logged_twin(path, duration=12.0):
    """A twin log with the metadata every node / run-bag log gets (twin_log_metadata)."""
    meta = twin_log_metadata(PUMP_YAML.read_text(), str(PUMP_YAML),
                             {"bearing_model": "short", "sample_period_s": 0.005})
    with McapLog(path, overwrite=True, metadata=meta) as log:
        log.add_topic("/twin/flow_summary", m.FLOAT64_MULTIARRAY)
        t = 0.0
        while t < duration:
            w, _ = profile(np.array([t]))
            t += 2 * np.pi / w[0]
            qth = DISP * w[0] / (2 * np.pi)
            q = eta_true(np.array([t]))[0] * qth
            log.write("/twin/flow_summary", m.float64_multiarray([q, qth, qth - q, q / qth], ("summary",)),
                      T0 + int(round(t * 1e9)))
    return path


def test_twin_logs_record_version_and_git_revision(tmp_path):
    """Behaviour: the software record is in every twin log; the revision is git's own answer."""
    f = open_mcap(write_logged_twin(tmp_path / "t.mcap"))
    sw = f.metadata[SOFTWARE_METADATA]
    assert sw["version"] == __version__
    head = _git_head()
    if head:
        assert sw["git_revision"].split("+")[0] == head
    else:
        assert sw["git_revision"].startswith("unknown")
    assert software_identity() == sw


@pytest.fixture(scope="module")
def page(tmp_path_factory):
    d = tmp_path_factory.mktemp("prov")
    b = write_bench(d / "bench.mcap")
    t = write_logged_twin(d / "twin.mcap")
    build_report(b, [t], d / "r.html")
    return html.unescape((d / "r.html").read_text()), b, t


def _row(page, key):
    m = re.search(rf"<tr><td class='l'>{re.escape(key)}</td><td class='l'>(.*?)</td></tr>", page)
    assert m, key
    return m.group(1)


def test_files_dates_and_hashes(page):
    """Golden: the bench start is its first log time in UTC; file hashes are the files' sha256."""
    text, b, t = page
    start = dt.datetime.fromtimestamp(T0 / 1e9, dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S")
    assert _row(text, "bench start (first message)").startswith(start)
    assert hashlib.sha256(Path(b).read_bytes()).hexdigest() in _row(text, "bench file")
    assert hashlib.sha256(Path(t).read_bytes()).hexdigest() in _row(text, "twin file 1")
    assert "600 speed, 600 pressure, 600 flow samples" in _row(text, "bench duration")


def test_pump_software_and_model(page):
    """Behaviour: the logged config, its calibration note, both software identities, the model."""
    text, _, _ = page
    assert str(PUMP_YAML) in _row(text, "pump config 1: twin (short)")
    assert "docs/calibration.json" in _row(text, "calibration source 1")
    sw = software_identity()
    assert f"gerotor_twin {sw['version']}, git {sw['git_revision']}" in _row(text, "twin log 1 written by")
    assert f"git {sw['git_revision']}; uPlot 1.6.32" in _row(text, "report written by")
    assert _row(text, "model 1: twin (short)") == "bearing model short"
    assert "sample_period_s=0.005" in _row(text, "twin parameters 1")
    assert "max_step_deg=" in _row(text, "numerics (config 1)")
