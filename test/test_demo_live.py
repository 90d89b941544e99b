"""``make demo`` (gerotor_twin.ros.demo_live): what it prints about the nominal and the calibrated twin."""
from pathlib import Path

from gerotor_twin.report.build import build_report
from gerotor_twin.ros.demo_live import FITTED, LABELS, calibration_note, plateau_lines
from report_helpers import write_bench, write_twin

ROOT = Path(__file__).resolve().parents[1]


def test_plateau_lines_show_both_twins_and_their_verdicts(tmp_path):
    """Behaviour: from a report of a nominal twin (0.6 L/min high) and a calibrated one (exact), the demo prints
    per plateau the measured, the nominal and the calibrated flow and both verdicts, then the headline with
    both verdict sets side by side."""
    b = write_bench(tmp_path / "b.mcap")
    logs = [write_twin(tmp_path / "nominal.mcap", offset_m3s=1e-5), write_twin(tmp_path / "cal.mcap", offset_m3s=0.0)]
    res = build_report(b, logs, tmp_path / "r.html", labels=list(LABELS))
    lines = plateau_lines(res)
    assert lines[0].startswith("  plateau: speed, pressure | flow [L/min] measured, nominal, calibrated from bench_map")
    assert len(lines) == 3
    first = lines[1]
    assert first.startswith("  plateau 1:   1000 rpm  10.0 bar | flow ") and first.endswith("| fail, pass")
    measured, nominal, calibrated = (float(x) for x in first.split("| flow ")[1].split(" |")[0].split(","))
    assert round(nominal - measured, 2) == 0.6 and round(calibrated - measured, 2) == 0.0
    assert lines[2].endswith("| fail, pass")
    assert res["headline"][0] == "2 plateaus — nominal: 0 pass, 2 fail; calibrated from bench_map: 2 pass, 0 fail"


def test_calibration_note_names_the_shipped_fit():
    """Behaviour: the demo says where its calibrated pump file comes from (tool, bag, fitted factor), read from
    the file's own calibration block; a file without one is named as such."""
    note = calibration_note(FITTED)
    assert FITTED == ROOT / "bags" / "pump_fitted_bench_map.yaml"
    assert "fitted by `gerotor-twin calibrate` on bags/bench_map.mcap" in note and "12 plateaus" in note
    assert " x 1.09" in note                      # the common clearance factor, truth 1.1 (bags/README.md)
    assert calibration_note(ROOT / "config" / "pump.yaml").endswith("pump.yaml: no calibration block")
