"""Write an MCAP log from a background thread, so a ROS executor never waits on the disk.

:class:`BackgroundMcapLog` wraps a :class:`~gerotor_twin.io.mcap_log.McapLog`
or :class:`~gerotor_twin.io.mcap_log.RotatingMcapLog`.  ``write``/``write_raw``
run in the caller's thread only as far as validation and CDR encoding (so a
bad message raises there, and later changes to the caller's arrays cannot
alter what is logged); the bytes then go to a bounded queue that one writer
thread empties into the file.

Queue full
    The new message is **dropped**, never queued by evicting older ones and
    never waited for longer than ``block_s`` (default 0: not at all).
    ``write`` returns False, the drop is counted per topic
    (:meth:`BackgroundMcapLog.stats`), logged (first drop, then at 10, 100,
    ... drops) and written into the file at close as metadata record
    :data:`STATS_METADATA`.
After close
    Writes return False and are counted as ``dropped_after_close``.
Written, pending, lost
    ``written`` counts a message once it is on disk: its chunk was handed to
    the OS (the file is flushed after every chunk and every ``flush_interval_s``)
    or the file was finalised, so ``written`` is what a recovery of the file
    finds.  Messages in the queue or the open chunk are ``pending``
    (``queued = written + pending + lost``; at close ``pending`` is 0, and
    every message offered is written or dropped).
Writer-thread I/O error (e.g. disk full)
    Logged once; the file is closed without finalising (what reached it stays
    recoverable: ``gerotor-twin log recover``).  Of the messages handed to that
    file, those in chunks that are complete on disk (read back from the file,
    :func:`~gerotor_twin.io.recover.recoverable_messages`) are ``written``; the
    rest (the chunk the error cut short, the open chunk), the message and all
    later ones are counted as ``lost`` (per topic in ``lost_by_topic``) while
    :attr:`BackgroundMcapLog.error` holds the exception.  With a
    :class:`Reopen` policy, every ``retry_s`` the thread checks the free
    space of the log directory and, once at least ``min_free_bytes`` are
    free, continues in the new file its factory returns (:attr:`LogStats.resumed` counts this, ``error`` is cleared,
    ``last_error`` keeps the reason).
Flushing
    The open chunk is written and the file flushed at least every
    ``flush_interval_s`` (busy or idle), so a crash of the process loses at
    most that much plus the queue; ``fsync=True`` also survives a power cut.
close()
    Stops accepting, lets the thread drain the queue, write the stats record
    and finalise the file, and waits for that up to ``timeout_s``.  It takes
    no lock that an interrupted producer could hold (the queue is a
    lock-free ``deque`` polled every ``poll_s``), so it is safe from a signal
    handler; it also runs at interpreter exit.  Idempotent.
"""
from __future__ import annotations

import collections
import itertools
import logging
import shutil
import threading
import time
import weakref
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable, Mapping, Union

from gerotor_twin.errors import InputError
from gerotor_twin.io.mcap_log import McapLog, RotatingMcapLog, _check_time
from gerotor_twin.io.qos import QosSpec
from gerotor_twin.io.reader import McapReadError
from gerotor_twin.io.recover import recoverable_messages

__all__ = ["STATS_METADATA", "LogStats", "Reopen", "BackgroundMcapLog"]

#: Name of the Metadata record with the writer's counters, written at close.
STATS_METADATA = "gerotor_twin.log_stats"

_log = logging.getLogger(__name__)
AnyLog = Union[McapLog, RotatingMcapLog]


@dataclass(frozen=True)
class LogStats:
    """Counters of a :class:`BackgroundMcapLog` [messages].

    Attributes
    ----------
    queued, written : int
        Accepted into the queue; written to the file.
    dropped_queue_full : dict[str, int]
        Per topic, rejected because the queue was full.
    dropped_after_close : int
        Writes attempted after :meth:`BackgroundMcapLog.close`.
    lost : int
        Accepted but not written because of a writer-thread error (not on disk).
    max_queue_depth : int
        Highest queue length seen.
    error : str or None
        Writer-thread error, if one is current (cleared when logging resumes).
    resumed : int
        Times logging resumed in a new file after an error.
    last_error : str or None
        The most recent writer-thread error, current or past.
    """

    queued: int
    written: int
    dropped_queue_full: dict[str, int] = field(default_factory=dict)
    dropped_after_close: int = 0
    lost: int = 0
    max_queue_depth: int = 0
    error: str | None = None
    resumed: int = 0
    last_error: str | None = None
    lost_by_topic: dict[str, int] = field(default_factory=dict)

    @property
    def dropped(self) -> int:
        """All messages offered but not written."""
        return sum(self.dropped_queue_full.values()) + self.dropped_after_close + self.lost

    @property
    def pending(self) -> int:
        """Accepted, not yet on disk (in the queue or the open chunk) and not lost."""
        return self.queued - self.written - self.lost

    def as_metadata(self) -> dict[str, str]:
        """String form for an MCAP Metadata record."""
        out = {"queued": str(self.queued), "written": str(self.written),
               "dropped_queue_full": str(sum(self.dropped_queue_full.values())),
               "dropped_after_close": str(self.dropped_after_close), "lost": str(self.lost),
               "max_queue_depth": str(self.max_queue_depth)}
        out.update({f"dropped_queue_full/{k}": str(v) for k, v in self.dropped_queue_full.items()})
        out.update({f"lost/{k}": str(v) for k, v in self.lost_by_topic.items()})
        if self.error:
            out["error"] = self.error
        if self.last_error:
            out.update(resumed=str(self.resumed), last_error=self.last_error)
        return out


@dataclass(frozen=True)
class Reopen:
    """How the writer thread resumes after a write error (e.g. disk full).

    Attributes
    ----------
    factory : callable
        Returns a new, open log (a new file; called in the writer thread).
    directory : Path
        Where free space is checked.
    min_free_bytes : int
        Free space needed before a new file is opened [bytes].
    retry_s : float
        Period of the check [s].
    """

    factory: Callable[[], Any]
    directory: Path
    min_free_bytes: int = 16_000_000
    retry_s: float = 5.0

    def free_bytes(self) -> int:
        """Free space available to this process in :attr:`directory` [bytes] (0 if unknown)."""
        try:
            return int(shutil.disk_usage(self.directory).free)
        except OSError:
            return 0


class _Pump:
    """State shared by the producer side and the writer thread (no reference to the wrapper)."""

    def __init__(self, log: AnyLog, max_queue: int, poll_s: float, flush_interval_s: float | None,
                 reopen: Reopen | None = None, fsync: bool = False):
        self.log = log
        self.reopen = reopen
        self.fsync = fsync
        self.resumed = 0
        self.last_error: BaseException | None = None
        self.next_retry = 0.0
        self.unfinalised: list[Any] = []          # paths of files closed unfinalised
        self.topics: dict[str, tuple[str, Any]] = {}   # registered topics, for a resumed file
        self.queue: collections.deque[Any] = collections.deque()
        self.max_queue = max_queue
        self.poll_s = poll_s
        self.flush_interval_s = flush_interval_s
        self.accepting = True
        self.stopping = False
        self.error: BaseException | None = None
        self.queued = itertools.count(1)    # next() is atomic in CPython
        self.n_queued = 0
        self.retracted = 0
        self.written = 0                    # on disk: base_written + the current log's confirmed messages
        self.base_written = 0               # on disk in the files given up after an error
        self.offered: dict[str, int] = {}   # per topic, handed to the current log
        self.lost = 0
        self.lost_by_topic: dict[str, int] = {}
        self.max_depth = 0
        self.drop_lock = threading.Lock()   # producers only; close() never takes it
        self.dropped: dict[str, int] = {}
        self.dropped_after_close = 0
        self.thread = threading.Thread(target=self.run, name="mcap-log-writer", daemon=True)

    def stats(self) -> LogStats:
        return LogStats(self.n_queued - self.retracted, self.written, dict(self.dropped),
                        self.dropped_after_close, self.lost, self.max_depth,
                        None if self.error is None else repr(self.error), self.resumed,
                        None if self.last_error is None else repr(self.last_error), dict(self.lost_by_topic))

    def _lose(self, topic: str, n: int = 1) -> None:
        self.lost += n
        self.lost_by_topic[topic] = self.lost_by_topic.get(topic, 0) + n

    def _settle(self) -> None:
        """After a write error: of the messages handed to this log, those on disk are written, the rest lost."""
        on_disk = _on_disk(self.log)
        for topic, n in self.offered.items():
            kept = min(n, on_disk.get(topic, 0))
            self.base_written += kept
            if n > kept:
                self._lose(topic, n - kept)
        self.offered = {}
        self.written = self.base_written

    def _fail(self, exc: BaseException) -> None:
        """A write error: stop writing this file, keep what it holds (unfinalised), report once."""
        self.error = self.last_error = exc
        path = getattr(self.log, "path", None)
        try:
            self.log.abandon()
        except Exception:  # noqa: BLE001 - the file is broken already
            pass
        self._settle()
        self.unfinalised.append(path)
        retry = "" if self.reopen is None else (
            f"; a new file is started when {self.reopen.min_free_bytes / 1e6:g} MB are free again "
            f"(checked every {self.reopen.retry_s:g} s)")
        _log.error("MCAP writer thread: %s; %s left unfinalised (recover it with `gerotor-twin log "
                   "recover`: %d message(s) written in all files, %d lost); messages are counted as lost%s",
                   exc, path, self.written, self.lost, retry)
        self.next_retry = time.monotonic() + (self.reopen.retry_s if self.reopen else 0.0)

    def _handle(self, item: Any) -> None:
        kind, args = item
        if kind == "flush":
            try:
                if self.error is None:
                    self.log.flush(self.fsync)
                    self.written = self.base_written + self.log.confirmed_messages
            except Exception as exc:
                self._fail(exc)
            if args is not None:
                args.set()
            return
        if kind == "msg" and self.error is not None:
            self._lose(args[0])
            return
        if self.error is not None:
            return
        try:
            if kind == "msg":
                topic, data, log_ns, pub_ns, seq = args
                self.offered[topic] = self.offered.get(topic, 0) + 1
                self.log.write_raw(topic, data, log_ns, pub_ns, sequence=seq)
                self.written = self.base_written + self.log.confirmed_messages
            else:
                self.log.add_metadata(*args)
        except Exception as exc:  # keep the thread alive; report once
            self._fail(exc)

    def _maybe_resume(self, now: float) -> None:
        """After a write error: every ``retry_s``, open a new file if there is space again."""
        r = self.reopen
        if r is None or now < self.next_retry:
            return
        self.next_retry = now + r.retry_s
        if r.free_bytes() < r.min_free_bytes:
            return
        try:
            new = r.factory()
            for topic, (msgtype, qos) in self.topics.items():
                new.add_topic(topic, msgtype, qos)
        except Exception as exc:  # noqa: BLE001 - still no space, permissions...: retry later
            _log.warning("MCAP log not resumed yet: %s", exc)
            return
        self.log, self.error = new, None
        self.resumed += 1
        _log.warning("MCAP log resumed in %s after: %s (%d message(s) lost meanwhile)",
                     getattr(new, "path", "?"), self.last_error, self.lost)

    def run(self) -> None:
        last_flush = time.monotonic()
        while True:
            now = time.monotonic()
            if self.error is not None:
                self._maybe_resume(now)
            elif self.flush_interval_s is not None and now - last_flush >= self.flush_interval_s:
                self._handle(("flush", None))
                last_flush = now
            try:
                item = self.queue.popleft()
            except IndexError:
                if self.stopping:
                    break
                time.sleep(self.poll_s)
                continue
            self._handle(item)
        self._finish()

    def _finish(self) -> None:
        """Flush (so the stats record holds the final counts), write the stats record, finalise."""
        if self.error is not None:
            return  # the file was closed unfinalised at the error
        try:
            self.log.flush(self.fsync)
            self.written = self.base_written + self.log.confirmed_messages
            self.log.add_metadata(STATS_METADATA, self.stats().as_metadata())
            self.log.close()
            self.written = self.base_written + self.log.confirmed_messages
        except Exception as exc:
            _log.error("MCAP log could not be finalised: %s", exc)
            self._fail(exc)

    def stop(self, timeout_s: float | None) -> bool:
        """Stop accepting, drain, finalise; True if the thread finished within ``timeout_s``."""
        self.accepting = False
        self.stopping = True
        if self.thread is threading.current_thread():
            return False
        if self.thread.is_alive():
            self.thread.join(timeout_s)
        elif self.thread.ident is None:  # never started
            self._finish()
        return not self.thread.is_alive()


def _on_disk(log: AnyLog) -> dict[str, int]:
    """Messages per topic a recovery of ``log``'s file finds: the confirmed ones, plus those in complete
    chunks after the confirmed point (read back from the file)."""
    d = log.durable
    counts = dict(d.counts)
    if d.path is None or d.complete:
        return counts
    try:
        after = recoverable_messages(d.path, d.offset)
    except (McapReadError, OSError, ValueError) as exc:
        _log.warning("MCAP log %s: could not read back what reached the disk (%s)", d.path, exc)
        return counts
    for cid, n in after.items():
        topic = d.channels.get(cid)
        if topic is not None:
            counts[topic] = counts.get(topic, 0) + n
    return counts


class BackgroundMcapLog:
    """Queue writes to a writer thread (bounded queue; drops are counted, never blocks for long).

    Parameters
    ----------
    log : McapLog | RotatingMcapLog
        The log to write; owned (closed) by this wrapper.
    max_queue : int
        Queue capacity [messages].
    block_s : float
        How long a producer may wait for room in a full queue before dropping [s].
    flush_interval_s : float or None
        Write the open chunk and flush the file at least this often [s] (bounds the loss on a crash).
    poll_s : float
        Writer-thread poll period when the queue is empty [s].
    reopen : Reopen, optional
        Resume in a new file after a write error (e.g. disk full); default: stay stopped.
    fsync : bool
        ``os.fsync`` at each periodic flush (survive a power cut, not only a process crash).
    """

    def __init__(self, log: AnyLog, *, max_queue: int = 10_000, block_s: float = 0.0,
                 flush_interval_s: float | None = 5.0, poll_s: float = 0.01,
                 reopen: Reopen | None = None, fsync: bool = False):
        if isinstance(max_queue, bool) or not isinstance(max_queue, int) or max_queue < 1:
            raise InputError("max_queue", max_queue, "an integer >= 1")
        if not 0.0 <= block_s <= 10.0:
            raise InputError("block_s", block_s, "[0, 10] s")
        if flush_interval_s is not None and not flush_interval_s > 0:
            raise InputError("flush_interval_s", flush_interval_s, "None or > 0 s")
        if not 0.0 < poll_s <= 1.0:
            raise InputError("poll_s", poll_s, "(0, 1] s")
        self._log = log
        self._block_s = float(block_s)
        self._pump = _Pump(log, max_queue, poll_s, flush_interval_s, reopen, fsync)
        self._pump.thread.start()
        self._finalizer = weakref.finalize(self, self._pump.stop, 30.0)

    # -- set-up (synchronous, before or between messages) ----------------------------------
    def add_topic(self, topic: str, msgtype: str, qos: QosSpec = "reliable") -> int:
        """Register a topic at once (see :meth:`McapLog.add_topic`)."""
        cid = self._pump.log.add_topic(topic, msgtype, qos)
        self._pump.topics.setdefault(topic, (msgtype, qos))
        return cid

    def add_metadata(self, name: str, data: Mapping[str, str]) -> bool:
        """Queue a Metadata record (not subject to the queue bound); False after close."""
        if not isinstance(name, str) or not name or not isinstance(data, Mapping) or not all(
                isinstance(k, str) and isinstance(v, str) for k, v in data.items()):
            raise InputError(f"metadata[{name!r}]", data, "a name and a dict[str, str]")
        if not self._pump.accepting:
            return False
        self._pump.queue.append(("meta", (name, dict(data))))
        return True

    # -- messages (any thread) --------------------------------------------------------------
    def write(self, topic: str, msg: Any, log_time_ns: int, publish_time_ns: int | None = None) -> bool:
        """Encode ``msg`` here and queue it; False if dropped (see module doc)."""
        return self.write_raw(topic, self._log.encode(topic, msg), log_time_ns, publish_time_ns)

    def write_raw(self, topic: str, data: bytes | bytearray | memoryview, log_time_ns: int,
                  publish_time_ns: int | None = None, *, sequence: int | None = None) -> bool:
        """Queue serialized bytes (copied); False if dropped.

        Raises
        ------
        InputError
            Unregistered topic or bad time stamps (checked here, not in the thread).
        """
        p = self._pump
        if not p.accepting:
            with p.drop_lock:
                p.dropped_after_close += 1
            return False
        self._log.msgtype_of(topic)  # InputError naming the known topics if unregistered
        log_ns = _check_time("log_time_ns", log_time_ns)
        pub_ns = None if publish_time_ns is None else _check_time("publish_time_ns", publish_time_ns)
        if len(p.queue) >= p.max_queue and not self._wait_for_room():
            with p.drop_lock:
                n = p.dropped[topic] = p.dropped.get(topic, 0) + 1
                total = sum(p.dropped.values())
            if str(total).rstrip("0") == "1":  # 1, 10, 100, ...
                _log.warning("MCAP log queue full (%d): dropped %d message(s) so far (%s: %d)",
                             p.max_queue, total, topic, n)
            return False
        item = ("msg", (topic, bytes(data), log_ns, pub_ns, sequence))
        p.queue.append(item)
        p.n_queued = next(p.queued)
        if not p.accepting:  # closed meanwhile (other thread, or a signal handler in this one)
            try:
                p.queue.remove(item)
            except (ValueError, IndexError, RuntimeError):
                pass  # the writer thread took it: it is written
            else:
                with p.drop_lock:
                    p.retracted += 1
                    p.dropped_after_close += 1
                return False
        depth = len(p.queue)
        if depth > p.max_depth:
            p.max_depth = depth
        return True

    def _wait_for_room(self) -> bool:
        p = self._pump
        deadline = time.monotonic() + self._block_s
        while time.monotonic() < deadline:
            time.sleep(min(0.001, self._block_s))
            if len(p.queue) < p.max_queue:
                return True
        return False

    # -- lifetime -------------------------------------------------------------------------
    def flush(self, timeout_s: float = 5.0) -> bool:
        """Write everything queued so far and flush the file; True if done within ``timeout_s``."""
        p = self._pump
        if not p.accepting or not p.thread.is_alive():
            return False
        done = threading.Event()
        p.queue.append(("flush", done))
        return done.wait(timeout_s)

    def close(self, timeout_s: float | None = 30.0) -> LogStats:
        """Drain the queue, finalise the file, return the counters (idempotent, signal-safe).

        Waits at most ``timeout_s`` [s] (None: until done); if the disk is that
        slow the thread goes on and finishes the file by itself.
        """
        self._finalizer.detach()
        if not self._pump.stop(timeout_s):
            _log.error("MCAP log not finalised within %s s; the writer thread goes on", timeout_s)
        return self._pump.stats()

    def __enter__(self) -> "BackgroundMcapLog":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- introspection --------------------------------------------------------------------
    def stats(self) -> LogStats:
        """Current counters (see :class:`LogStats`)."""
        return self._pump.stats()

    @property
    def error(self) -> BaseException | None:
        """The writer-thread error, if one happened."""
        return self._pump.error

    @property
    def queue_depth(self) -> int:
        return len(self._pump.queue)

    @property
    def closed(self) -> bool:
        return not self._pump.accepting

    @property
    def log(self) -> AnyLog:
        """The log being written (read its ``path``/``paths``; write only through this wrapper)."""
        return self._pump.log

    @property
    def unfinalised(self) -> list:
        """Files closed unfinalised after a write error (recover them with ``log recover``)."""
        return list(self._pump.unfinalised)

    @property
    def topics(self) -> dict[str, str]:
        return self._pump.log.topics
