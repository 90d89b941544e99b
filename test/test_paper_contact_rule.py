"""Issue 13 §3: the fixed-centre contact rule is a choice (``micro_motion.fixed_centre_contact``)."""
from dataclasses import replace

import numpy as np
import pytest

from gerotor_twin.config import MicroMotion, parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady
from gerotor_twin.paper.gap_pattern import fixed_centre_gap_pattern, gap_pattern


def _with(cfg, rule, volumes="nominal"):
    return replace(cfg, micro_motion=MicroMotion(fixed_centre_contact=rule, chamber_volumes=volumes))


def test_rotate_rule_closes_the_suction_side_and_opens_the_delivery_side(cfg):
    """Behaviour: sec. 3.7 turns the centred gear set to one contact, ≈ 6 µm / 56 µm (issue 13 review) at δ = 31.4 µm."""
    m = PumpModel(_with(cfg, "rotate"), "fixed")
    pat = fixed_centre_gap_pattern(m)
    assert cfg.clearances.tooth_tip_m == pytest.approx(31.4e-6)
    assert 4e-6 < pat["suction_m"] < 9e-6
    assert 50e-6 < pat["delivery_m"] < 62e-6
    # the inner gear is turned by ≈ 1.55 mrad (the figure) and one lobe touches
    turns = [m.gaps(t, (0.0, 0.0))[1] for t in np.linspace(0.0, m.tables.period, 60, endpoint=False)]
    assert 1.4e-3 < np.mean(turns) < 1.7e-3
    assert min(m.gaps(0.3, (0.0, 0.0))[0]) == 0.0


def test_none_rule_keeps_every_gap_at_the_nominal_clearance(cfg):
    """Closed form: centred, unturned gears have every gap equal to δ (the expansion's constant term)."""
    m = PumpModel(_with(cfg, "none"), "fixed")
    for t in np.linspace(0.0, m.tables.period, 25):
        h, gamma, _ = m.gaps(t, (0.0, 0.0))
        assert gamma == 0.0
        np.testing.assert_allclose(h, cfg.clearances.tooth_tip_m, rtol=0, atol=1e-12)
    pat = fixed_centre_gap_pattern(m)
    assert pat["suction_m"] == pytest.approx(cfg.clearances.tooth_tip_m, abs=1e-12)
    assert pat["delivery_m"] == pytest.approx(cfg.clearances.tooth_tip_m, abs=1e-12)


def test_min_open_tooth_gap():
    """Closed form: each row's contact lobe is left out of the minimum; all gaps equal give that gap."""
    from gerotor_twin.model.steady import min_open_gap
    gaps = np.array([[0.0, 5e-6, 9e-6], [7e-6, 0.0, 3e-6], [4e-6, 8e-6, 0.0]])
    assert min_open_gap(gaps, np.array([0, 1, 2])) == 3e-6
    assert min_open_gap(np.full((4, 7), 31.4e-6), np.zeros(4, dtype=int)) == 31.4e-6
    assert np.isnan(min_open_gap(np.zeros((0, 7)), np.zeros(0, dtype=int)))


def test_effective_tooth_gap():
    """Closed form: ⟨h³⟩^(1/3): equal gaps give that gap; gaps 0 and h give h / 2^(1/3)."""
    from gerotor_twin.model.steady import effective_gap
    assert effective_gap(np.full((3, 7), 31.4e-6)) == pytest.approx(31.4e-6, rel=1e-12)
    assert effective_gap(np.array([[0.0, 10e-6]])) == pytest.approx(10e-6 / 2 ** (1 / 3), rel=1e-12)


def test_min_open_tooth_gap_in_the_steady_summary(cfg):
    """Closed form with the none rule (every gap δ); behaviour with the sec. 3.7 rule: one lobe touches
    (min_tooth_gap_m 0) while the open ones stay between 0 and the largest gap."""
    s = run_steady(PumpModel(_with(cfg, "none"), "fixed"), 2000, 10, min_revolutions=1, max_revolutions=3).summary()
    assert s["min_open_tooth_gap_m"] == pytest.approx(cfg.clearances.tooth_tip_m, abs=1e-12)
    assert s["effective_tooth_gap_m"] == pytest.approx(cfg.clearances.tooth_tip_m, rel=1e-9)
    r = run_steady(PumpModel(_with(cfg, "rotate"), "fixed"), 2000, 10, min_revolutions=1, max_revolutions=3)
    s = r.summary()
    assert s["min_tooth_gap_m"] == 0.0
    assert 0.0 < s["min_open_tooth_gap_m"] < s["effective_tooth_gap_m"] < float(r.outputs.gaps.max())


def test_none_rule_leaves_moving_models_on_the_sec_3_7_rule(cfg):
    """Behaviour: the choice is for the fixed centre only; the mobility model still rests on one contact."""
    m = PumpModel(_with(cfg, "none"), "mobility")
    h, gamma, _ = m.gaps(0.3, (0.0, 0.0))
    assert gamma > 1e-3 and min(h) == 0.0


def test_fixed_rotate_has_nearly_the_mobility_gap_pattern(cfg):
    """Behaviour: the reason MM − fixed is small: both models see ≈ the same suction/delivery gaps."""
    c = _with(cfg, "rotate")
    fixed = fixed_centre_gap_pattern(PumpModel(c, "fixed"))
    m = PumpModel(c, "mobility")
    r = run_steady(m, 1000.0, 27.5)
    mob = gap_pattern(m, r.outputs.theta, r.outputs.gaps)
    assert abs(mob["suction_m"] - fixed["suction_m"]) < 3e-6
    assert abs(mob["delivery_m"] - fixed["delivery_m"]) < 5e-6


def test_fixed_models_differ_by_the_rule_in_efficiency(cfg):
    """Behaviour: nominal gaps (none) leak differently from the turned set (rotate); both run and differ."""
    eta = {rule: run_steady(PumpModel(_with(cfg, rule), "fixed"), 1000.0, 27.5).volumetric_efficiency
           for rule in ("rotate", "none")}
    assert all(0.5 < v < 1.0 for v in eta.values())
    assert abs(eta["rotate"] - eta["none"]) > 1e-3


@pytest.mark.parametrize("key,value", [("fixed_centre_contact", "turn"), ("chamber_volumes", "exact"),
                                       ("fixed_centre_contact", 3), ("contact", "none")])
def test_micro_motion_section_rejects_bad_values(cfg, key, value):
    """Bad input: one InputError naming the field and the allowed values."""
    raw = cfg.to_dict()
    raw["micro_motion"] = {key: value}
    with pytest.raises(InputError) as exc:
        parse_config(raw)
    assert "micro_motion" in str(exc.value)


def test_micro_motion_section_is_optional_and_round_trips(cfg):
    """Behaviour: absent section → defaults (rotate, displaced); to_dict → parse gives the same choice."""
    raw = cfg.to_dict()
    raw.pop("micro_motion")
    assert parse_config(raw).micro_motion == MicroMotion()
    raw["micro_motion"] = {"fixed_centre_contact": "none"}
    c = parse_config(raw)
    assert c.micro_motion.fixed_centre_contact == "none"
    assert parse_config(c.to_dict()).micro_motion == c.micro_motion
