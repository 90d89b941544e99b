"""Header-stamp checks (gerotor_twin.twin.stamps) and their effect in the twin core: one bad sample never
blocks good ones; zero stamps counted and reported.  ROS-free.  Tier: behaviour."""
import math

import pytest

from gerotor_twin.io import messages as m
from gerotor_twin.twin import TwinCore, TwinSettings
from gerotor_twin.twin.stamps import REBASE, RESTART, StampGuard

MS = 1_000_000
S = 1_000_000_000
W = 2000 * math.pi / 30
PD = 101325.0 + 20e5


def stream(guard, t0_ms, n, *, step_ms=5, offset_ms=0, latency_ms=1):
    """n good samples: stamp = t + offset, received latency later; returns the verdicts."""
    out = []
    for k in range(n):
        t = (t0_ms + k * step_ms) * MS
        v = guard.check(t + offset_ms * MS, t + latency_ms * MS)
        if v in (None, RESTART, REBASE):
            guard.accept(t + offset_ms * MS, t + latency_ms * MS, v)
        out.append(v)
    return out


def test_single_future_stamp_rejected_alone():
    """The issue's case: one sample 0.9 s ahead (below stamp_restart_s); the next good ones all pass."""
    g = StampGuard(restart_ns=1 * S, ahead_ns=500 * MS)
    assert stream(g, 0, 100) == [None] * 100
    t = 500 * MS
    assert g.check(t + 900 * MS, t) == "future_stamp"
    assert stream(g, 500, 200) == [None] * 200          # 1 s of good samples: none blocked


def test_constant_clock_offset_is_not_ahead():
    """A bench clock 10 s ahead of the twin's is an offset, not a fault."""
    g = StampGuard(restart_ns=1 * S, ahead_ns=100 * MS)
    assert stream(g, 0, 50, offset_ms=10_000) == [None] * 50


def test_first_sample_glitch_costs_at_most_rebase_minus_one():
    g = StampGuard(restart_ns=1 * S, ahead_ns=500 * MS, rebase_after=3)
    g.accept(900 * MS, 0)                                # the very first sample is 0.9 s ahead: nothing to compare
    v = stream(g, 5, 50)
    assert v[:3] == ["out_of_order_stamp", "out_of_order_stamp", REBASE] and v[3:] == [None] * 47
    assert g.rebases == 1


def test_small_glitch_accepted_then_stream_reanchors():
    """A stamp ahead by less than the tolerance slips in; the good stream re-anchors after 3 samples."""
    g = StampGuard(restart_ns=1 * S, ahead_ns=500 * MS, rebase_after=3)
    stream(g, 0, 20)
    g.accept(100 * MS + 300 * MS, 100 * MS)
    v = stream(g, 105, 100)
    assert v.count("out_of_order_stamp") == 2 and v[2] == REBASE and v[3:] == [None] * 97


def test_source_clock_jump_forward_rebases():
    g = StampGuard(restart_ns=1 * S, ahead_ns=200 * MS, rebase_after=3)
    stream(g, 0, 20)
    v = stream(g, 100, 20, offset_ms=5000)               # source clock stepped 5 s forward and stays there
    assert v[:3] == ["future_stamp", "future_stamp", REBASE] and v[3:] == [None] * 17


def test_two_interleaved_clocks_never_rebase():
    """A second source 2 s ahead, interleaved sample by sample: its samples stay rejected, the first's pass."""
    g = StampGuard(restart_ns=1 * S, ahead_ns=200 * MS, rebase_after=3)
    stream(g, 0, 10)
    verdicts = []
    for k in range(100):
        t = (50 + 5 * k) * MS
        for off in (0, 2 * S):
            v = g.check(t + off, t + MS)
            if v in (None, RESTART, REBASE):
                g.accept(t + off, t + MS, v)
            verdicts.append((off, v))
    assert all(v is None for off, v in verdicts if off == 0)
    assert all(v == "future_stamp" for off, v in verdicts if off)


def test_sim_clock_steps_creep_without_rejection():
    """/clock in 200 ms steps (replay at 10x, 50 Hz clock): stamps run ahead of the clock by up to one step."""
    g = StampGuard(restart_ns=1 * S, ahead_ns=500 * MS)
    verdicts = []
    for k in range(400):                                 # 5 ms samples, clock = last 200 ms step
        stamp = k * 5 * MS
        recv = (stamp // (200 * MS)) * 200 * MS
        v = g.check(stamp, recv)
        if v in (None, RESTART, REBASE):
            g.accept(stamp, recv, v)
        verdicts.append(v)
    assert verdicts == [None] * 400


def test_restart_and_duplicate_unchanged():
    g = StampGuard(restart_ns=1 * S, ahead_ns=500 * MS)
    g.accept(5 * S, 5 * S)
    assert g.check(5 * S, 5 * S + 1) == "duplicate_stamp"
    assert g.check(5 * S - 10 * MS, 5 * S + 2) == "out_of_order_stamp"
    assert g.check(1 * S, 5 * S + 3) == RESTART


# --------------------------------------------------------------------------- in the core
@pytest.fixture(scope="module")
def model():
    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    return PumpModel(load_config(), "fixed")


def test_core_future_stamp_does_not_hold_the_model(model):
    """Behaviour: before the fix the next 0.9 s of good speed samples were rejected and the model held."""
    core = TwinCore(model, TwinSettings(stale_timeout_s=0.1))
    accepted = []
    for k in range(400):                                 # 2 s at 200 Hz
        t = k * 5 * MS
        if k == 100:
            assert core.add_sample("shaft_speed", W, t + 900 * MS, t) is False
        accepted.append(core.add_sample("shaft_speed", W, t, t))
        core.add_sample("delivery_pressure", PD, t, t)
        core.tick(t)
        if k > 20:
            assert core.status == "running", (k, core.snapshot(t)["reason"])
    assert all(accepted)
    rep = core.input_report(2 * S)["shaft_speed"]
    assert rep["rejected"]["future_stamp"] == 1 and rep["rejected"]["out_of_order_stamp"] == 0
    assert "ahead" in rep["last_error"] and "shaft_speed.header.stamp" in rep["last_error"]


def test_core_zero_stamps_counted_and_reported(model):
    core = TwinCore(model)
    for k in range(50):
        t = k * 5 * MS
        core.add_message("shaft_speed", m.joint_state(0, name=["s"], velocity=[W]), t)
        core.add_sample("delivery_pressure", PD, t + MS, t)      # stamped (not 0 at k = 0)
        core.tick(t)
    rep = core.input_report(250 * MS)["shaft_speed"]
    assert rep["zero_stamps"] == 50 and rep["accepted"] == 50
    assert any("header stamp 0" in text for _, text in core.pop_events())
    st = core.diagnostics(250 * MS)["status"][1]
    values = {kv["key"]: kv["value"] for kv in st["values"]}
    assert st["level"] == m.DIAG_WARN and "stamps = 0" in st["message"]
    assert values["shaft_speed.zero_stamps"] == "50" and values["delivery_pressure.zero_stamps"] == "0"
    st2 = core.diagnostics(1250 * MS)["status"][1]        # none in the next period: no longer WARN for it
    assert "stamps = 0" not in st2["message"]


def test_lone_stale_sample_taken_as_restart_does_not_block():
    """A single sample stamped 5 s in the past is taken as a source restart (accepted, counted);
    the good stream that follows is newer than it and is accepted without a single rejection."""
    g = StampGuard(restart_ns=1 * S, ahead_ns=500 * MS)
    stream(g, 10_000, 100)
    t = 10_500 * MS
    assert g.check(t - 5 * S, t) == RESTART
    g.accept(t - 5 * S, t, RESTART)
    assert stream(g, 10_500, 200) == [None] * 200 and g.restarts == 1
