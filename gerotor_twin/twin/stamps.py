"""Header-stamp checks of one input stream: order, duplicates, restarts, plausibility against receive time.

:class:`StampGuard` decides, for each stamped sample, whether its header
stamp is acceptable.  The rules (all times of one input, in ns):

* **Duplicate** (stamp equal to the last accepted one): rejected.
* **Out of order** (older than the last accepted one by at most
  ``restart_ns``): rejected.  Older by more: a **restart** of the source,
  accepted and counted; the stream's usual offset is then learnt again from
  the next sample (so a lone stale sample does not make the good stream that
  follows look ahead).
* **Ahead** (``future_stamp``): the stamp minus its receive time exceeds the
  stream's usual offset by more than ``ahead_ns``: rejected by itself.  The
  usual offset is the largest ``stamp - receive`` of the accepted samples
  (the least-delayed ones; a constant clock offset between bench and twin is
  fine), decaying by 1 ms per second of receive time so that it follows a
  source clock running slow.  Under ``use_sim_time`` stamps run ahead of
  ``/clock`` by up to one clock step; consecutive samples raise the offset
  step by step, so only a jump of more than ``ahead_ns`` is refused.
* **One bad sample never blocks good ones**: when ``rebase_after``
  consecutive samples are rejected as out of order or ahead but agree with
  each other (stamps increasing, offsets within ``ahead_ns`` of each other),
  the last accepted stamp was the outlier (or the source clock jumped): the
  guard re-anchors on them (``rebase``, counted) and accepts from there.  A
  single stamp far ahead that slipped in (the first sample, or one within
  ``ahead_ns``) thus costs at most ``rebase_after - 1`` good samples.

Pure Python, no clock of its own: the caller passes the receive time.
"""
from __future__ import annotations

__all__ = ["StampGuard", "ACCEPT", "RESTART", "REBASE"]

ACCEPT = None            #: verdict: in order
RESTART = "restart"      #: verdict: accepted, the source restarted (stamp far back)
REBASE = "rebase"        #: verdict: accepted, re-anchored on a consistent run after rejections
_DECAY = 1e-3            #: usual-offset decay [s per s of receive time]


class StampGuard:
    """Stamp order and plausibility of one input stream (see the module docstring).

    Parameters
    ----------
    restart_ns : int
        A stamp older than the last accepted one by more than this is a restart [ns].
    ahead_ns : int
        Largest excess of ``stamp - receive`` over the stream's usual offset [ns].
    rebase_after : int
        Consecutive consistent rejected samples after which the guard re-anchors.
    """

    def __init__(self, restart_ns: int, ahead_ns: int, rebase_after: int = 3):
        self.restart_ns = int(restart_ns)
        self.ahead_ns = int(ahead_ns)
        self.rebase_after = max(1, int(rebase_after))
        self.last_stamp: int | None = None
        self.offset_ns: float | None = None      #: usual stamp - receive [ns]
        self._offset_at: int | None = None
        self._run: list[tuple[int, int]] = []    #: (stamp, offset) of consecutive consistent rejections
        self.restarts = 0
        self.rebases = 0

    def reset(self) -> None:
        """Forget order and offset (clock jump back, bag loop); counters are kept."""
        self.last_stamp = None
        self.offset_ns = None
        self._offset_at = None
        self._run.clear()

    def usual_offset(self, receive_ns: int) -> float | None:
        """The stream's usual ``stamp - receive`` at ``receive_ns`` [ns] (None before the first sample)."""
        if self.offset_ns is None:
            return None
        return self.offset_ns - max(0, receive_ns - self._offset_at) * _DECAY

    def check(self, stamp_ns: int, receive_ns: int) -> str | None:
        """Verdict for a stamped sample: None / ``restart`` / ``rebase`` (accept) or a rejection reason.

        Rejection reasons: ``duplicate_stamp``, ``out_of_order_stamp``, ``future_stamp``.
        Call :meth:`accept` when the sample is finally accepted (its value may still be refused).
        """
        verdict = None
        last = self.last_stamp
        if last is not None and stamp_ns == last:
            self._run.clear()
            return "duplicate_stamp"
        if last is not None and stamp_ns < last:
            if last - stamp_ns > self.restart_ns:
                self._run.clear()
                return RESTART
            verdict = "out_of_order_stamp"
        usual = self.usual_offset(receive_ns)
        if verdict is None and usual is not None and stamp_ns - receive_ns - usual > self.ahead_ns:
            verdict = "future_stamp"
        if verdict is None:
            self._run.clear()
            return ACCEPT
        return REBASE if self._consistent_run(stamp_ns, stamp_ns - receive_ns) else verdict

    def _consistent_run(self, stamp_ns: int, offset_ns: int) -> bool:
        run = self._run
        if run and (stamp_ns <= run[-1][0] or abs(offset_ns - run[0][1]) > self.ahead_ns):
            run.clear()
        run.append((stamp_ns, offset_ns))
        return len(run) >= self.rebase_after

    def accept(self, stamp_ns: int, receive_ns: int, verdict: str | None = None) -> None:
        """Record an accepted sample (with the verdict :meth:`check` gave it)."""
        if verdict == RESTART:          # learn the new offset from the next sample, not from this one:
            self.restarts += 1          # a lone stale sample must not make the good stream look "ahead"
            self.offset_ns = None
            self._offset_at = None
            self.last_stamp = stamp_ns
            return
        if verdict == REBASE:
            self.rebases += 1
            self.offset_ns = None
            self._run.clear()
        off = stamp_ns - receive_ns
        usual = self.usual_offset(receive_ns)
        self.offset_ns = off if usual is None else max(float(off), usual)
        self._offset_at = receive_ns
        self.last_stamp = stamp_ns
