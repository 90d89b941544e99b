"""MCAP writers for ROS 2 messages, following rosbag2's MCAP conventions (no rclpy).

A file written here is what ``ros2 bag record -s mcap`` would write for the
same topics: Header profile ``ros2``; one Schema per message type, name
``pkg/msg/Type``, encoding ``ros2msg`` (complete definition from the
installed interfaces, see :mod:`~gerotor_twin.io.schemas`); one Channel per
topic, message encoding ``cdr``, metadata ``offered_qos_profiles`` (YAML, see
:mod:`~gerotor_twin.io.qos`) and ``topic_type_hash`` (``RIHS01_...``);
Message records with log time = receive/prediction time [ns] and publish
time [ns]; chunked (zstd by default) with message indexes, chunk indexes,
Statistics, repeated schemas/channels and summary offsets in the summary.
Metadata records carry the pump configuration and node parameters.

:class:`McapLog` writes one file (or stream).  :class:`RotatingMcapLog`
splits a run into ``<stem>_0000.mcap``, ``<stem>_0001.mcap``... by size or
by log-time span; every file is self-contained (schemas, channels and
metadata repeated).  Both are thread-safe (one lock) and their ``close()``
is idempotent, finalises the summary, and may be called from a signal
handler or at interpreter exit (it also runs automatically then); for
writing off the executor thread see :mod:`~gerotor_twin.io.background`.
"""
from __future__ import annotations

import contextlib
import fcntl
import functools
import operator
import os
import re
import struct
import threading
import weakref
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Callable, Iterator, Mapping, Union

import mcap_ros2
from mcap.writer import LIBRARY_IDENTIFIER as _MCAP_LIBRARY
from mcap.writer import CompressionType, Writer

from gerotor_twin import __version__
from gerotor_twin.errors import InputError
from gerotor_twin.io.codec import encoder_for, field_names
from gerotor_twin.io.fastcdr import FAST_ENCODERS
from gerotor_twin.io.qos import QosSpec, resolve_qos
from gerotor_twin.io.rosbag2_meta import ROSBAG2_METADATA, TopicCount, rosbag2_record
from gerotor_twin.io.schemas import SCHEMA_ENCODING, message_definition, normalize_msgtype

__all__ = [
    "PROFILE", "MESSAGE_ENCODING", "LIBRARY", "COMPRESSIONS",
    "PUMP_CONFIG_METADATA", "NODE_PARAMETERS_METADATA", "twin_log_metadata",
    "McapLogClosed", "McapLog", "RotatingMcapLog", "Durable",
]

#: Metadata record names used by the project (values: ``{"yaml": <file text>}`` for the
#: pump configuration, one key per parameter with its value as text for the node).
PUMP_CONFIG_METADATA = "gerotor_twin.pump_config"
NODE_PARAMETERS_METADATA = "gerotor_twin.node_parameters"



def twin_log_metadata(config_yaml: str, config_source: str, parameters: dict,
                      extra: dict[str, dict] | None = None) -> dict[str, dict[str, str]]:
    """The Metadata records of every twin log, the node's and run-bag's alike.

    ``gerotor_twin.pump_config``: the pump YAML text and where it came from;
    ``gerotor_twin.node_parameters``: one key per parameter, the value as text
    (strings quoted, as ``repr``); ``gerotor_twin.software``: version and git revision
    (:func:`gerotor_twin.software.software_identity`); ``extra``: further records by name.
    """
    from gerotor_twin.software import SOFTWARE_METADATA, software_identity
    meta = {PUMP_CONFIG_METADATA: {"yaml": config_yaml, "path": str(config_source)},
            NODE_PARAMETERS_METADATA: {k: repr(v) if isinstance(v, str) else str(v) for k, v in parameters.items()},
            SOFTWARE_METADATA: dict(software_identity())}
    meta.update(extra or {})
    return meta


PROFILE = "ros2"
MESSAGE_ENCODING = "cdr"
LIBRARY = f"gerotor_twin/{__version__} {_MCAP_LIBRARY} mcap-ros2-support/{mcap_ros2.__version__}"
COMPRESSIONS = {"zstd": CompressionType.ZSTD, "lz4": CompressionType.LZ4, "none": CompressionType.NONE}

_U64 = 2**64
_U32 = 2**32
_MAGIC_SIZE = 8     # b"\x89MCAP0\r\n": the first record starts after it [bytes]
# Message record overhead in a chunk: opcode 1, length 8, channel 2, sequence 4,
# log/publish time 16; plus its message-index entry (16).
_MESSAGE_OVERHEAD = 47
_TOKEN = r"[A-Za-z_][A-Za-z0-9_]*"
_TOPIC_RE = re.compile(rf"^/?{_TOKEN}(/{_TOKEN})*$")

PathOrStream = Union[str, "os.PathLike[str]", IO[bytes]]


class McapLogClosed(RuntimeError):
    """A write was attempted on a log that is already closed."""


def _check_time(field: str, value: int) -> int:
    try:
        v = operator.index(value)
    except TypeError:
        raise InputError(field, value, "an integer number of nanoseconds") from None
    if not 0 <= v < _U64:
        raise InputError(field, value, f"[0, {_U64}) ns")
    return v


def _check_str_map(field: str, data: Mapping[str, str]) -> dict[str, str]:
    if not isinstance(data, Mapping) or not all(
            isinstance(k, str) and isinstance(v, str) for k, v in data.items()):
        raise InputError(field, data, "a dict[str, str]")
    return dict(data)


@dataclass
class _Topic:
    msgtype: str
    qos: str
    channel_id: int
    sequence: int = 0
    type_hash: str = ""


@dataclass(frozen=True)
class Durable:
    """What a log is known to hold on disk: its last confirmed point.

    Messages are confirmed when the chunk holding them has been handed to the
    OS (the stream flushed after the chunk, or the file finalised).  After a
    write error (disk full) the file may hold more: complete chunks after
    ``offset``, which :func:`gerotor_twin.io.recover.recoverable_messages` counts.

    Attributes
    ----------
    path : Path or None
        The file (None for a stream).
    offset : int
        Bytes of the file known to be written; the first byte of a record [bytes].
    counts : dict[str, int]
        Messages per topic before ``offset`` [-].
    channels : dict[int, str]
        Channel id -> topic, to read further counts by channel.
    complete : bool
        The file was finalised: ``counts`` are all its messages, nothing to read back.
    """

    path: Path | None
    offset: int
    counts: dict[str, int]
    channels: dict[int, str]
    complete: bool = False

    @functools.cached_property
    def messages(self) -> int:
        """All messages before ``offset`` [-]."""
        return sum(self.counts.values())


def _bag_metadata(name: str, compression: str, topics: dict[str, _Topic], counts: dict[str, int],
                  span: list) -> dict[str, str]:
    """The ``rosbag2`` record of a file from the writer's own bookkeeping (no McapLog reference)."""
    return rosbag2_record(name, [TopicCount(k, t.msgtype, t.qos, t.type_hash, counts.get(k, 0))
                                 for k, t in topics.items()], span[0], span[1], compression)


class _Sink:
    """The open mcap Writer and what closing it needs (no reference to the McapLog).

    ``lock`` is re-entrant; ``owner`` is the thread inside :meth:`guard`.  A
    ``close()`` from a signal handler that interrupted that same thread is
    deferred to the end of the interrupted operation instead of corrupting it.
    """

    def __init__(self, writer: Writer, stream: IO[bytes], own_stream: bool, name: str,
                 final_metadata: Callable[[], dict[str, str]] | None = None):
        self.writer = writer
        self.stream = stream
        self.own_stream = own_stream
        self.name = name
        self.final_metadata = final_metadata
        self.abandoned = False
        self.lock = threading.RLock()
        self.owner: int | None = None
        self.closed = False
        self.close_pending = False

    @contextlib.contextmanager
    def guard(self) -> Iterator[Writer]:
        try:
            with self.lock:
                self.owner = threading.get_ident()
                try:
                    if self.closed:
                        raise McapLogClosed(f"{self.name}: the MCAP log is closed")
                    yield self.writer
                finally:
                    self.owner = None
        finally:
            if self.close_pending:
                self.close()

    def close(self) -> None:
        if self.owner == threading.get_ident():
            self.close_pending = True
            return
        with self.lock:
            if self.closed:
                return
            self.owner = threading.get_ident()
            try:
                if self.abandoned:      # after a write error: keep the valid prefix as it is
                    return
                if self.final_metadata is not None:
                    self.writer.add_metadata(ROSBAG2_METADATA, self.final_metadata())
                self.writer.finish()
            finally:
                self.closed = True
                self.owner = None
                if self.own_stream:
                    _close_quietly(self.stream, raise_error=not self.abandoned)
                else:
                    self.stream.flush()


def _close_quietly(stream: IO[bytes], raise_error: bool) -> None:
    """Close a file; after a write error the unwritable buffer is discarded, not raised again."""
    try:
        stream.close()
    except OSError:
        if raise_error:
            raise


class McapLog:
    """Write ROS 2 messages to one MCAP file or stream, the way rosbag2 does.

    Parameters
    ----------
    output : str | os.PathLike | binary stream
        File to create, or a writable binary stream (e.g. ``io.BytesIO``; it is
        flushed, not closed, by :meth:`close`).
    compression : {'zstd', 'lz4', 'none'}
        Chunk compression.
    chunk_size : int
        Uncompressed chunk size that triggers writing a chunk [bytes].
    metadata : dict[str, dict[str, str]], optional
        Metadata records written at once (e.g. ``{"gerotor_twin.pump_config": {...}}``).
    overwrite : bool
        Replace an existing file (default: refuse, so that no log is lost).
    library : str
        Header ``library`` string.
    close_at_exit : bool
        Finalise the file if the log is garbage-collected or the interpreter
        exits while it is open (default True).

    Raises
    ------
    InputError
        Bad option, or the file exists and ``overwrite`` is false.
    """

    def __init__(self, output: PathOrStream, *, compression: str = "zstd",
                 chunk_size: int = 1 << 20, metadata: Mapping[str, Mapping[str, str]] | None = None,
                 overwrite: bool = False, library: str = LIBRARY, close_at_exit: bool = True):
        if compression not in COMPRESSIONS:
            raise InputError("compression", compression, " | ".join(COMPRESSIONS))
        if isinstance(chunk_size, bool) or not isinstance(chunk_size, int) or chunk_size <= 0:
            raise InputError("chunk_size", chunk_size, "an integer > 0 bytes")
        self._path: Path | None
        if isinstance(output, (str, os.PathLike)):
            self._path = Path(output)
            try:
                stream: IO[bytes] = open(self._path, "wb" if overwrite else "xb")
            except FileExistsError:
                raise InputError("path", str(self._path), "a file that does not exist yet",
                                 "pass overwrite=True to replace it") from None
            own, name = True, str(self._path)
            _lock_for_writing(stream)
        else:
            self._path, stream, own, name = None, output, False, f"<{type(output).__name__}>"
        try:
            writer = Writer(stream, chunk_size=chunk_size, compression=COMPRESSIONS[compression])
        except Exception:
            if own:
                stream.close()
            raise
        self._topics: dict[str, _Topic] = {}
        self._counts: dict[str, int] = {}
        self._span: list = [None, None]     # first, last message log time [ns]
        final = functools.partial(_bag_metadata, Path(name).name if own else name, compression,
                                  self._topics, self._counts, self._span)
        self._sink = _Sink(writer, stream, own, name, final)
        # Finalise the file if the log is garbage-collected or the interpreter exits unclosed.
        self._finalizer = weakref.finalize(self, self._sink.close)
        if not close_at_exit:
            self._finalizer.detach()
        self._stream = stream
        self._schema_ids: dict[str, int] = {}
        self._tell = self._safe_tell()
        self._unflushed = 0
        self._durable = Durable(self._path, _MAGIC_SIZE, {}, {})    # what is known to be in the file
        with self._sink.guard() as w:
            w.start(profile=PROFILE, library=library)
            self._tell = self._safe_tell()      # magic and header: not a chunk
        for mname, data in (metadata or {}).items():
            self.add_metadata(mname, data)

    # -- set-up ---------------------------------------------------------------------------
    def add_topic(self, topic: str, msgtype: str, qos: QosSpec = "reliable") -> int:
        """Register a topic (Schema once per type, then a Channel); return its channel id.

        Parameters
        ----------
        topic : str
            Topic name as recorded; use the fully qualified name (``/bench/shaft_speed``).
        msgtype : str
            ``pkg/msg/Type`` (or ``pkg/Type``) of an installed interface.
        qos : 'sensor' | 'reliable' | QosProfile | list of QosProfile | str
            Offered QoS for ``offered_qos_profiles`` (a YAML string is validated and kept).

        Registering the same topic again with the same type and QoS returns the same id.

        Raises
        ------
        InputError
            Bad topic name, unknown type, bad QoS, or the topic exists with another type/QoS.
        """
        if not isinstance(topic, str) or not _TOPIC_RE.match(topic):
            raise InputError("topic", topic, "a ROS topic name such as '/bench/shaft_speed'")
        definition = message_definition(normalize_msgtype(msgtype))
        qos_yaml = resolve_qos(qos)
        with self._sink.guard() as w:
            known = self._topics.get(topic)
            if known is not None:
                if (known.msgtype, known.qos) != (definition.msgtype, qos_yaml):
                    raise InputError("topic", topic,
                                     f"one type and QoS per topic (already {known.msgtype})")
                return known.channel_id
            schema_id = self._schema_ids.get(definition.msgtype)
            if schema_id is None:
                schema_id = w.register_schema(definition.msgtype, SCHEMA_ENCODING,
                                              definition.text.encode("utf-8"))
                self._schema_ids[definition.msgtype] = schema_id
            channel_id = w.register_channel(
                topic, MESSAGE_ENCODING, schema_id,
                {"offered_qos_profiles": qos_yaml, "topic_type_hash": definition.type_hash})
            self._topics[topic] = _Topic(definition.msgtype, qos_yaml, channel_id,
                                         type_hash=definition.type_hash)
            self._counts[topic] = 0
            if self._safe_tell() != self._tell:     # the records filled a chunk: it went to the stream
                self._chunk_written()
        return channel_id

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """Write a Metadata record (``name`` and string key/values, e.g. pump config YAML)."""
        if not isinstance(name, str) or not name:
            raise InputError("metadata name", name, "a non-empty string")
        data = _check_str_map(f"metadata[{name!r}]", data)
        with self._sink.guard() as w:
            w.add_metadata(name, data)
            self._tell = self._safe_tell()      # a record beside the open chunk, which stays open

    # -- messages -------------------------------------------------------------------------
    def msgtype_of(self, topic: str) -> str:
        """``pkg/msg/Type`` of a registered topic (InputError naming the known topics if not)."""
        return self._topic(topic).msgtype

    def encode(self, topic: str, msg: Any) -> bytes:
        """CDR bytes of ``msg`` (dict with field names, or object) for ``topic``'s type: the twin's periodic
        outputs as dicts (Float64MultiArray, Float64, FluidPressure, JointState, Vector3Stamped) by
        :mod:`~gerotor_twin.io.fastcdr`, as the node publishes them (tens of thousands per minute of a run,
        ≈ 1 µs each against 20–60 µs by the generic encoder); anything else by :func:`~.codec.encoder_for`, and so
        is a dict whose top-level fields differ from the type's, or that the fast encoder cannot read (a
        misspelt nested field, a value that is not a number): the generic encoder's error names what is wrong.
        An unknown field nested inside a known one is not seen on the fast path."""
        msgtype = self._topic(topic).msgtype
        if isinstance(msg, dict):
            fast = FAST_ENCODERS.get(msgtype)
            if fast is not None and msg.keys() == field_names(msgtype):   # else the generic error names it
                try:
                    return fast(msg)
                except (KeyError, TypeError, ValueError, OverflowError, struct.error):
                    pass           # a misspelt nested field or a bad value: the generic error names it
        return encoder_for(msgtype)(msg)

    def write(self, topic: str, msg: Any, log_time_ns: int, publish_time_ns: int | None = None) -> None:
        """Encode ``msg`` (dict/object, see :mod:`~gerotor_twin.io.messages`) and log it.

        Parameters
        ----------
        log_time_ns, publish_time_ns : int
            Log (prediction/receive) and publish time [ns]; publish defaults to log time.
        """
        self.write_raw(topic, self.encode(topic, msg), log_time_ns, publish_time_ns)

    def write_raw(self, topic: str, data: bytes | bytearray | memoryview, log_time_ns: int,
                  publish_time_ns: int | None = None, *, sequence: int | None = None) -> None:
        """Log serialized CDR bytes as received (e.g. from a ``raw=True`` subscription), untouched.

        Parameters
        ----------
        data : bytes-like
            The serialized message including its 4-byte encapsulation header.
        log_time_ns, publish_time_ns : int
            Receive and source time [ns]; publish defaults to log time.
        sequence : int, optional
            Publisher sequence number; default: a per-topic counter from 1.

        Raises
        ------
        InputError
            Unregistered topic, bad times, or fewer than 4 bytes.
        McapLogClosed
            After :meth:`close`.
        """
        t = self._topic(topic)
        log_ns = _check_time("log_time_ns", log_time_ns)
        pub_ns = log_ns if publish_time_ns is None else _check_time("publish_time_ns", publish_time_ns)
        payload = bytes(data)
        if len(payload) < 4:
            raise InputError("data", payload, "serialized CDR (>= 4 bytes with encapsulation header)")
        with self._sink.guard() as w:
            t.sequence += 1
            seq = t.sequence if sequence is None else operator.index(sequence)
            w.add_message(t.channel_id, log_ns, payload, pub_ns, seq % _U32)
            self._counts[topic] += 1
            span = self._span
            span[0] = log_ns if span[0] is None else min(span[0], log_ns)
            span[1] = log_ns if span[1] is None else max(span[1], log_ns)
            if self._safe_tell() != self._tell:  # a chunk (with this message) went to the stream
                self._chunk_written()
            else:
                self._unflushed += len(payload) + _MESSAGE_OVERHEAD

    # -- lifetime -------------------------------------------------------------------------
    def flush(self, fsync: bool = False) -> None:
        """Write the open chunk and flush the stream (data then survives a crash of the process).

        Parameters
        ----------
        fsync : bool
            Also ``os.fsync`` the file (survives a power cut; costs a disk round trip).
        """
        with self._sink.guard() as w:
            w.flush()
            if fsync and self._sink.own_stream:
                os.fsync(self._stream.fileno())
            self._confirm()

    def abandon(self) -> None:
        """Close without finalising, after a write error (e.g. disk full); idempotent.

        What reached the file stays as it is: readable with
        :func:`~gerotor_twin.io.reader.open_mcap` and made a finalised copy by
        :func:`~gerotor_twin.io.recover.recover` (``gerotor-twin log recover``).
        """
        self._sink.abandoned = True
        self.close()

    def close(self) -> None:
        """Finalise (summary, statistics, indexes, footer) and close; idempotent, signal-safe.

        Called from a signal handler that interrupted a write of this same
        thread, the close happens right after that write completes.

        Raises
        ------
        OSError
            If the file cannot be finalised (e.g. disk full); it is closed anyway.
        """
        self._finalizer()  # runs _sink.close() once and drops the at-exit hook
        self._sink.close()  # no-op unless already closed or deferred
        if self._sink.closed and not self._sink.abandoned:      # finalised: every message is in the file
            self._durable = Durable(self._path, self._durable.offset, dict(self._counts),
                                    self._durable.channels, complete=True)

    def __enter__(self) -> "McapLog":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    # -- introspection --------------------------------------------------------------------
    @property
    def closed(self) -> bool:
        return self._sink.closed

    @property
    def path(self) -> Path | None:
        """File written, or None for a stream."""
        return self._path

    @property
    def topics(self) -> dict[str, str]:
        """Registered topics: ``{topic: pkg/msg/Type}``."""
        return {k: v.msgtype for k, v in self._topics.items()}

    @property
    def message_counts(self) -> dict[str, int]:
        """Messages written per topic."""
        return dict(self._counts)

    @property
    def message_count(self) -> int:
        return sum(self._counts.values())

    @property
    def first_log_time_ns(self) -> int | None:
        return self._span[0]

    @property
    def last_log_time_ns(self) -> int | None:
        return self._span[1]

    @property
    def size_estimate(self) -> int:
        """Bytes in the file plus the (uncompressed) chunk still in memory [bytes]."""
        return self._tell + self._unflushed

    @property
    def durable(self) -> "Durable":
        """What is known to be in the file (written to the OS): see :class:`Durable`."""
        return self._durable

    @property
    def confirmed_messages(self) -> int:
        """Messages known to be in the file (:attr:`durable`; the open chunk is not) [-]."""
        return self._durable.messages

    def _chunk_written(self) -> None:
        """A chunk went to the stream: hand it to the OS and count its messages as in the file."""
        self._stream.flush()
        self._confirm()

    def _confirm(self) -> None:
        """Everything so far has reached the OS (after a successful flush): move :attr:`durable` here."""
        self._tell, self._unflushed = self._safe_tell(), 0
        self._durable = Durable(self._path, self._tell, dict(self._counts),
                                {t.channel_id: k for k, t in self._topics.items()})

    def _topic(self, topic: str) -> _Topic:
        t = self._topics.get(topic)
        if t is None:
            raise InputError("topic", topic, "a topic registered with add_topic(): "
                             + (", ".join(self._topics) or "(none yet)"))
        return t

    def _safe_tell(self) -> int:
        try:
            return self._stream.tell()
        except (OSError, ValueError):
            return 0


def _lock_for_writing(stream: IO[bytes]) -> None:
    """Hold an exclusive ``flock`` on a file being written, so that recovery skips live files.

    The lock goes with the process: after a crash (SIGKILL, power cut) nobody
    holds it and :func:`gerotor_twin.io.recover.unfinalised_logs` may recover the file.
    """
    try:
        fcntl.flock(stream.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
    except OSError:
        pass  # no flock here (some network file systems): a live file may then be copied by
        # recovery too; recovery only reads the original, so the live file is never harmed


def _close_current(current: list[McapLog]) -> None:
    current[0].close()


class RotatingMcapLog:
    """Same API as :class:`McapLog`, split into ``<stem>_0000.mcap``, ``<stem>_0001.mcap``...

    A new file is started before a message would be written to a file that has
    reached ``max_bytes`` (:attr:`McapLog.size_estimate`: file plus open chunk,
    so a file may exceed it by about one compressed chunk and the summary), or
    whose first message is ``max_duration_s`` or more older (log time) than
    the new one.  Every file repeats all schemas, channels and metadata, so
    each is readable and playable on its own; no message is split or lost.

    Parameters
    ----------
    directory : str | os.PathLike
        Created if missing.
    stem : str
        File name stem (no path separator).
    max_bytes : int, optional
        Size limit [bytes] (>= 1024).
    max_duration_s : float, optional
        Log-time span per file [s] (> 0).
    **options
        ``compression``, ``chunk_size``, ``metadata``, ``overwrite``, ``library``
        as for :class:`McapLog`.
    """

    def __init__(self, directory: str | os.PathLike[str], stem: str, *, max_bytes: int | None = None,
                 max_duration_s: float | None = None, compression: str = "zstd",
                 chunk_size: int = 1 << 20, metadata: Mapping[str, Mapping[str, str]] | None = None,
                 overwrite: bool = False, library: str = LIBRARY):
        if not isinstance(stem, str) or not stem or "/" in stem or os.sep in stem:
            raise InputError("stem", stem, "a file name stem without path separators")
        if max_bytes is not None and (isinstance(max_bytes, bool) or not isinstance(max_bytes, int)
                                      or max_bytes < 1024):
            raise InputError("max_bytes", max_bytes, "None or an integer >= 1024 bytes")
        if max_duration_s is not None and not (isinstance(max_duration_s, (int, float))
                                               and 0 < max_duration_s < 1e9):
            raise InputError("max_duration_s", max_duration_s, "None or (0, 1e9) s")
        self._dir = Path(directory)
        self._dir.mkdir(parents=True, exist_ok=True)
        self._stem = stem
        self._max_bytes = max_bytes
        self._max_ns = None if max_duration_s is None else int(round(max_duration_s * 1e9))
        self._options = dict(compression=compression, chunk_size=chunk_size,
                             overwrite=overwrite, library=library)
        self._topics: dict[str, tuple[str, QosSpec]] = {}
        self._metadata: list[tuple[str, dict[str, str]]] = []
        self._paths: list[Path] = []
        self._counts: dict[str, int] = {}
        self._done: dict[str, int] = {}      # messages per topic of the files closed (finalised) so far
        self._lock = threading.RLock()
        self._current: list[McapLog] = [self._open(0)]
        # One at-exit/GC hook for whichever file is current (created before any wrapper's hook,
        # so a BackgroundMcapLog around this log drains its queue first).
        self._finalizer = weakref.finalize(self, _close_current, self._current)
        for mname, data in (metadata or {}).items():
            self.add_metadata(mname, data)

    def _open(self, index: int) -> McapLog:
        path = self._dir / f"{self._stem}_{index:04d}.mcap"
        log = McapLog(path, close_at_exit=False, **self._options)  # type: ignore[arg-type]
        self._paths.append(path)
        for topic, (msgtype, qos) in self._topics.items():
            log.add_topic(topic, msgtype, qos)
        for mname, data in self._metadata:
            log.add_metadata(mname, data)
        return log

    @property
    def _log(self) -> McapLog:
        return self._current[0]

    def _rotate_if_due(self, log_time_ns: int) -> None:
        log = self._log
        if log.message_count == 0:
            return
        due = (self._max_bytes is not None and log.size_estimate >= self._max_bytes) or \
              (self._max_ns is not None and log.first_log_time_ns is not None
               and log_time_ns - log.first_log_time_ns >= self._max_ns)
        if due:
            for k, v in log.message_counts.items():
                self._counts[k] = self._counts.get(k, 0) + v
            log.close()
            new = self._open(len(self._paths))
            self._done = _merged(self._done, log.durable.counts)
            self._current[0] = new

    def add_topic(self, topic: str, msgtype: str, qos: QosSpec = "reliable") -> int:
        """See :meth:`McapLog.add_topic`; the topic is re-registered in every later file."""
        with self._lock:
            cid = self._log.add_topic(topic, msgtype, qos)
            self._topics.setdefault(topic, (msgtype, qos))
            return cid

    def add_metadata(self, name: str, data: Mapping[str, str]) -> None:
        """See :meth:`McapLog.add_metadata`; repeated in every later file."""
        with self._lock:
            self._log.add_metadata(name, data)
            self._metadata.append((name, dict(data)))

    def msgtype_of(self, topic: str) -> str:
        """See :meth:`McapLog.msgtype_of`."""
        return self._log.msgtype_of(topic)

    def encode(self, topic: str, msg: Any) -> bytes:
        """See :meth:`McapLog.encode`."""
        return self._log.encode(topic, msg)

    def write(self, topic: str, msg: Any, log_time_ns: int, publish_time_ns: int | None = None) -> None:
        self.write_raw(topic, self.encode(topic, msg), log_time_ns, publish_time_ns)

    def write_raw(self, topic: str, data: bytes | bytearray | memoryview, log_time_ns: int,
                  publish_time_ns: int | None = None, *, sequence: int | None = None) -> None:
        with self._lock:
            self._log.msgtype_of(topic)  # unknown topic: fail before rotating
            self._rotate_if_due(_check_time("log_time_ns", log_time_ns))
            self._log.write_raw(topic, data, log_time_ns, publish_time_ns, sequence=sequence)

    def flush(self, fsync: bool = False) -> None:
        with self._lock:
            self._log.flush(fsync)

    def close(self) -> None:
        """Close the current file (idempotent, signal-safe like :meth:`McapLog.close`)."""
        self._finalizer()
        self._log.close()

    def abandon(self) -> None:
        """Close the current file without finalising it (see :meth:`McapLog.abandon`)."""
        self._finalizer.detach()
        self._log.abandon()

    def __enter__(self) -> "RotatingMcapLog":
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()

    @property
    def closed(self) -> bool:
        return self._log.closed

    @property
    def paths(self) -> list[Path]:
        """Files written so far, in order."""
        return list(self._paths)

    @property
    def path(self) -> Path:
        """The file being written."""
        return self._paths[-1]

    @property
    def topics(self) -> dict[str, str]:
        return self._log.topics

    @property
    def message_counts(self) -> dict[str, int]:
        """Messages written per topic over all files."""
        out = dict(self._counts)
        for k, v in self._log.message_counts.items():
            out[k] = out.get(k, 0) + v
        return out

    @property
    def message_count(self) -> int:
        return sum(self.message_counts.values())

    @property
    def durable(self) -> Durable:
        """As :attr:`McapLog.durable` for the file being written, with the counts of the closed files added."""
        cur = self._log.durable
        return Durable(cur.path, cur.offset, _merged(self._done, cur.counts), cur.channels, cur.complete)

    @property
    def confirmed_messages(self) -> int:
        """Messages known to be on disk over all files [-]."""
        return sum(self._done.values()) + self._log.confirmed_messages


def _merged(a: dict[str, int], b: dict[str, int]) -> dict[str, int]:
    """Per-topic counts added."""
    out = dict(a)
    for k, v in b.items():
        out[k] = out.get(k, 0) + v
    return out
