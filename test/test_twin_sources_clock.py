"""More than one publisher on an input topic (gerotor_twin.twin.sources) and a stalled clock
(gerotor_twin.twin.clockwatch); ROS-free.  Tier: behaviour."""
import math

import pytest

from gerotor_twin.io import messages as m
from gerotor_twin.twin import TwinCore, TwinSettings
from gerotor_twin.twin.clockwatch import ClockWatch
from gerotor_twin.twin.sources import SourceTracker

MS = 1_000_000
W = 2000 * math.pi / 30
PD = 101325.0 + 20e5


def test_one_publisher_always_used_even_with_lost_samples():
    tr = SourceTracker(switch_after_ns=250 * MS)
    seqs = [s for s in range(1, 500) if s % 7]          # best effort: every 7th lost
    assert all(tr.observe(s, s * MS) for s in seqs)
    assert tr.sources_seen == 1 and tr.other_samples == 0 and tr.active(499 * MS) == 1


@pytest.mark.parametrize("b_start", [1, 5000])
def test_two_publishers_follow_the_first(b_start):
    """Strict alternation, B started together with A (same numbers) or long before (numbers ahead): A's samples
    used, B's not (B's very first sample, when its numbers are ahead, looks like a jump of A and is used once)."""
    tr = SourceTracker(switch_after_ns=250 * MS)
    used = []
    for k in range(200):
        used.append(("A", tr.observe(1 + k, 2 * k * MS)))
        used.append(("B", tr.observe(b_start + k, (2 * k + 1) * MS)))
    assert all(u for who, u in used if who == "A")
    assert sum(u for who, u in used if who == "B") == (1 if b_start > 1 else 0)
    assert tr.active(400 * MS) == 2 and tr.sources_seen == 2


def test_second_publisher_behind_never_used():
    """B started after A (numbers below A's): none of B's samples is used."""
    tr = SourceTracker(switch_after_ns=250 * MS)
    used = []
    for k in range(200):
        used.append(("A", tr.observe(5000 + k, 2 * k * MS)))
        used.append(("B", tr.observe(1 + k, (2 * k + 1) * MS)))
    assert all(u for who, u in used if who == "A") and not any(u for who, u in used if who == "B")
    assert tr.other_samples == 200 and tr.sources_seen == 2


def test_followed_source_dies_switch_to_the_other():
    tr = SourceTracker(switch_after_ns=250 * MS)
    for k in range(100):                                 # both publish, A followed
        tr.observe(1 + k, 10 * k * MS)
        tr.observe(9000 + k, (10 * k + 5) * MS)
    used = [tr.observe(9100 + k, (1000 + 10 * k) * MS) for k in range(100)]   # A silent from t = 1 s
    assert not any(used[:25]) and all(used[26:]) and tr.switches == 1


def test_publisher_restart_is_followed_after_the_switch_delay():
    """The bench node restarts (new writer, numbers from 1) after 1 s: followed from its 5th sample."""
    tr = SourceTracker(switch_after_ns=250 * MS)
    for k in range(100):
        tr.observe(1000 + k, 10 * k * MS)
    used = [tr.observe(1 + k, (2000 + 10 * k) * MS) for k in range(10)]
    assert used == [False] * 4 + [True] * 6 and tr.switches == 1


def test_node_stall_does_not_switch_the_followed_source():
    """The node stalls 0.4 s (> switch delay); the first sample it then takes is B's, A's follow at once."""
    tr = SourceTracker(switch_after_ns=250 * MS)
    for k in range(100):                                  # A followed, B interleaved (numbers behind)
        assert tr.observe(5000 + k, 10 * k * MS)
        assert not tr.observe(1 + k, (10 * k + 5) * MS)
    t = 1000 * MS + 400 * MS
    used = []
    for k in range(40):                                   # the backlog, B first, 10 µs apart
        used.append(("B", tr.observe(200 + k, t)))
        used.append(("A", tr.observe(5200 + k, t + 5000)))
        t += 10_000
    assert all(u for who, u in used if who == "A") and not any(u for who, u in used if who == "B")
    assert tr.switches == 0


def test_unknown_sequence_is_one_source():
    tr = SourceTracker(switch_after_ns=250 * MS)
    assert all(tr.observe(s, k) for k, s in enumerate([None, 0, None, 0]))


@pytest.fixture(scope="module")
def model():
    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    return PumpModel(load_config(), "fixed")


def test_core_two_sources_warn_and_no_out_of_order_rejections(model):
    """Behaviour: the issue's case (30 % rejected while OK): now the second source is WARNed and ignored."""
    core = TwinCore(model)
    for k in range(400):
        t = k * 5 * MS
        a = core.add_message("shaft_speed", m.joint_state(t, name=["s"], velocity=[W]), t, sequence=1 + k)
        b = core.add_message("shaft_speed", m.joint_state(t - 2 * MS, name=["s"], velocity=[0.5 * W]), t + 1,
                             sequence=1 + k)
        assert a and not b
        core.add_sample("delivery_pressure", PD, t, t)
        core.tick(t)
    rep = core.input_report(2000 * MS)["shaft_speed"]
    assert rep["value"] == pytest.approx(W) and rep["other_source_samples"] == 400
    assert sum(rep["rejected"].values()) == 0 and rep["sources_active"] == 2
    st = core.diagnostics(2000 * MS)["status"][1]
    assert st["level"] == m.DIAG_WARN and "2 sources publishing" in st["message"]
    assert any("more than one publisher" in text for _, text in core.pop_events())


def test_clock_watch():
    cw = ClockWatch(stall_after_s=1.0)
    assert cw.update(0, 0.0).status == "waiting"
    assert cw.update(5, 0.5).status == "ok"
    assert cw.update(5, 1.0).status == "ok"
    st = cw.update(5, 1.6)
    assert st.status == "stalled" and st.unchanged_s == pytest.approx(1.1) and "stalled" in st.describe()
    assert cw.update(5, 3.0).status == "stalled" and cw.stalls == 1
    assert cw.update(6, 3.1).status == "ok"
    cw.update(6, 4.2)
    assert cw.stalls == 2


def test_clock_stall_said_once_per_stall():
    """Behaviour: the update that finds a stall says so (``started``: the node logs it once at WARN), the
    following updates of the same stall do not; a new stall after the clock moved is said again."""
    cw = ClockWatch(stall_after_s=1.0)
    seen = [cw.update(5, t).started for t in (0.0, 0.5, 1.2, 1.5, 3.0)]
    assert seen == [False, False, True, False, False]
    assert not cw.update(6, 3.1).started and cw.update(6, 4.2).started and cw.stalls == 2


def test_burst_with_heavy_loss_is_one_source():
    """Seen in the full suite: a burst of 10 000 messages overflows the subscription history (depth 100), the
    node receives what is left, with sequence gaps of thousands, after stalls.  An earlier rule that bounded a
    source's step by its usual spacing split this one publisher into six sources.  Any forward step is the
    same source."""
    tr = SourceTracker(switch_after_ns=250 * MS)
    seq, recv, used = 1, 0, []
    for _ in range(3):
        for _ in range(100):                              # normal, 200 Hz
            used.append(tr.observe(seq, recv))
            seq, recv = seq + 1, recv + 5 * MS
        seq += 9900                                       # 10 000 published in 10 ms, the last 100 kept
        recv += 700 * MS                                  # after a 0.7 s stall
        for _ in range(100):
            used.append(tr.observe(seq, recv))
            seq, recv = seq + 1, recv + 10_000
    assert all(used) and tr.sources_seen == 1 and tr.switches == 0
