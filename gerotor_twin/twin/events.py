"""Rate-limited events of the twin core: input errors, resets, skips (:class:`EventLog`).

Every event has a key ``(kind, reason)`` (``kind`` = an input or ``model``).
At most one event per key is queued per ``period_ns`` of clock time; the
ones in between are counted and the count is appended to the next one
(``"(+3 similar since the last report)"``).  A clock that goes back
(``t_ns`` before the last report of the key) always reports.
"""
from __future__ import annotations

import collections

__all__ = ["EventLog"]


class EventLog:
    """Queue of ``(level, text)`` events, rate-limited per ``(kind, reason)``.

    Parameters
    ----------
    period_ns : int
        Least clock time between two queued events of one key [ns].
    maxlen : int, optional
        Events kept until :meth:`pop` (older ones dropped), default 1000.
    """

    def __init__(self, period_ns: int, maxlen: int = 1000):
        self._period = int(period_ns)
        self._events: collections.deque = collections.deque(maxlen=maxlen)
        self._reported: dict[tuple[str, str], list] = {}

    def report(self, kind: str, reason: str, level: int, text: str, t_ns: int) -> None:
        """Queue an event, at most one per (kind, reason) per period.

        Parameters
        ----------
        kind, reason : str
            The key (an input kind or ``model``; the reason of the event).
        level : int
            1 = WARN, 2 = ERROR.
        text : str
            The message.
        t_ns : int
            Clock time of the event [ns].
        """
        key = (kind, reason)
        rec = self._reported.get(key)
        if rec is None or t_ns - rec[0] >= self._period or t_ns < rec[0]:
            extra = f" (+{rec[1]} similar since the last report)" if rec and rec[1] else ""
            self._events.append((level, text + extra))
            self._reported[key] = [t_ns, 0]
        else:
            rec[1] += 1

    def pop(self) -> list[tuple[int, str]]:
        """Events since the last call: ``(level, text)``, level 1 = WARN, 2 = ERROR."""
        out = list(self._events)
        self._events.clear()
        return out
