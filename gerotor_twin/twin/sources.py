"""Which publisher a sample came from, and which one the twin follows (more than one source on a topic).

What identifies a source: rclpy 7.1 (Jazzy) gives a ``raw=True`` subscription
callback a message-info dict with only ``source_timestamp``,
``received_timestamp``, ``publication_sequence_number`` and
``reception_sequence_number`` (checked on this build; the publisher GID that
``rmw_message_info_t`` carries is not passed on).  The publication sequence
number is counted per publisher (DDS writer), from 1, and a best-effort
reader never delivers a writer's samples out of order, so the samples of each
publisher form one increasing sequence, with gaps where samples were lost
(a burst that overflows the subscription history loses thousands at once).

:class:`SourceTracker` attributes a sample to the known source whose last
number is the closest below it (any forward step: lost samples), on a tie to
the source that delivered least recently (this follows strict alternation of
two publishers started together).  A sample that continues no source (its
number is not above any source's last one) comes from another publisher (or
from a restarted one, which starts again at 1): a new source.  One ambiguity
is repaired afterwards: when a second publisher whose numbers are *ahead*
first appears, its sample looks like a jump of the first source; when the
first source's next sample then falls between its number before that jump
and the jump, the jump is split off as the new source.  (Its one sample was
already used.)  Two publishers started together whose samples arrive in
swapped order cannot always be told apart; they are still counted and WARNed.
The node also reads the topic's publishers from the ROS graph (names, GIDs)
for the diagnostics.  A sample without a sequence number (an rmw that does
not provide it, or a recording without it: MCAP sequence 0) counts as the
one source.

Policy (documented in docs/node.md): the twin **follows the first source**.
Samples of any other source are still logged (the node logs every received
message before this decision) and counted (``other_source``) but not used.
When the followed source has been silent for ``switch_after_ns`` (a dead
sensor, or the same bench node restarted: a new writer starts again at 1)
while other sources delivered 5 samples in a row, the source that delivered
the last of them is followed from then on (counted as a switch).  Both
conditions, because the node's receive times stall with the node: after a
stall the first sample taken may be the other source's, but the followed
source's samples come right after it.  More than one source active within
``ACTIVE_WINDOW_NS`` is a WARN on ``/diagnostics``.  A clock jump back (bag
loop) changes nothing here: publication sequence numbers do not jump with
the clock.
"""
from __future__ import annotations

from dataclasses import dataclass

__all__ = ["SourceTracker", "ACTIVE_WINDOW_NS"]

ACTIVE_WINDOW_NS = 1_000_000_000      #: a source that delivered within this [ns] counts as active
_FORGET_NS = 30_000_000_000           #: a source silent this long [ns] is forgotten
_MAX_SOURCES = 64
_JUMP = 16                            #: a forward step above this is remembered as a jump (see above)
_SWITCH_SAMPLES = 5                   #: samples of other sources in a row needed (with the silence) to switch


@dataclass
class _Source:
    ident: int                  #: 1, 2, ... in order of first appearance
    last_seq: int
    last_receive: int
    samples: int = 0
    before_jump: int | None = None   #: last number before its latest jump (None: no jump since)


class SourceTracker:
    """Sources of one input topic from publication sequence numbers; decides which samples to use.

    Parameters
    ----------
    switch_after_ns : int
        The followed source silent this long [ns]: the next delivering source is followed.
    """

    def __init__(self, switch_after_ns: int):
        self.switch_after_ns = int(switch_after_ns)
        self._sources: list[_Source] = []
        self._next_id = 1
        self.followed: int | None = None        #: ident of the followed source
        self.other_samples = 0                  #: samples of other sources: logged, not used
        self.switches = 0                       #: times the followed source changed
        self.sources_seen = 0                   #: distinct sources since start
        self._others_in_row = 0                 #: samples of other sources since the followed one's last

    def observe(self, sequence: int | None, receive_ns: int) -> bool:
        """Attribute one sample; True if it comes from the followed source (use it), False otherwise."""
        if sequence is None or sequence <= 0:
            return True
        fol = self._find(self.followed)
        silent_ns = None if fol is None else receive_ns - fol.last_receive
        src = self._attribute(int(sequence), int(receive_ns))
        self._others_in_row = 0 if src is fol else self._others_in_row + 1
        if fol is None or (src is not fol and silent_ns > self.switch_after_ns
                           and self._others_in_row >= _SWITCH_SAMPLES):
            if self.followed is not None:
                self.switches += 1
            self.followed = src.ident
            self._others_in_row = 0
        if src.ident != self.followed:
            self.other_samples += 1
            return False
        return True

    def _find(self, ident: int | None) -> _Source | None:
        return next((s for s in self._sources if s.ident == ident), None)

    def _new(self, seq: int, receive_ns: int) -> _Source:
        if len(self._sources) >= _MAX_SOURCES:
            self._sources.remove(min(self._sources, key=lambda s: s.last_receive))
        src = _Source(self._next_id, seq, receive_ns)
        self._next_id += 1
        self.sources_seen += 1
        self._sources.append(src)
        return src

    def _attribute(self, seq: int, receive_ns: int) -> _Source:
        self._sources = [s for s in self._sources if receive_ns - s.last_receive <= _FORGET_NS
                         or s.ident == self.followed]
        ahead = [s for s in self._sources if s.last_seq < seq]
        if ahead:
            src = min(ahead, key=lambda s: (seq - s.last_seq, s.last_receive))
            src.before_jump = src.last_seq if seq - src.last_seq > _JUMP else src.before_jump
        else:
            src = next((s for s in self._sources if s.before_jump is not None and s.before_jump < seq), None)
            if src is not None:                  # its last jump was another publisher: split it off
                intruder = self._new(src.last_seq, src.last_receive)
                intruder.samples = 1
                src.before_jump = None
            else:
                src = self._new(seq, receive_ns)
                src.samples -= 1                 # counted below
        src.last_seq, src.last_receive = seq, receive_ns
        src.samples += 1
        return src

    def active(self, now_ns: int, window_ns: int = ACTIVE_WINDOW_NS) -> int:
        """Sources that delivered within ``window_ns`` before ``now_ns``."""
        return sum(1 for s in self._sources if 0 <= now_ns - s.last_receive <= window_ns)
