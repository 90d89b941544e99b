"""Inbox between the receiving thread and the model thread (no DDS).

Tier: behaviour.
"""
import threading

import pytest

from gerotor_twin.twin.inbox import Inbox


class FakeClock:
    def __init__(self):
        self.t = 0
        self.lock = threading.Lock()

    def __call__(self):
        with self.lock:
            self.t += 1
            return self.t


def test_take_returns_everything_stamped_up_to_now_in_order():
    """Two threads put while one takes: every item stamped <= now is in that take, none lost."""
    clock = FakeClock()
    box = Inbox(clock)
    n = 20_000
    taken = []

    def producer(kind):
        for k in range(n):
            box.put(kind, k)

    threads = [threading.Thread(target=producer, args=(k,)) for k in ("a", "b")]
    for t in threads:
        t.start()
    while any(t.is_alive() for t in threads) or len(box):
        now, items = box.take()
        assert all(stamp < now for _, _, stamp, _ in items)
        taken.extend(items)
    for kind in ("a", "b"):
        assert [p for k, p, _, _ in taken if k == kind] == list(range(n))
    stamps = [s for _, _, s, _ in taken]
    assert stamps == sorted(stamps)


def test_overflow_counted_not_queued():
    box = Inbox(FakeClock(), max_items=3)
    for k in range(5):
        box.put("a", k)
    now, items = box.take()
    assert [p for _, p, _, _ in items] == [0, 1, 2] and box.dropped == 2
    with pytest.raises(ValueError, match="max_items"):
        Inbox(FakeClock(), max_items=0)
