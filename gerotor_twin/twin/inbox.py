"""Hand-over of received inputs from the receiving thread to the model thread (no ROS).

The receiving thread (the ROS executor) must never wait for a model advance.
:meth:`Inbox.put` stamps a message with the clock and appends it under a lock
held for microseconds only; the model thread's :meth:`Inbox.take` reads the
clock and empties the inbox under the same lock.  So every message stamped at
or before the ``now`` returned by :meth:`take` is in the batch it returns, and
the core, ticked to that ``now``, has seen every sample received up to it
(the zero-order hold then does not depend on thread timing).

Bounded: beyond ``max_items`` waiting messages (the model thread stuck for a
long time) the newest are not queued and are counted in :attr:`Inbox.dropped`
(they were logged by the receiving thread; only the model misses them).
"""
from __future__ import annotations

import threading
from typing import Any, Callable

__all__ = ["Inbox"]


class Inbox:
    """Thread-safe FIFO of ``(kind, payload, receive_ns, extra)`` items stamped with ``clock_ns``.

    Parameters
    ----------
    clock_ns : callable
        Returns the current time of the node clock [ns].
    max_items : int
        Most items waiting [messages].
    """

    def __init__(self, clock_ns: Callable[[], int], max_items: int = 1_000_000):
        if not (isinstance(max_items, int) and max_items >= 1):
            raise ValueError(f"max_items = {max_items!r}; allowed: an integer >= 1")
        self._clock = clock_ns
        self._max = max_items
        self._lock = threading.Lock()
        self._items: list[tuple[str, Any, int, Any]] = []
        self.dropped = 0

    def put(self, kind: str, payload: Any, extra: Any = None) -> int:
        """Stamp and queue one message; returns its receive time [ns] (also when dropped)."""
        with self._lock:
            t = self._clock()
            if len(self._items) < self._max:
                self._items.append((kind, payload, t, extra))
            else:
                self.dropped += 1
        return t

    def take(self) -> tuple[int, list[tuple[str, Any, int, Any]]]:
        """``(now_ns, items)``: the clock now and every item stamped up to it, in arrival order."""
        with self._lock:
            now = self._clock()
            items, self._items = self._items, []
        return now, items

    def __len__(self) -> int:
        return len(self._items)
