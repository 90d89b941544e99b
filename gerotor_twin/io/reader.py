"""Read ROS 2 MCAP logs back (reports, offline runs), with clear errors and crash recovery.

:func:`open_mcap` checks a file and gives a :class:`McapFile`:

========================  ===================================================
file                      result
========================  ===================================================
missing / a directory     :class:`McapReadError` "does not exist" / "is a directory"
0 bytes                   :class:`McapReadError` "empty file"
no MCAP magic             :class:`McapReadError` "not an MCAP file"
truncated (crash, copy)   read as far as valid: every record before the cut
                          is recovered (a chunk cut in two is lost); a
                          :class:`TruncatedMcapWarning` names the file, the
                          byte offset and the number of messages recovered
corrupt chunk / record    :class:`McapReadError` naming the byte offset
                          (CRC, decompression or parse error)
========================  ===================================================

Messages are read by one linear pass over the data section (no reliance on
the index, so chunked, unchunked and truncated files are read alike) and
decoded with ``mcap_ros2`` from the schema embedded in the file, not from the
installed interfaces.  :func:`read_topics` returns per-topic
:class:`TopicSeries` sorted by log time; :func:`scalar_series` and
:func:`multiarray_series` turn them into NumPy arrays.
"""
from __future__ import annotations

import io
import re
import struct
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Callable, Iterable, Iterator, Mapping, Sequence, Union

import numpy as np
from mcap.exceptions import McapError
from mcap.opcode import Opcode
from mcap.reader import SeekingReader
from mcap.records import Channel, Chunk, DataEnd, Header, Message, Metadata, Schema
from mcap.stream_reader import StreamReader, breakup_chunk
from mcap_ros2.decoder import DecoderFactory

from gerotor_twin.errors import InputError
from gerotor_twin.io import cdr_arrays
from gerotor_twin.io.messages import ns_from_stamp
from gerotor_twin.io.schemas import normalize_msgtype

__all__ = [
    "McapReadError", "TruncatedMcapWarning", "McapFile", "TopicSeries",
    "open_mcap", "read_topics", "topic_types", "metadata", "require",
    "scalar_series", "multiarray_series", "multiarray_values",
]

cdr_arrays.apply()            # numeric array fields in one struct call each (cdr_arrays: 7 of a report's 14 s)

PathLike = Union[str, Path]
#: A file path, or an MCAP already in memory (bytes or a binary stream such as io.BytesIO).
Source = Union[str, Path, bytes, bytearray, memoryview, IO[bytes]]
_MAGIC = b"\x89MCAP0\r\n"
_RECORD_HEADER = struct.Struct("<BQ")


class McapReadError(ValueError):
    """An MCAP file cannot be read; the message names the file and what is wrong.

    Parameters
    ----------
    source : str, Path, bytes or binary stream
        A file, or an MCAP in memory (e.g. the ``io.BytesIO`` a :class:`McapLog` wrote).
        The file.
    what : str
        What is wrong with it.
    """

    def __init__(self, path: PathLike, what: str):
        self.path = str(path)
        self.what = what
        super().__init__(f"{self.path}: {what}")


class TruncatedMcapWarning(UserWarning):
    """A truncated MCAP file was read as far as it is valid."""


class _Truncated(Exception):
    def __init__(self, offset: int):
        self.offset = offset


@dataclass(frozen=True, eq=False)
class McapFile:
    """A checked MCAP file (no file handle is kept open).

    Attributes
    ----------
    path : Path or str
        The file, or ``"<memory>"`` for an in-memory MCAP.
    size : int
        File size [bytes].
    profile, library : str
        From the Header record.
    complete : bool
        True if the file has a valid footer and summary; False if truncated.
    truncated_at : int or None
        Byte offset of the first incomplete record (truncated files).
    schemas, channels : dict[int, Schema], dict[int, Channel]
    metadata : dict[str, dict[str, str]]
        Metadata records by name (a later record of the same name wins).
    message_count : int
        Messages in the file (Statistics record), or recovered (truncated file).
    """

    path: Path | str
    size: int
    profile: str
    library: str
    complete: bool
    truncated_at: int | None
    schemas: dict[int, Schema]
    channels: dict[int, Channel]
    metadata: dict[str, dict[str, str]]
    message_count: int
    _open: Callable[[], IO[bytes]] = field(default=None, repr=False)  # type: ignore[assignment]
    _decoders: dict[int, Callable[[bytes], Any]] = field(default_factory=dict, repr=False)

    def topic_types(self) -> dict[str, str]:
        """``{topic: pkg/msg/Type}`` (schema name) of every channel."""
        return {c.topic: (self.schemas[c.schema_id].name if c.schema_id in self.schemas else "")
                for c in self.channels.values()}

    def iter_raw(self, topics: Iterable[str] | None = None) -> Iterator[tuple[Channel, Message]]:
        """Messages in file order as ``(channel, message)`` (raw CDR in ``message.data``).

        Raises
        ------
        McapReadError
            At a corrupt chunk or record (offset named).
        """
        wanted = None if topics is None else set(topics)
        channels = dict(self.channels)
        try:
            yield from self._iter_raw(wanted, channels)
        except _Truncated as cut:  # the footer said complete: a length field is damaged
            raise McapReadError(self.path, f"corrupt record at byte {cut.offset}: "
                                           "its length runs past the end of the file") from None

    def _iter_raw(self, wanted: set[str] | None, channels: dict[int, Channel]
                  ) -> Iterator[tuple[Channel, Message]]:
        for offset, rec in _expanded(self._open, self.path, self.size, stop_at=self.truncated_at):
            if isinstance(rec, Channel):
                channels.setdefault(rec.id, rec)
            elif isinstance(rec, Message):
                ch = channels.get(rec.channel_id)
                if ch is None:
                    raise McapReadError(self.path, f"message at byte {offset} refers to "
                                                   f"unknown channel {rec.channel_id}")
                if wanted is None or ch.topic in wanted:
                    yield ch, rec

    def decode(self, channel: Channel, message: Message) -> Any:
        """Decode one message with ``mcap_ros2`` from the file's own schema."""
        decoder = self._decoders.get(channel.id)
        if decoder is None:
            schema = self.schemas.get(channel.schema_id)
            try:
                decoder = DecoderFactory().decoder_for(channel.message_encoding, schema)
            except Exception as exc:
                raise McapReadError(self.path,
                                    f"schema of {channel.topic} cannot be parsed: {exc}") from None
            if decoder is None:
                raise McapReadError(self.path, f"{channel.topic}: cannot decode encoding "
                                               f"{channel.message_encoding!r} with schema encoding "
                                               f"{getattr(schema, 'encoding', None)!r} "
                                               "(need cdr / ros2msg)")
            self._decoders[channel.id] = decoder
        try:
            return decoder(message.data)
        except Exception as exc:
            raise McapReadError(self.path, f"message on {channel.topic} at log time "
                                           f"{message.log_time} ns cannot be decoded: {exc}") from None


def _records(opener: Callable[[], IO[bytes]], path: Path | str, size: int,
             stop_at: int | None = None, start: int | None = None) -> Iterator[tuple[int, Any]]:
    """Top-level records of the data section as ``(offset, record)``; Chunks not expanded.

    Starts after the magic, or at byte ``start`` (the first byte of a record).
    Stops after DataEnd / Footer.  Raises :class:`_Truncated` where a record
    runs past the end of the file, :class:`McapReadError` for a record that is
    complete but cannot be parsed.
    """
    with opener() as f:
        pos = len(_MAGIC) if start is None else max(len(_MAGIC), int(start))
        f.seek(pos)
        while True:
            if stop_at is not None and pos >= stop_at:
                return
            head = f.read(_RECORD_HEADER.size)
            if len(head) < _RECORD_HEADER.size:
                raise _Truncated(pos)
            opcode, length = _RECORD_HEADER.unpack(head)
            if pos + _RECORD_HEADER.size + length > size:
                raise _Truncated(pos)
            body = f.read(length)
            if opcode == Opcode.FOOTER:
                return
            try:
                record = next(StreamReader(io.BytesIO(head + body), skip_magic=True,
                                           emit_chunks=True).records, None)
            except Exception as exc:
                raise McapReadError(path, f"corrupt record (opcode {opcode:#04x}) at byte {pos}: "
                                          f"{exc or type(exc).__name__}") from None
            if record is not None:
                yield pos, record
            if isinstance(record, DataEnd):
                return
            pos += _RECORD_HEADER.size + length


def _expanded(opener: Callable[[], IO[bytes]], path: Path | str, size: int,
              stop_at: int | None = None) -> Iterator[tuple[int, Any]]:
    """Like :func:`_records`, with the records inside each Chunk (CRC-checked) in its place."""
    for offset, record in _records(opener, path, size, stop_at):
        if isinstance(record, Chunk):
            try:
                inner = breakup_chunk(record, validate_crc=True)
            except Exception as exc:
                raise McapReadError(path, f"corrupt chunk at byte {offset}: {exc}") from None
            for rec in inner:
                yield offset, rec
        else:
            yield offset, record


def _source(source: Source) -> tuple[Path | str, Callable[[], IO[bytes]], int]:
    """Name, opener (fresh binary stream) and size of a file or in-memory MCAP, checked."""
    if isinstance(source, (str, Path)):
        path: Path | str = Path(source)
        assert isinstance(path, Path)
        if not path.exists():
            raise McapReadError(path, "file does not exist")
        if path.is_dir():
            raise McapReadError(path, "is a directory, not an MCAP file")
        size = path.stat().st_size
        opener: Callable[[], IO[bytes]] = lambda: open(path, "rb")  # noqa: E731
    else:
        if isinstance(source, (bytes, bytearray, memoryview)):
            data = bytes(source)
        elif isinstance(source, io.BytesIO):
            data = source.getvalue()
        else:
            source.seek(0)
            data = source.read()
        path, size = "<memory>", len(data)
        opener = lambda: io.BytesIO(data)  # noqa: E731
    if size == 0:
        raise McapReadError(path, "empty file (0 bytes), not an MCAP log")
    with opener() as f:
        head = f.read(len(_MAGIC))
    if head != _MAGIC:
        raise McapReadError(path, f"not an MCAP file (starts with {head[:8]!r}, "
                                  f"expected magic {_MAGIC!r})")
    return path, opener, size


def _from_summary(opener: Callable[[], IO[bytes]], path: Path | str, size: int) -> McapFile | None:
    """A complete file's contents from its summary, or None if there is no valid summary."""
    with opener() as f:
        f.seek(size - len(_MAGIC))
        if f.read() != _MAGIC:
            return None
        try:
            f.seek(0)
            reader = SeekingReader(f, validate_crcs=True)
            header = reader.get_header()
            summary = reader.get_summary()
            if summary is None or summary.statistics is None:
                return None
            meta = {m.name: dict(m.metadata) for m in reader.iter_metadata()}
        except (McapError, struct.error, ValueError, EOFError, OSError):
            return None
    return McapFile(path, size, header.profile, header.library, True, None,
                    dict(summary.schemas), dict(summary.channels), meta,
                    summary.statistics.message_count, opener)


def _by_scan(opener: Callable[[], IO[bytes]], path: Path | str, size: int) -> McapFile:
    """Contents of a file without a valid summary, read as far as valid."""
    schemas: dict[int, Schema] = {}
    channels: dict[int, Channel] = {}
    meta: dict[str, dict[str, str]] = {}
    profile = library = ""
    count = 0
    truncated_at = None
    try:
        for _, rec in _expanded(opener, path, size):
            if isinstance(rec, Schema):
                schemas.setdefault(rec.id, rec)
            elif isinstance(rec, Channel):
                channels.setdefault(rec.id, rec)
            elif isinstance(rec, Message):
                count += 1
            elif isinstance(rec, Metadata):
                meta[rec.name] = dict(rec.metadata)
            elif isinstance(rec, Header):
                profile, library = rec.profile, rec.library
        truncated_at = size  # data complete, summary/footer missing or bad
    except _Truncated as cut:
        truncated_at = cut.offset
    if not profile and not library and not channels:
        raise McapReadError(path, f"truncated at byte {truncated_at} of {size}: no complete MCAP "
                                  "header, nothing to recover")
    warnings.warn(f"{path}: truncated or unfinished MCAP (no valid summary; data valid up to byte "
                  f"{truncated_at} of {size}); recovered {count} messages",
                  TruncatedMcapWarning, stacklevel=3)
    return McapFile(path, size, profile, library, False, truncated_at, schemas, channels, meta,
                    count, opener)


def open_mcap(source: Source) -> McapFile:
    """Check an MCAP file and read its header, schemas, channels and metadata.

    Parameters
    ----------
    source : str, Path, bytes or binary stream
        A file, or an MCAP in memory (e.g. the ``io.BytesIO`` a :class:`McapLog` wrote).

    Returns
    -------
    McapFile

    Raises
    ------
    McapReadError
        Missing, empty, not MCAP, or corrupt (see module doc).

    Warns
    -----
    TruncatedMcapWarning
        The file is truncated; it is read as far as valid.
    """
    path, opener, size = _source(source)
    return _from_summary(opener, path, size) or _by_scan(opener, path, size)


@dataclass(frozen=True, eq=False)
class TopicSeries:
    """All messages of one topic, sorted by log time.

    Attributes
    ----------
    topic : str
    msgtype : str
        ``pkg/msg/Type``.
    log_time_ns, publish_time_ns : numpy.ndarray of int64
        Log (receive / prediction) and publish times [ns].
    messages : tuple
        Decoded messages (``mcap_ros2`` objects with field attributes).
    """

    topic: str
    msgtype: str
    log_time_ns: np.ndarray
    publish_time_ns: np.ndarray
    messages: tuple[Any, ...]

    def __len__(self) -> int:
        return len(self.messages)


def _as_sources(sources: Source | Sequence[Source]) -> list[Source]:
    if isinstance(sources, (str, Path, bytes, bytearray, memoryview)) or hasattr(sources, "read"):
        return [sources]  # type: ignore[list-item]
    return list(sources)  # type: ignore[arg-type]


def read_topics(sources: Source | Sequence[Source],
                topics: Iterable[str] | None = None) -> dict[str, TopicSeries]:
    """Read and decode topics of one file, or of several files in order (rotated logs).

    Parameters
    ----------
    sources : path, in-memory MCAP, or a sequence of them
    topics : iterable of str, optional
        Topics to read (default: all).  Each must be present.

    Returns
    -------
    dict[str, TopicSeries]

    Raises
    ------
    McapReadError
        File problems, an absent requested topic, or one topic with two types.
    """
    wanted = None if topics is None else list(topics)
    rows: dict[str, tuple[str, list[int], list[int], list[Any]]] = {}
    for src in _as_sources(sources):
        f = open_mcap(src)
        p = f.path
        types = f.topic_types()
        if wanted is not None:
            absent = [t for t in wanted if t not in types]
            if absent:
                raise McapReadError(p, f"topic(s) {', '.join(absent)} not in file; it has: "
                                       f"{', '.join(sorted(types)) or '(no topics)'}")
        for t in (types if wanted is None else wanted):
            prev = rows.get(t)
            if prev is not None and prev[0] != types[t]:
                raise McapReadError(p, f"topic {t} is {types[t]} here but {prev[0]} in an earlier file")
            rows.setdefault(t, (types[t], [], [], []))
        for ch, msg in f.iter_raw(wanted):
            _, logs, pubs, msgs = rows[ch.topic]
            logs.append(msg.log_time)
            pubs.append(msg.publish_time)
            msgs.append(f.decode(ch, msg))
    out = {}
    for t, (msgtype, logs, pubs, msgs) in rows.items():
        log_arr = np.asarray(logs, dtype=np.int64)
        order = np.argsort(log_arr, kind="stable")
        out[t] = TopicSeries(t, msgtype, log_arr[order], np.asarray(pubs, dtype=np.int64)[order],
                             tuple(msgs[i] for i in order))
    return out


def topic_types(path: Source) -> dict[str, str]:
    """``{topic: pkg/msg/Type}`` of a file (no messages decoded)."""
    return open_mcap(path).topic_types()


def metadata(path: Source) -> dict[str, dict[str, str]]:
    """Metadata records of a file: ``{name: {key: value}}``."""
    return open_mcap(path).metadata


def require(path: Source, expected: Mapping[str, str]) -> dict[str, str]:
    """Check that ``path`` has each topic with the given type; return all topic types.

    Parameters
    ----------
    expected : dict[str, str]
        ``{topic: msgtype}``; ``pkg/Type`` and ``pkg/msg/Type`` both accepted.

    Raises
    ------
    McapReadError
        Listing every absent topic (with the topics present) and every type mismatch.
    """
    f = open_mcap(path)
    types = f.topic_types()
    problems = []
    for topic, want in expected.items():
        want_n = normalize_msgtype(want)
        have = types.get(topic)
        if have is None:
            problems.append(f"topic {topic} ({want_n}) is missing")
        elif have != want_n:
            problems.append(f"topic {topic} is {have}, expected {want_n}")
    if problems:
        raise McapReadError(f.path, "; ".join(problems) + "; topics present: "
                                  + (", ".join(f"{k} ({v})" for k, v in sorted(types.items()))
                                     or "(none)"))
    return types


# -- numeric extraction ------------------------------------------------------------------

_PATH_TOKEN = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)((?:\[-?\d+\])*)")


def _compile_path(field_path: str) -> list[tuple[str, list[int]]]:
    steps = []
    for part in field_path.split("."):
        m = _PATH_TOKEN.fullmatch(part)
        if m is None:
            raise InputError("field_path", field_path, "names with optional [index], "
                             "e.g. 'velocity[0]', 'vector.x', 'status[0].level'")
        steps.append((m.group(1), [int(i) for i in re.findall(r"-?\d+", m.group(2))]))
    return steps


_MISSING = object()


def _get(msg: Any, steps: list[tuple[str, list[int]]]) -> Any:
    v = msg
    for name, indexes in steps:
        v = getattr(v, name, _MISSING)
        if v is _MISSING:
            raise AttributeError(name)
        for i in indexes:
            v = v[i]
    return v


def _times(series: TopicSeries, stamp: str, t0_ns: int) -> np.ndarray:
    if stamp == "log":
        ns = series.log_time_ns
    elif stamp == "publish":
        ns = series.publish_time_ns
    elif stamp == "header":
        try:
            ns = np.array([ns_from_stamp(m.header.stamp) for m in series.messages], dtype=np.int64)
        except AttributeError:
            raise InputError("stamp", stamp, "'log' | 'publish'",
                             f"{series.msgtype} has no header") from None
    else:
        raise InputError("stamp", stamp, "'log' | 'publish' | 'header'")
    return (ns - np.int64(t0_ns)).astype(np.float64) * 1e-9


def scalar_series(series: TopicSeries, field_path: str, *, stamp: str = "log", t0_ns: int = 0,
                  missing: str = "raise") -> tuple[np.ndarray, np.ndarray]:
    """One numeric field of every message, with its time.

    Parameters
    ----------
    series : TopicSeries
    field_path : str
        Dotted path with indexes: ``"velocity[0]"``, ``"fluid_pressure"``, ``"data"``,
        ``"vector.x"``, ``"data[3]"``.
    stamp : {'log', 'publish', 'header'}
        Time of a sample: MCAP log time, publish time, or ``header.stamp``.
    t0_ns : int
        Subtracted from the times [ns].
    missing : {'raise', 'nan'}
        For a message lacking the field or index (e.g. an empty ``velocity``).

    Returns
    -------
    t_s : numpy.ndarray
        Times [s] relative to ``t0_ns``.
    values : numpy.ndarray
        float64 values (units of the field).

    Raises
    ------
    InputError
        Bad path, field absent (``missing='raise'``) or not numeric.
    """
    if missing not in ("raise", "nan"):
        raise InputError("missing", missing, "'raise' | 'nan'")
    steps = _compile_path(field_path)
    values = np.empty(len(series.messages), dtype=np.float64)
    for k, msg in enumerate(series.messages):
        try:
            v = _get(msg, steps)
        except (AttributeError, IndexError, TypeError) as exc:
            if missing == "nan":
                values[k] = np.nan
                continue
            raise InputError(f"{series.topic}.{field_path}", f"message {k}",
                             f"a field of {series.msgtype} present in every message",
                             f"{type(exc).__name__}: {exc}") from None
        try:
            values[k] = float(v)
        except (TypeError, ValueError):
            raise InputError(f"{series.topic}.{field_path}", v, "a numeric field") from None
    return _times(series, stamp, t0_ns), values


def multiarray_values(msg: Any) -> np.ndarray:
    """Values of a Float64MultiArray shaped by its layout (row major, ``data_offset`` applied)."""
    data = np.asarray(msg.data, dtype=np.float64)
    dims = list(msg.layout.dim)
    data = data[int(msg.layout.data_offset):]
    if not dims:
        return data
    shape = tuple(int(d.size) for d in dims)
    n = int(np.prod(shape))
    if n > data.size:
        raise InputError("layout", shape, f"sizes whose product <= {data.size} values")
    return data[:n].reshape(shape)


def multiarray_series(series: TopicSeries, *, stamp: str = "log", t0_ns: int = 0
                      ) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    """Stack the Float64MultiArray messages of a topic.

    Returns
    -------
    t_s : numpy.ndarray
        Times [s] relative to ``t0_ns`` (shape ``(n,)``).
    values : numpy.ndarray
        Shape ``(n, *layout_sizes)`` (``(n, N)`` for a 1-D layout), units of the topic.
    labels : tuple of str
        Layout dimension labels of the first message (e.g. ``("chamber",)``).

    Raises
    ------
    InputError
        If the topic is not Float64MultiArray or the messages differ in shape.
    """
    if series.msgtype != "std_msgs/msg/Float64MultiArray":
        raise InputError(series.topic, series.msgtype, "std_msgs/msg/Float64MultiArray")
    arrays = [multiarray_values(m) for m in series.messages]
    shapes = {a.shape for a in arrays}
    if len(shapes) > 1:
        raise InputError(series.topic, sorted(shapes), "one shape for all messages")
    labels = tuple(d.label for d in series.messages[0].layout.dim) if series.messages else ()
    values = np.stack(arrays) if arrays else np.empty((0, 0))
    return _times(series, stamp, t0_ns), values, labels
