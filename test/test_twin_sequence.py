"""Inputs lost before reception, from publisher sequence-number gaps (no DDS).

Tier: behaviour.  Expected counts are worked out by hand from the sequences
fed in (what a DDS writer numbers 1, 2, 3, ... and what a receiver saw).
"""
import pytest

from gerotor_twin.twin.sequence import SequenceGaps

MS = 1_000_000


def feed(g, seqs, t0=0, step=MS):
    return [g.add(s, t0 + k * step) for k, s in enumerate(seqs)]


def test_contiguous_stream_loses_nothing():
    g = SequenceGaps()
    assert feed(g, range(1, 1001)) == [0] * 1000
    c = g.counts()
    assert (c.received, c.lost, c.missed_at_start, c.streams) == (1000, 0, 0, 1)


def test_gaps_counted_with_their_size():
    g = SequenceGaps()
    got = feed(g, [1, 2, 5, 6, 7, 100, 101])
    assert got == [0, 0, 2, 0, 0, 92, 0]
    assert g.counts().lost == 94
    # published 1..101 = received 7 + lost 94 + missed_at_start 0
    assert g.counts().received + g.counts().lost == 101


def test_first_sample_above_one_is_missed_at_start_not_lost():
    g = SequenceGaps()
    feed(g, [41, 42, 44])
    c = g.counts()
    assert (c.missed_at_start, c.lost) == (40, 1)


def test_publisher_restart_starts_a_new_stream():
    g = SequenceGaps()
    feed(g, [1, 2, 3, 500, 501])                   # 496 lost before the restart
    feed(g, [1, 2, 4], t0=10 * MS)                 # restarted publisher: 1 lost
    c = g.counts()
    assert (c.lost, c.streams_started) == (496 + 1, 2)


def test_two_interleaved_publishers_each_with_a_loss():
    """A: 1..6 with 3 lost; B: 1000..1005 with 1002, 1003 lost; arrival interleaved."""
    g = SequenceGaps()
    order = [1, 1000, 2, 1001, 4, 1004, 5, 1005, 6]
    feed(g, order)
    c = g.counts()
    assert c.lost == 1 + 2
    assert c.missed_at_start == 0 + 999         # B's first number seen is 1000
    assert c.streams == 2


def test_two_publishers_with_crossing_numbers():
    """A counts 1..20 and B 5..24 in lock step, nothing lost: nothing counted lost."""
    g = SequenceGaps()
    for k in range(20):
        g.add(1 + k, k * MS)
        g.add(5 + k, k * MS + 1)
    assert g.counts().lost == 0


def test_duplicates_and_unnumbered_are_not_gaps():
    g = SequenceGaps()
    feed(g, [1, 2, 2, None, 0, 3])
    c = g.counts()
    assert (c.lost, c.duplicates, c.unnumbered, c.received) == (0, 1, 2, 6)


def test_idle_run_forgotten_single_run_kept():
    g = SequenceGaps(idle_s=1.0)
    g.add(1, 0)
    g.add(2, 5_000 * MS)                           # 5 s pause of the only publisher: same stream
    assert g.counts().streams_started == 1
    for k, t in enumerate((5_001, 5_500, 6_100, 6_200)):
        g.add(1 + k, t * MS)                       # restarted publisher; the old run goes idle
    c = g.counts()
    assert (c.lost, c.streams, c.streams_started) == (0, 1, 2)


def test_restart_long_after_a_gap_keeps_the_gap():
    """1..3, 500 (496 lost), then a restart 1, 2, 3, 4: the old run must not take 4 back."""
    g = SequenceGaps(relink_window=2)
    feed(g, [1, 2, 3, 500, 501, 502])
    feed(g, [1, 2, 3, 4, 5], t0=10 * MS)
    assert g.counts().lost == 496


def test_bad_settings_refused():
    with pytest.raises(ValueError, match="max_runs"):
        SequenceGaps(max_runs=1)
    with pytest.raises(ValueError, match="relink_window"):
        SequenceGaps(relink_window=0)
    with pytest.raises(ValueError, match="idle_s"):
        SequenceGaps(idle_s=0.0)


def test_accounting_metadata_adds_up():
    """Behaviour: the MCAP record states received, logged (minus writer drops), lost per input."""
    from gerotor_twin.twin.sequence import accounting_metadata
    g = SequenceGaps()
    feed(g, [1, 2, 3, 6, 7])
    meta = accounting_metadata({"shaft_speed": g.counts().as_dict()},
                               {"shaft_speed": {"accepted": 4, "rejected": {"nonfinite": 1}}},
                               {"/bench/shaft_speed": 1, "/twin/x": 9}, {"shaft_speed": "/bench/shaft_speed"}, 0)
    assert meta["shaft_speed.received"] == "5" and meta["shaft_speed.logged"] == "4"
    assert meta["shaft_speed.lost"] == "2" and meta["shaft_speed.rejected"] == "1"
    assert all(isinstance(v, str) for v in meta.values())
