"""Which publisher a sample came from, and which one the twin follows (more than one source on a topic).

What identifies a source: rclpy 7.1 (Jazzy) gives a ``raw=True`` subscription
callback a message-info dict with only ``source_timestamp``,
``received_timestamp``, ``publication_sequence_number`` and
``reception_sequence_number`` (checked on this build; the publisher GID that
``rmw_message_info_t`` carries is not passed on).  The publication sequence
number is counted per publisher (DDS writer), from 1, so the samples of each
publisher form one increasing sequence.  :class:`SourceTracker` attributes a
sample to the sequence it continues (the one whose last number is just
below, a gap of lost samples allowed as far as the publisher time since its
last sample and its usual spacing explain it (twice that, at least 16, at
most ``max_gap``; publisher time = the DDS source timestamp, so a stall of
the node followed by a burst does not split a source); on a tie the source that delivered least recently, which
follows strict alternation), or starts a new source.  The node also reads the topic's publishers from the ROS graph
(names, GIDs) for the diagnostics.  A sample without a sequence number (an
rmw that does not provide it, or a recording without it: MCAP sequence 0)
counts as the one source.

Policy (documented in docs/node.md): the twin **follows the first source**.
Samples of any other source are still logged (the node logs every received
message before this decision) and counted (``other_source``) but not used.
When the followed source has been silent for ``switch_after_ns`` (a dead
sensor, or the same bench node restarted: a new writer starts again at 1),
the next source that delivers is followed from then on (counted as a
switch).  More than one source active within ``ACTIVE_WINDOW_NS`` is a WARN
on ``/diagnostics``.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SourceTracker", "ACTIVE_WINDOW_NS"]

ACTIVE_WINDOW_NS = 1_000_000_000      #: a source that delivered within this [ns] counts as active
_FORGET_NS = 30_000_000_000           #: a source silent this long [ns] is forgotten
_MAX_SOURCES = 64
_MIN_GAP = 16                         #: sequence steps always taken as the same source (a few lost samples)


@dataclass
class _Source:
    ident: int                  #: 1, 2, ... in order of first appearance
    last_seq: int
    last_receive: int
    last_source: int            #: source (publisher) time of its last sample [ns]
    samples: int = 0
    interval_ns: float = 0.0    #: running mean of the publication spacing [ns] (0 until known)

    def max_step(self, source_ns: int, cap: int) -> int:
        """Largest sequence step still taken as this source: lost samples as its elapsed time allows."""
        dt = max(0, source_ns - self.last_source)
        expect = 2.0 * dt / self.interval_ns if self.interval_ns > 0 else 0.0
        return int(min(cap, _MIN_GAP + expect))


class SourceTracker:
    """Sources of one input topic from publication sequence numbers; decides which samples to use.

    Parameters
    ----------
    switch_after_ns : int
        The followed source silent this long [ns]: the next delivering source is followed.
    max_gap : int
        Largest jump of a source's sequence number still taken as the same source (lost samples).
    """

    def __init__(self, switch_after_ns: int, max_gap: int = 10_000):
        self.switch_after_ns = int(switch_after_ns)
        self.max_gap = int(max_gap)
        self._sources: list[_Source] = []
        self._next_id = 1
        self.followed: int | None = None        #: ident of the followed source
        self.other_samples = 0                  #: samples of other sources: logged, not used
        self.switches = 0                       #: times the followed source changed
        self.sources_seen = 0                   #: distinct sources since start

    def observe(self, sequence: int | None, receive_ns: int, source_ns: int | None = None) -> bool:
        """Attribute one sample; True if it comes from the followed source (use it), False otherwise.

        ``source_ns`` is the publisher's time of the sample (DDS source timestamp,
        MCAP publish time): the spacing of a source is measured on it, so the
        node's own scheduling (a stall, then a burst) does not split a source in
        two.  Default: the receive time.
        """
        if sequence is None or sequence <= 0:
            return True
        src = self._attribute(int(sequence), int(receive_ns), int(receive_ns if source_ns is None else source_ns))
        fol = self._find(self.followed)
        if fol is None or (fol is not src and receive_ns - fol.last_receive > self.switch_after_ns):
            if self.followed is not None:
                self.switches += 1
            self.followed = src.ident
        if src.ident != self.followed:
            self.other_samples += 1
            return False
        return True

    def _find(self, ident: int | None) -> _Source | None:
        return next((s for s in self._sources if s.ident == ident), None)

    def _attribute(self, seq: int, receive_ns: int, source_ns: int) -> _Source:
        self._sources = [s for s in self._sources if receive_ns - s.last_receive <= _FORGET_NS
                         or s.ident == self.followed]
        best = None
        for s in self._sources:
            if s.last_seq < seq <= s.last_seq + s.max_step(source_ns, self.max_gap):
                key = (seq - s.last_seq, s.last_receive)
                if best is None or key < best[0]:
                    best = (key, s)
        if best is None:
            if len(self._sources) >= _MAX_SOURCES:
                self._sources.remove(min(self._sources, key=lambda s: s.last_receive))
            src = _Source(self._next_id, seq, receive_ns, source_ns)
            self._next_id += 1
            self.sources_seen += 1
            self._sources.append(src)
        else:
            src = best[1]
        if src.samples:
            dt = max(0, source_ns - src.last_source) / max(1, seq - src.last_seq)
            src.interval_ns = dt if src.interval_ns == 0 else 0.9 * src.interval_ns + 0.1 * dt
        src.last_seq, src.last_receive, src.last_source = seq, receive_ns, source_ns
        src.samples += 1
        return src

    def active(self, now_ns: int, window_ns: int = ACTIVE_WINDOW_NS) -> int:
        """Sources that delivered within ``window_ns`` before ``now_ns``."""
        return sum(1 for s in self._sources if 0 <= now_ns - s.last_receive <= window_ns)

    def reset(self) -> None:
        """Forget the sources (clock jump back); counters are kept."""
        self._sources.clear()
        self.followed = None
