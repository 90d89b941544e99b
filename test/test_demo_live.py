"""``make demo`` (gerotor_twin.ros.demo_live): what it prints about the nominal and the calibrated twin."""
import os
import re
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from gerotor_twin.report.build import build_report
from gerotor_twin.ros.domain import claim_domain
from gerotor_twin.ros.demo_live import Background, build_parser, calibration_note, labels, plateau_lines
from report_helpers import write_bench, write_twin

ROOT = Path(__file__).resolve().parents[1]


def test_plateau_lines_show_both_twins_and_their_verdicts(tmp_path):
    """Behaviour: from a report of a nominal twin (0.6 L/min high) and a calibrated one (exact), the demo prints
    per plateau the measured, the nominal and the calibrated flow and both verdicts, then the headline with
    both verdict sets side by side."""
    b = write_bench(tmp_path / "b.mcap")
    logs = [write_twin(tmp_path / "nominal.mcap", offset_m3s=1e-5), write_twin(tmp_path / "cal.mcap", offset_m3s=0.0)]
    res = build_report(b, logs, tmp_path / "r.html", labels=labels(build_parser().parse_args([])))
    lines = plateau_lines(res)
    assert lines[0].startswith("  plateau: speed, pressure | flow [L/min] measured, nominal, calibrated from bench_map")
    assert len(lines) == 3
    first = lines[1]
    assert first.startswith("  plateau 1:   1000 rpm  10.0 bar | flow ") and first.endswith("| fail, pass")
    measured, nominal, calibrated = (float(x) for x in first.split("| flow ")[1].split(" |")[0].split(","))
    assert round(nominal - measured, 2) == 0.6 and round(calibrated - measured, 2) == 0.0
    assert lines[2].endswith("| fail, pass")
    assert res["headline"][0] == "2 plateaus — nominal: 0 pass, 2 fail; calibrated from bench_map: 2 pass, 0 fail"


def test_calibration_note_and_labels():
    """Behaviour: the demo says what a calibrated pump file's own calibration block says (recording, plateaus,
    fitted factor with its interval, efficiency RMSE before and after), shown on the shipped fit of the map
    recording; a file without such a block is named as such; the labels name the calibration's source."""
    note = calibration_note(ROOT / "bags" / "pump_fitted_bench_map.yaml")
    assert note.startswith("bags/bench_map.mcap, 12 plateaus: ") and " x 1.09" in note and "95 % CI" in note
    assert "eta_v RMSE 6.98 -> 0.04 %-pt" in note
    assert calibration_note(ROOT / "config" / "pump.yaml").endswith("pump.yaml: no calibration block")
    assert labels(build_parser().parse_args([])) == ["nominal", "calibrated from bench_map"]
    assert labels(build_parser().parse_args(["--calibrated", "bags/pump_fitted_bench_map.yaml"]))[1] == \
        "calibrated from pump_fitted_bench_map"


def test_calibration_note_says_the_prediction_interval_and_a_refusal(tmp_path):
    """Behaviour: a calibration block with a prediction interval and a refused verdict (nominal values kept)
    gives both in the note, the factor's interval called a parameter interval."""
    p = tmp_path / "fitted.yaml"
    p.write_text(yaml.safe_dump({"calibration": {
        "bags": ["b.mcap"], "plateaus": 9, "fitted_combinations": [
            {"combination": "ln(lateral)", "factor": 1.2, "factor_ci95": [1.19, 1.21]}],
        "prediction_interval": {"eta_half_width_twin": 0.0123},
        "verdict": {"calibrated": False, "message": "calibration refused: ..."}}}))
    note = calibration_note(p)
    assert "(parameter 95 % CI 1.1900-1.2100)" in note
    assert "eta_v predicted +- 1.23 %-pt (95 %, model form included)" in note
    assert note.endswith("calibration refused: the nominal values kept")


def test_background_steps_stop_at_a_failure_and_on_cancel(tmp_path):
    """Behaviour: the background commands run in order at low priority; the first failure stops the chain and
    is named; cancel ends a running command at once (no calibration left running after a failed node)."""
    py = sys.executable
    bg = Background([("ok", [py, "-c", "import os; print(os.nice(0))"], tmp_path / "ok.log"),
                     ("bad", [py, "-c", "raise SystemExit(3)"], tmp_path / "bad.log"),
                     ("never", [py, "-c", "pass"], tmp_path / "never.log")])
    bg.start()
    bg.join(60)
    assert bg.failed == "bad" and not (tmp_path / "never.log").exists()
    assert int((tmp_path / "ok.log").read_text()) >= 10
    slow = Background([("sleep", [py, "-c", "import time; time.sleep(60)"], tmp_path / "sleep.log")])
    slow.start()
    time.sleep(1.0)
    t0 = time.monotonic()
    slow.cancel()
    assert time.monotonic() - t0 < 10 and slow.failed == "sleep" and not slow.is_alive()


@pytest.mark.slow
def test_make_demo_end_to_end(tmp_path):
    """Behaviour (real processes: node, replay over DDS, calibrate, run-bag; ≈ 1 min): ``make demo``'s job
    calibrates on the map recording (the emulated pump's clearance factor, 1.1, inside the fit's interval),
    prints both twins' verdicts side by side, the calibrated twin passing every plateau and the nominal one
    failing some, and writes one report with both twins."""
    env = dict(os.environ, GEROTOR_TWIN_DEMO_DOMAIN=str(claim_domain()))
    run = subprocess.run([sys.executable, "-m", "gerotor_twin.ros.demo_live", "--out", str(tmp_path)], cwd=ROOT,
                         env=env, capture_output=True, text=True, timeout=400)
    assert run.returncode == 0, run.stdout[-2000:] + run.stderr[-2000:]
    lines = run.stdout.splitlines()
    head = [ln for ln in lines if ln.startswith("demo: 4 plateaus — ")]
    assert len(head) == 1, run.stdout[-2000:]
    assert re.fullmatch(r"demo: 4 plateaus — nominal: \d pass, [1-4] fail(, \d no data)?; "
                        r"calibrated from bench_map: 4 pass, 0 fail", head[0]), head[0]
    lo, hi = (float(x) for x in re.search(r"95 % CI (\d\.\d+)-(\d\.\d+)", run.stdout).groups())
    assert lo <= 1.1 <= hi
    fit = yaml.safe_load((tmp_path / "pump_fitted.yaml").read_text())
    assert fit["calibration"]["bags"] == ["bags/bench_map.mcap"]
    page = (tmp_path / "report.html").read_text()
    assert "id='tab-compare'" in page and "verdict calibrated from bench_map" in page


def test_an_output_directory_under_a_file_is_one_line(tmp_path, capsys):
    """Behaviour: ``make demo``'s ``--out`` below a regular file (``out`` a file in the checkout): one line naming
    the path and why, exit status 2, before any domain is claimed or process started, as every command says it."""
    from gerotor_twin.ros.demo_live import main
    blocker = tmp_path / "out"
    blocker.write_text("not a directory")
    assert main(["--out", str(blocker / "demo")]) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("error: ") and "\n" not in err and str(blocker) in err and "Not a directory" in err, err
    assert blocker.read_text() == "not a directory"
    from gerotor_twin.cli import main as cli                 # the same line from a command of the CLI
    assert cli(["batch", str(ROOT / "bags"), "-o", str(blocker / "fleet"), "--model", "fixed"]) == 2
    assert capsys.readouterr().err.strip() == err.replace(str(blocker / "demo" / "log"), str(blocker / "fleet"))
