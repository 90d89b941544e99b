"""Acceptance criterion of the report: per-plateau verdicts, options, file, errors, ``--check``, two twins side by
side."""
import csv

import pytest

from gerotor_twin.cli import build_parser, main
from gerotor_twin.errors import InputError
from gerotor_twin.report.acceptance import AcceptanceCriterion, criterion_from_args, verdict
from gerotor_twin.report.build import build_report
from report_helpers import write_bench, write_twin

LPM = 6e4


def _row(q_m_lpm, q_p_lpm, eta_m, eta_p, n=20, bins=20):
    return {"flow_measured_m3s": q_m_lpm / LPM, "flow_predicted_m3s": None if q_p_lpm is None else q_p_lpm / LPM,
            "eta_measured": eta_m, "eta_predicted": eta_p, "bins": bins,
            "flow_error_m3s": {"n": n}}


def test_flow_tolerance_closed_form():
    """Closed form: tolerance = 0.2 L/min + 1 % of 60 L/min = 0.8 L/min (defaults)."""
    c = AcceptanceCriterion()
    assert c.flow_tolerance_m3s(60 / LPM) * LPM == pytest.approx(0.8)
    assert verdict(_row(60, 60.79, 0.9, 0.9), c)["verdict"] == "pass"
    v = verdict(_row(60, 60.81, 0.9, 0.9), c)
    assert v["verdict"] == "fail" and v["failed"] == ["flow"] and "±0.800" in v["reasons"][0]
    assert verdict(_row(60, 59.21, 0.9, 0.9), c)["verdict"] == "pass"       # symmetric


def test_eta_tolerance_and_both_checks():
    """Closed form: |Δη| <= 1.0 point by default; each failing check is named."""
    c = AcceptanceCriterion()
    assert verdict(_row(60, 60, 0.90, 0.9099), c)["verdict"] == "pass"
    assert verdict(_row(60, 60, 0.90, 0.9101), c)["failed"] == ["η"]
    assert verdict(_row(60, 62, 0.90, 0.93), c)["failed"] == ["flow", "η"]


def test_no_data_and_disabled_checks():
    """Behaviour: too few predicted bins give 'no data'; 'off' tolerances are not checked."""
    c = AcceptanceCriterion()
    assert verdict(_row(60, 60, 0.9, 0.9, n=15, bins=20), c)["verdict"] == "no data"    # 75 % < 80 %
    assert verdict(_row(60, 60, 0.9, 0.9, n=16, bins=20), c)["verdict"] == "pass"
    assert verdict(_row(60, None, 0.9, None), c)["verdict"] == "no data"
    off = AcceptanceCriterion(flow_abs_lpm=None, flow_rel=None, eta_pts=None)
    assert verdict(_row(60, 90, 0.5, 0.99), off)["verdict"] == "pass"
    only_rel = AcceptanceCriterion(flow_abs_lpm=None)          # one part off -> 0, the other stays
    assert only_rel.flow_tolerance_m3s(60 / LPM) * LPM == pytest.approx(0.6)


def _args(*extra):
    return build_parser().parse_args(["report", "--bench", "b", "--twin", "t", "-o", "r.html", *extra])


def test_options_file_and_precedence(tmp_path):
    """Behaviour: defaults < --acceptance file < single options; 'off' disables."""
    f = tmp_path / "acc.yaml"
    f.write_text("acceptance:\n  flow_abs_lpm: 9\n  eta_pts: 2.5\n  min_fraction: 0.5\n")
    c = criterion_from_args(_args("--acceptance", str(f), "--tol-flow-lpm", "0.5", "--tol-flow-rel", "off"))
    assert (c.flow_abs_lpm, c.flow_rel, c.eta_pts, c.min_fraction) == (0.5, 0.0, 2.5, 0.5)
    assert criterion_from_args(_args()) == AcceptanceCriterion()
    assert criterion_from_args(_args("--tol-eta-pts", "off")).eta_pts is None


def test_bad_tolerances_name_field_value_and_range(tmp_path):
    """Bad input: a clear one-line error naming the option, the value and the allowed range."""
    with pytest.raises(InputError, match=r"--tol-eta-pts.*-1.*>= 0"):
        criterion_from_args(_args("--tol-eta-pts", "-1"))
    with pytest.raises(InputError, match=r"--tol-flow-lpm.*abc"):
        criterion_from_args(_args("--tol-flow-lpm", "abc"))
    with pytest.raises(InputError, match=r"min_fraction.*1.5.*\[0, 1\]"):
        criterion_from_args(_args("--min-predicted-fraction", "1.5"))
    f = tmp_path / "acc.yaml"
    f.write_text("eta_pt: 1\n")
    with pytest.raises(InputError, match=r"eta_pt.*unknown key"):
        criterion_from_args(_args("--acceptance", str(f)))
    with pytest.raises(InputError, match="--acceptance"):
        criterion_from_args(_args("--acceptance", str(tmp_path / "missing.yaml")))


def test_cli_verdicts_and_check_exit_status(tmp_path, capsys):
    """Behaviour: a twin 0.6 L/min (2.6-2.8 η points) off fails the defaults, passes loose tolerances;
    ``--check`` turns a failure into exit status 1; a bad option is exit status 2, one line."""
    b = write_bench(tmp_path / "b.mcap")
    t = write_twin(tmp_path / "t.mcap", offset_m3s=1e-5)
    base = ["report", "--bench", str(b), "--twin", str(t), "-o", str(tmp_path / "r.html")]
    assert main(base + ["--check"]) == 1
    assert "0 pass, 2 fail" in capsys.readouterr().out
    assert main(base) == 0                                   # without --check: the verdict is only reported
    assert main(base + ["--check", "--tol-flow-lpm", "0.7", "--tol-eta-pts", "3"]) == 0
    assert "2 pass, 0 fail" in capsys.readouterr().out
    assert main(base + ["--tol-eta-pts", "x"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "--tol-eta-pts" in err and len(err.strip().splitlines()) == 1
    assert main(base + ["--flow-sensor-tau", "-0.5"]) == 2
    err = capsys.readouterr().err
    assert "--flow-sensor-tau" in err and "[0, 60] s" in err and len(err.strip().splitlines()) == 1
    assert main(base + ["--flow-sensor-tau", "0.2"]) == 0    # the lag noted, the verdict still reported
    assert "through a first-order lag of 0.2 s" in capsys.readouterr().err


def test_two_twins_verdicts_side_by_side(tmp_path):
    """Behaviour: a report of a nominal twin (0.6 L/min high) and a calibrated one (exact) over the same bench
    recording leads its headline with both verdict sets in one line, and shows them side by side in one table
    (page and CSV); a single twin keeps its one headline line and gets no such table."""
    b = write_bench(tmp_path / "b.mcap")
    nominal = write_twin(tmp_path / "nominal.mcap", offset_m3s=1e-5)
    calibrated = write_twin(tmp_path / "calibrated.mcap", offset_m3s=0.0)
    res = build_report(b, [nominal, calibrated], tmp_path / "r.html", labels=["nominal", "calibrated"],
                       csv_dir=tmp_path / "csv")
    assert res["headline"][0] == "2 plateaus — nominal: 0 pass, 2 fail; calibrated: 2 pass, 0 fail"
    assert res["headline"][1].startswith("nominal: 2 plateaus: 0 pass, 2 fail;")
    assert res["headline"][2].startswith("calibrated: 2 plateaus: 2 pass, 0 fail;")
    page = (tmp_path / "r.html").read_text()
    assert "2 plateaus — nominal: 0 pass, 2 fail; calibrated: 2 pass, 0 fail" in page
    table = page[page.index("id='tab-compare'"):]
    table = table[:table.index("</table>")]
    assert "verdict nominal" in table and "verdict calibrated" in table
    assert table.count("verdict-fail'>FAIL (") == 2 and table.count("verdict-pass'>PASS<") == 2
    with open(tmp_path / "csv" / "r_verdicts_side_by_side.csv") as f:
        rows = list(csv.DictReader(f))
    assert [(r["verdict nominal"], r["verdict calibrated"]) for r in rows] == [("FAIL (flow, η)", "PASS"),
                                                                              ("FAIL (η)", "PASS")]
    assert [float(r["flow nominal [L/min]"]) - float(r["flow calibrated [L/min]"]) for r in rows] == \
        pytest.approx([0.6, 0.6], abs=0.02)
    one = build_report(b, [nominal], tmp_path / "one.html", labels=["nominal"])
    assert one["headline"][0].startswith("nominal: 2 plateaus: 0 pass, 2 fail;")
    assert "tab-compare" not in (tmp_path / "one.html").read_text()
