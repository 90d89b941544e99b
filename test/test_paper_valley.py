"""Issue 13 §3: the calibration valley and the tests that pin the argument about the paper's MM gain.

The recorded valley is ``docs/valley.json`` (``gerotor-twin paper calibrate --valley --json``);
the tests recompute what they assert from it (golden tier for the recorded lateral clearances,
behaviour/closed form for the rest), and the paper's own tables (literature tier).
"""
import json
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest

from gerotor_twin.cli import main
from gerotor_twin.config import MicroMotion
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady
from gerotor_twin.paper.calibration import evaluate, acceptance
from gerotor_twin.paper.efficiency import with_clearances
from gerotor_twin.paper.reference import PAPER_EFFICIENCY, PRESSURES_BAR, SPEEDS_RPM
from gerotor_twin.paper.setting import paper_setting
from gerotor_twin.paper.valley import closed_paths, loss_split, mm_minus_fixed

VALLEY = Path(__file__).resolve().parents[1] / "docs" / "valley.json"
CHECKED_DELTAS_UM = (18.0, 31.4, 60.0, 80.0, 100.0)      # ends, calibrated point, where the gain grows


def _paper_gain(rpm, bar):
    i = PRESSURES_BAR.index(bar)
    return 100 * (PAPER_EFFICIENCY[("mobility", rpm)][i] - PAPER_EFFICIENCY[("fixed", rpm)][i])


@pytest.fixture(scope="module")
def valley_rows():
    rows = {round(r["tooth_tip_m"] * 1e6, 1): r for r in json.loads(VALLEY.read_text())["rows"]}
    assert set(CHECKED_DELTAS_UM) <= set(rows)
    return rows


def test_paper_rows_are_linear_in_pressure():
    """Literature: every row of tables 3–5 is a straight line in pressure to its 0.01 % rounding (residual
    ≤ 0.01 pt), except one point, the fixed row at 2000 rpm / 10 bar (0.80 pt below the line)."""
    p = np.array(PRESSURES_BAR)
    for (model, rpm), row in PAPER_EFFICIENCY.items():
        y = 100 * np.array(row)
        keep = np.ones(p.size, bool)
        if (model, rpm) == ("fixed", 2000.0):
            keep[PRESSURES_BAR.index(10.0)] = False
        res = y - np.polyval(np.polyfit(p[keep], y[keep], 1), p)
        assert np.all(np.abs(res[keep]) <= 0.01), (model, rpm, res)
        if not keep.all():
            assert res[~keep][0] == pytest.approx(-0.80, abs=0.01)


def test_paper_gain_has_a_pressure_independent_part():
    """Literature: the paper's MM − fixed extrapolates to 1.22 / 1.61 / 1.36 pt at zero pressure (1000 / 2000 /
    3000 rpm) and its 5-bar value is ≥ 70 % of its 27.5-bar value: a gain that does not vanish with Δp."""
    p = np.array(PRESSURES_BAR)
    for rpm in SPEEDS_RPM:
        gain = np.array([_paper_gain(rpm, b) for b in PRESSURES_BAR])
        keep = np.ones(p.size, bool)
        if rpm == 2000.0:
            keep[PRESSURES_BAR.index(10.0)] = False          # the fixed-row outlier
        assert np.polyval(np.polyfit(p[keep], gain[keep], 1), 0.0) > 1.2
        assert _paper_gain(rpm, 5.0) / _paper_gain(rpm, 27.5) > 0.7


@pytest.mark.parametrize("rule", ["rotate", "none"])
def test_tip_conductance_zero_gives_mm_equal_fixed(cfg, valley_rows, rule):
    """Closed form: with the tooth-tip flow switched off (and nominal chamber volumes) nothing the gear's motion
    changes reaches the chambers, so MM − fixed is exactly 0 — at δ = 100 µm, where the gaps matter most."""
    row = valley_rows[100.0]
    c = with_clearances(paper_setting(cfg), row["tooth_tip_m"], row["lateral_m"])   # the valley is eq. (23)'s
    c = replace(c, micro_motion=MicroMotion(fixed_centre_contact=rule, chamber_volumes="nominal"))
    for rpm, bar in ((1000.0, 27.5), (3000.0, 5.0)):
        eta = [run_steady(closed_paths(PumpModel(c, m), tips=True), rpm, bar).volumetric_efficiency
               for m in ("fixed", "mobility")]
        assert eta[1] - eta[0] == 0.0, eta
    # with the tips open the same pair differs (the test above can fail)
    assert abs(mm_minus_fixed(c, 1000.0, 27.5, rule)) > 1.0


@pytest.mark.slow
@pytest.mark.parametrize("delta_um", CHECKED_DELTAS_UM)
def test_gap_driven_gain_at_5_bar_stays_far_below_the_papers(cfg, valley_rows, delta_um):
    """Behaviour: along the valley (the recorded lateral clearance still meets ±2 pt / slopes ±10 %), the MM gain
    the gaps can give at 5 bar is at least 0.5 pt below the paper's at every speed (measured ≤ 0.79 pt at
    1000 rpm, ≤ 0.12 pt at 2000 and < 0 at 3000 rpm; the issue's '≤ 0.5 pt' holds up to δ = 90 µm), and where
    the 27.5-bar gain is large (≥ 1 pt) the 5-bar gain is ≤ 30 % of it (paper: ≥ 70 %): a gap-driven gain
    scales with Δp; the paper's needs a pressure-independent term."""
    row = valley_rows[delta_um]
    c = with_clearances(paper_setting(cfg), row["tooth_tip_m"], row["lateral_m"])   # the valley is eq. (23)'s
    fit = evaluate(c, row["tooth_tip_m"], row["lateral_m"])
    assert acceptance(fit["points"], fit["slopes"])["passed"]
    for rule in ("rotate", "none"):
        for rpm in SPEEDS_RPM:
            g5 = mm_minus_fixed(c, rpm, 5.0, rule)
            assert g5 <= _paper_gain(rpm, 5.0) - 0.5, (rule, rpm, g5)
            g27 = mm_minus_fixed(c, rpm, 27.5, rule)
            if g27 >= 1.0:
                assert g5 <= 0.3 * g27, (rule, rpm, g5, g27)


def test_loss_split_adds_up(cfg):
    """Behaviour: the five paths and their interaction make the lost points; drain and suction–delivery are
    the line conductances × Δp (closed form of the imposed delivery pressure)."""
    ls = loss_split(cfg, 1000.0, 27.5)
    m = PumpModel(cfg, "fixed")
    qth = m.theoretical_flow(2 * np.pi * 1000.0 / 60.0)
    dp = 27.5e5 + cfg.fluid.atmospheric_pa - cfg.boundary.suction_pressure_pa
    assert ls["drain"] == pytest.approx(100 * m.kernel.pc.g_drain * dp / qth, rel=1e-9)
    assert ls["suction_delivery"] == pytest.approx(100 * m.kernel.pc.g_suction_delivery * dp / qth, rel=1e-9)
    assert all(ls[k] > 0 for k in ("drain", "lateral", "suction_delivery", "tips", "filling"))
    assert abs(ls["interaction"]) < 0.1 * ls["lost"]


def test_valley_cli_prints_the_three_tables(capsys, tmp_path):
    """Behaviour: `paper calibrate --valley` for one δ: fit, loss split, MM − fixed; progress on stderr; JSON."""
    out = tmp_path / "v.json"
    assert main(["paper", "calibrate", "--valley", "--deltas", "31.4", "--json", str(out)]) == 0
    cap = capsys.readouterr()
    for head in ("fit to the fixed-centre rows", "lost points by path", "MM − fixed [pt]"):
        assert head in cap.out
    assert "refitting the lateral clearance" in cap.err
    rows = json.loads(out.read_text())["rows"]
    assert len(rows) == 1 and rows[0]["passed"]


@pytest.mark.parametrize("bad", ["abc", "0", "31.4,600"])
def test_valley_cli_rejects_bad_deltas(capsys, bad):
    """Bad input: one line naming --deltas, exit status 2."""
    assert main(["paper", "calibrate", "--valley", "--deltas", bad]) == 2
    assert "--deltas" in capsys.readouterr().err
