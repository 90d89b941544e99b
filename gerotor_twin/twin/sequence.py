"""Inputs lost before the node saw them, from gaps in the publishers' sequence numbers (no ROS).

Every DDS writer numbers its samples 1, 2, 3, ... (RTPS ``publication_sequence_number``,
given by rclpy in the message info of a ``raw=True`` subscription).  A sample that
never reaches the subscriber's callback -- dropped by a full subscription history
(``input_queue_depth``), by the transport, or by a best-effort network -- leaves a
gap in that numbering.  :class:`SequenceGaps` counts those gaps for one topic.

Several publishers on one topic
    rclpy (Jazzy) gives no publisher GID with the message info (keys:
    ``source_timestamp``, ``received_timestamp``, ``publication_sequence_number``,
    ``reception_sequence_number``), so publishers are told apart by their
    numbering.  Samples are grouped in *runs* of consecutive numbers.  A sample
    that continues no run starts a new run, linked (gap counted) to the open run
    whose last number is the closest below it.  If that run is continued
    within the next ``relink_window`` samples of the topic while no open run
    lies below the sample, it belonged to another publisher: the link and its gap are taken back and the new run is a
    stream of its own (its first number - 1 is ``missed_at_start``).  One
    publisher per topic (the bench case) is counted exactly; several are
    counted exactly while their numbers do not fall inside each other's gaps.
    Runs idle for ``idle_s`` are forgotten (the most recent is always kept).
What is not a gap
    Numbers below a stream's first sample (published before the subscription
    matched, or before the node started) are reported as ``missed_at_start``,
    not as lost; samples after the last one received cannot be seen (a loss at
    the very end of a run is invisible to any receiver).  A repeated number is a
    ``duplicate``; a message without a number (0 / None: RMW without support) is
    ``unnumbered``.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SequenceGaps", "GapCounts", "ACCOUNTING_METADATA", "accounting_metadata"]

#: Name of the MCAP Metadata record with the per-input accounting, written by the node at close.
ACCOUNTING_METADATA = "gerotor_twin.input_accounting"


@dataclass(frozen=True)
class GapCounts:
    """Counters of one topic [messages]."""
    received: int = 0          #: samples seen (numbered or not)
    lost: int = 0              #: numbers skipped inside a stream (lost before reception)
    missed_at_start: int = 0   #: numbers below each stream's first sample (first number - 1)
    duplicates: int = 0        #: numbers equal to a stream's last one
    unnumbered: int = 0        #: samples without a sequence number
    streams: int = 0           #: open runs (about: publishers) currently tracked
    streams_started: int = 0   #: streams started so far (publishers seen, restarts)

    def as_dict(self) -> dict[str, int]:
        return {k: getattr(self, k) for k in self.__dataclass_fields__}


class _Run:
    __slots__ = ("first", "last", "seen_ns", "pred", "gap", "succ", "linked_at")

    def __init__(self, first: int, seen_ns: int):
        self.first = self.last = first
        self.seen_ns = seen_ns
        self.pred: _Run | None = None      # run this one continues after a gap
        self.gap = 0                       # numbers lost between pred and this run
        self.succ: _Run | None = None      # run that continues this one
        self.linked_at = 0                 # topic sample count when succ was linked


class SequenceGaps:
    """Gap counter for the samples of one topic (not thread-safe: one receiving thread).

    Parameters
    ----------
    max_runs : int
        Most runs tracked at once; the least recently seen is forgotten beyond.
    idle_s : float
        A run without a sample for this long (receive time) is forgotten [s].
    relink_window : int
        Samples of the topic during which a run that got a successor after a gap
        may still be continued (then it was another publisher) [messages].
    """

    def __init__(self, max_runs: int = 16, idle_s: float = 10.0, relink_window: int = 32):
        if not (isinstance(max_runs, int) and max_runs >= 2):
            raise ValueError(f"max_runs = {max_runs!r}; allowed: an integer >= 2")
        if not idle_s > 0:
            raise ValueError(f"idle_s = {idle_s!r}; allowed: > 0 s")
        if not (isinstance(relink_window, int) and relink_window >= 1):
            raise ValueError(f"relink_window = {relink_window!r}; allowed: an integer >= 1")
        self._max = max_runs
        self._idle_ns = int(idle_s * 1e9)
        self._window = relink_window
        self._runs: list[_Run] = []
        self.received = self.lost = self.missed_at_start = self.duplicates = self.unnumbered = 0
        self.streams_started = 0

    def add(self, seq: int | None, receive_ns: int) -> int:
        """Book one received sample; returns the change of the lost count it causes (usually 0).

        Parameters
        ----------
        seq : int or None
            Its ``publication_sequence_number`` (``None``/0: unknown).
        receive_ns : int
            Receive time [ns] (only to forget idle runs).
        """
        self.received += 1
        if not isinstance(seq, int) or seq <= 0:
            self.unnumbered += 1
            return 0
        self._forget(receive_ns)
        before = self.lost
        run = self._continued(seq)
        if run is not None:
            run.last = seq
            run.seen_ns = receive_ns
            if run.succ is not None:          # alive after all: its "successor" is another publisher
                self._unlink(run.succ)
            return self.lost - before
        if any(r.last == seq for r in self._runs):
            self.duplicates += 1
            return 0
        new = _Run(seq, receive_ns)
        pred = None
        for r in self._runs:
            if r.succ is None and r.last < seq and (pred is None or r.last > pred.last):
                pred = r
        if pred is None:
            self._new_stream(new)
        else:
            new.pred, new.gap = pred, seq - pred.last - 1
            pred.succ, pred.linked_at = new, self.received
            self.lost += new.gap
        self._runs.append(new)
        return self.lost - before

    def _continued(self, seq: int) -> _Run | None:
        """The run ``seq`` continues without a gap; a linked run only if no open run could precede it."""
        best = None
        open_below = any(r.succ is None and r.last < seq for r in self._runs)
        for r in self._runs:
            if r.last + 1 == seq and (r.succ is None or (not open_below
                                                         and self.received - r.linked_at <= self._window)):
                if best is None or (best.succ is not None and r.succ is None) or (
                        (best.succ is None) == (r.succ is None) and r.seen_ns > best.seen_ns):
                    best = r
        return best

    def _new_stream(self, run: _Run) -> None:
        self.streams_started += 1
        self.missed_at_start += run.first - 1

    def _unlink(self, run: _Run) -> None:
        self.lost -= run.gap
        run.pred.succ = None
        run.pred, run.gap = None, 0
        self._new_stream(run)

    def _forget(self, now_ns: int) -> None:
        runs = self._runs
        if len(runs) < 2:
            return
        keep = [r for r in runs if now_ns - r.seen_ns <= self._idle_ns
                and (r.succ is None or self.received - r.linked_at <= self._window)]
        if len(keep) > self._max:
            keep = sorted(keep, key=lambda r: r.seen_ns)[-self._max:]
        if len(keep) != len(runs):
            self._runs = keep or [max(runs, key=lambda r: r.seen_ns)]

    def counts(self) -> GapCounts:
        """Current counters."""
        return GapCounts(self.received, self.lost, self.missed_at_start, self.duplicates, self.unnumbered,
                         sum(1 for r in self._runs if r.succ is None), self.streams_started)


def accounting_metadata(gaps: dict, report: dict, log_dropped: dict, topics: dict,
                        model_dropped: int = 0) -> dict[str, str]:
    """The :data:`ACCOUNTING_METADATA` record: per subscribed input, what was received, logged, lost.

    Parameters
    ----------
    gaps : dict
        ``TwinCore.input_accounting()`` (kind -> :meth:`GapCounts.as_dict`).
    report : dict
        ``TwinCore.input_report()`` (kind -> accepted, rejected by reason, ...).
    log_dropped : dict
        MCAP writer drops per topic (``LogStats.dropped_queue_full``).
    topics : dict
        kind -> fully qualified topic of the subscribed inputs.
    model_dropped : int
        Inputs logged but not handed to the model (inbox overflow).

    Returns
    -------
    dict[str, str]
        Keys ``<kind>.<counter>``: ``topic``, ``received``, ``logged`` (received -
        dropped by the MCAP writer), ``lost`` (before reception), ``missed_at_start``,
        ``duplicates``, ``unnumbered``, ``accepted``, ``rejected``; plus
        ``model_inbox_dropped``.  In the file: published = logged + log_dropped
        + lost (+ missed_at_start before the first sample of each publisher).
    """
    out = {"model_inbox_dropped": str(model_dropped)}
    for kind, topic in topics.items():
        g = gaps[kind]
        dropped = int(log_dropped.get(topic, 0))
        rep = report.get(kind, {})
        vals = {"topic": topic, "received": g["received"], "logged": g["received"] - dropped,
                "log_dropped": dropped, "lost": g["lost"], "missed_at_start": g["missed_at_start"],
                "duplicates": g["duplicates"], "unnumbered": g["unnumbered"],
                "accepted": rep.get("accepted", 0), "rejected": sum(rep.get("rejected", {}).values())}
        out.update({f"{kind}.{k}": str(v) for k, v in vals.items()})
    return out
