"""Recover unfinalised MCAP files (crash, kill, power cut, disk full): ``gerotor-twin log recover``.

:func:`recover` does what ``mcap recover`` does: it reads the data section
linearly as far as it is valid and writes a new, finalised and indexed file
(summary, statistics, chunk and message indexes, footer) holding every
schema, channel, message, metadata record and attachment that was complete.
A chunk whose CRC or decompression fails is skipped (counted) and the scan
goes on; the first record cut short or unparsable ends it (the byte offset is
reported).  The ``rosbag2`` metadata record is written anew from what was
recovered (see :mod:`~gerotor_twin.io.rosbag2_meta`), so ``ros2 bag``,
Foxglove and ``rosbags`` read the copy.  The original is never modified.

:func:`unfinalised_logs` lists the files of a directory that a crashed writer
left unfinalised: no footer, not locked by a live writer (a
:class:`~gerotor_twin.io.mcap_log.McapLog` holds an exclusive ``flock`` on the
file it writes, released by the kernel when the process dies), and not yet
recovered.  :func:`recover_directory` recovers each of them beside the
original as ``<name>.recovered.mcap``.  Written to a temporary name and
renamed, a recovered file is either complete or absent.
"""
from __future__ import annotations

import fcntl
import os
import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterator

from mcap.records import Attachment, Channel, Chunk, Header, Message, Metadata, Schema
from mcap.stream_reader import breakup_chunk
from mcap.writer import Writer

from gerotor_twin.errors import InputError
from gerotor_twin.io.mcap_log import COMPRESSIONS
from gerotor_twin.io.reader import McapReadError, _records, _source, _Truncated
from gerotor_twin.io.rosbag2_meta import ROSBAG2_METADATA, TopicCount, rosbag2_record

__all__ = ["RecoveryReport", "recover", "recovered_path", "is_finalised", "is_locked",
           "unfinalised_logs", "recover_directory", "recoverable_messages"]

RECOVERED_SUFFIX = ".recovered.mcap"
_FOOTER_TAIL = 1 + 8 + 8 + 8 + 4 + 8   # footer opcode, length, 2 offsets, CRC, closing magic
_MAGIC = b"\x89MCAP0\r\n"


@dataclass(frozen=True)
class RecoveryReport:
    """What :func:`recover` found and wrote.

    Attributes
    ----------
    source, output : Path
    source_complete : bool
        The source had a footer (it was finalised; the copy is then a plain re-index).
    valid_bytes : int
        Bytes of the source read as valid [bytes].
    stop_reason : str
        Why the scan ended ('' = end of data section reached).
    messages, channels, schemas, metadata, attachments : int
        Records written to the output [-].
    skipped_chunks : int
        Chunks dropped for a CRC / decompression error [-].
    orphan_messages : int
        Messages dropped because their channel record was lost [-].
    first_ns, last_ns : int or None
        First and last message log time [ns].
    """

    source: Path
    output: Path
    source_complete: bool
    valid_bytes: int
    stop_reason: str
    messages: int
    channels: int
    schemas: int
    metadata: int
    attachments: int
    skipped_chunks: int
    orphan_messages: int
    first_ns: int | None
    last_ns: int | None

    def summary(self) -> str:
        """One line for logs and the CLI."""
        span = "" if self.first_ns is None else f", {(self.last_ns - self.first_ns) * 1e-9:.3f} s"
        why = f"; scan stopped: {self.stop_reason}" if self.stop_reason else ""
        skipped = f"; {self.skipped_chunks} corrupt chunk(s) skipped" if self.skipped_chunks else ""
        return (f"{self.source} -> {self.output}: {self.messages} messages on {self.channels} channels"
                f"{span} (valid up to byte {self.valid_bytes}){skipped}{why}")


def recovered_path(path: str | os.PathLike[str]) -> Path:
    """Default output of :func:`recover`: ``run.mcap`` -> ``run.recovered.mcap`` beside it."""
    p = Path(path)
    return p.with_name((p.name[:-5] if p.name.endswith(".mcap") else p.name) + RECOVERED_SUFFIX)


def is_finalised(path: str | os.PathLike[str]) -> bool:
    """True if the file ends with a Footer record and the closing magic (cheap check)."""
    p = Path(path)
    try:
        size = p.stat().st_size
        if size < len(_MAGIC) + _FOOTER_TAIL:
            return False
        with open(p, "rb") as f:
            f.seek(size - _FOOTER_TAIL)
            tail = f.read()
    except OSError:
        return False
    return tail[0] == 0x02 and tail[-8:] == _MAGIC


def is_locked(path: str | os.PathLike[str]) -> bool:
    """True if a live process holds the writer's ``flock`` on the file."""
    try:
        with open(path, "rb") as f:
            try:
                fcntl.flock(f.fileno(), fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                return True
            fcntl.flock(f.fileno(), fcntl.LOCK_UN)
    except OSError:
        return False
    return False


def unfinalised_logs(directory: str | os.PathLike[str]) -> list[Path]:
    """MCAP files in ``directory`` left unfinalised by a dead writer and not yet recovered."""
    d = Path(directory)
    if not d.is_dir():
        return []
    out = []
    for p in sorted(d.glob("*.mcap")):
        if p.name.endswith(RECOVERED_SUFFIX) or recovered_path(p).exists():
            continue
        if p.stat().st_size > 0 and not is_finalised(p) and not is_locked(p):
            out.append(p)
    return out


class _Copy:
    """Writes records into a new file, mapping the source's schema/channel ids to the new ones."""

    def __init__(self, stream, compression: str, chunk_size: int):
        self.writer = Writer(stream, chunk_size=chunk_size, compression=COMPRESSIONS[compression])
        self.compression = compression
        self.schema_ids: dict[int, int] = {0: 0}
        self.channels: dict[int, tuple[int, Channel]] = {}
        self.counts: dict[int, int] = {}
        self.n = dict(messages=0, schemas=0, metadata=0, attachments=0, orphans=0)
        self.span: list = [None, None]
        self.started = False

    def start(self, profile: str, library: str) -> None:
        if not self.started:
            self.writer.start(profile=profile, library=library)
            self.started = True

    def add(self, rec: Any) -> None:
        if isinstance(rec, Header):
            self.start(rec.profile, rec.library)
            return
        self.start("", "")
        w = self.writer
        if isinstance(rec, Schema) and rec.id not in self.schema_ids:
            self.schema_ids[rec.id] = w.register_schema(rec.name, rec.encoding, rec.data)
            self.n["schemas"] += 1
        elif isinstance(rec, Channel) and rec.id not in self.channels:
            new = w.register_channel(rec.topic, rec.message_encoding,
                                     self.schema_ids.get(rec.schema_id, 0), dict(rec.metadata))
            self.channels[rec.id] = (new, rec)
            self.counts[rec.id] = 0
        elif isinstance(rec, Message):
            self._message(rec)
        elif isinstance(rec, Metadata) and rec.name != ROSBAG2_METADATA:
            w.add_metadata(rec.name, dict(rec.metadata))
            self.n["metadata"] += 1
        elif isinstance(rec, Attachment):
            w.add_attachment(rec.create_time, rec.log_time, rec.name, rec.media_type, rec.data)
            self.n["attachments"] += 1

    def _message(self, rec: Message) -> None:
        ch = self.channels.get(rec.channel_id)
        if ch is None:
            self.n["orphans"] += 1
            return
        self.writer.add_message(ch[0], rec.log_time, rec.data, rec.publish_time, rec.sequence)
        self.counts[rec.channel_id] += 1
        self.n["messages"] += 1
        t = rec.log_time
        self.span[0] = t if self.span[0] is None else min(self.span[0], t)
        self.span[1] = t if self.span[1] is None else max(self.span[1], t)

    def finish(self, file_name: str, schemas: dict[int, str]) -> None:
        topics = [TopicCount(ch.topic, schemas.get(ch.schema_id, ""),
                             ch.metadata.get("offered_qos_profiles", ""),
                             ch.metadata.get("topic_type_hash", ""), self.counts[cid])
                  for cid, (_, ch) in self.channels.items()]
        self.writer.add_metadata(ROSBAG2_METADATA,
                                 rosbag2_record(file_name, topics, self.span[0], self.span[1]))
        self.writer.finish()


def _scan(opener, path, size, start: int | None = None) -> Iterator[tuple[str, Any]]:
    """``("record", rec)`` for each valid record (chunks expanded) from byte ``start`` (default: the first
    record), then ``("end", (offset, why))``."""
    offset = 8
    try:
        for offset, rec in _records(opener, path, size, start=start):
            if isinstance(rec, Chunk):
                try:
                    inner = breakup_chunk(rec, validate_crc=True)
                except Exception as exc:  # noqa: BLE001 - CRC, zstd/lz4 or parse error
                    yield "skipped", f"chunk at byte {offset}: {exc}"
                    continue
                for r in inner:
                    yield "record", r
            else:
                yield "record", rec
        yield "end", (size, "")
    except _Truncated as cut:
        yield "end", (cut.offset, "the file ends without DataEnd/Footer (writer never finished)"
                      if cut.offset == size else f"the record at byte {cut.offset} runs past the end "
                                                 f"of the file ({size} bytes): cut while being written")
    except McapReadError as exc:
        yield "end", (offset, exc.what)


def recoverable_messages(path: str | os.PathLike[str], start: int = 8) -> dict[int, int]:
    """Messages :func:`recover` would find in ``path`` from byte ``start`` on, per channel id.

    ``start`` must be the first byte of a record (e.g. where a writer's last
    successful flush ended).  The writer uses it after a write error to count
    as written exactly what a recovery of the file will hold.

    Raises
    ------
    McapReadError
        Missing, empty or not an MCAP file.
    """
    name, opener, size = _source(Path(path))
    counts: dict[int, int] = {}
    for kind, item in _scan(opener, name, size, start):
        if kind == "record" and isinstance(item, Message):
            counts[item.channel_id] = counts.get(item.channel_id, 0) + 1
    return counts


def recover(source: str | os.PathLike[str], output: str | os.PathLike[str] | None = None, *,
            overwrite: bool = False, compression: str = "zstd",
            chunk_size: int = 1 << 20) -> RecoveryReport:
    """Write a finalised, indexed copy of everything valid in an MCAP file.

    Parameters
    ----------
    source : path
        The MCAP file (finalised or not).
    output : path, optional
        Default :func:`recovered_path` (``<name>.recovered.mcap`` beside the source).
    overwrite : bool
        Replace an existing output (default: refuse).
    compression : {'zstd', 'lz4', 'none'}
    chunk_size : int
        Uncompressed chunk size of the output [bytes].

    Returns
    -------
    RecoveryReport

    Raises
    ------
    McapReadError
        Missing, empty or not an MCAP file.
    InputError
        Bad option, output exists, or output equals source.
    """
    if compression not in COMPRESSIONS:
        raise InputError("compression", compression, " | ".join(COMPRESSIONS))
    name, opener, size = _source(Path(source))
    src = Path(name)
    out = recovered_path(src) if output is None else Path(output)
    if out.resolve() == src.resolve():
        raise InputError("output", str(out), "a file other than the source")
    if out.exists() and not overwrite:
        raise InputError("output", str(out), "a file that does not exist yet", "pass -f to replace it")
    tmp = out.with_name(f".{out.name}.{os.getpid()}.part")
    schemas: dict[int, str] = {}
    skipped, end = 0, (8, "")
    try:
        with open(tmp, "wb") as stream:
            copy = _Copy(stream, compression, chunk_size)
            for kind, item in _scan(opener, src, size):
                if kind == "record":
                    if isinstance(item, Schema):
                        schemas.setdefault(item.id, item.name)
                    copy.add(item)
                elif kind == "skipped":
                    skipped += 1
                else:
                    end = item
            copy.start("", "")
            copy.finish(out.name, schemas)
        os.replace(tmp, out)
    finally:
        if tmp.exists():
            tmp.unlink()
    n = copy.n
    return RecoveryReport(src, out, is_finalised(src), end[0], end[1], n["messages"],
                          len(copy.channels), n["schemas"], n["metadata"], n["attachments"], skipped,
                          n["orphans"], copy.span[0], copy.span[1])


def recover_directory(directory: str | os.PathLike[str]) -> list[RecoveryReport | tuple[Path, str]]:
    """Recover every file of :func:`unfinalised_logs` beside its original.

    Returns
    -------
    list
        A :class:`RecoveryReport` per recovered file, or ``(path, error text)`` for a
        file that could not be recovered (e.g. no MCAP header at all).
    """
    out: list[RecoveryReport | tuple[Path, str]] = []
    for p in unfinalised_logs(directory):
        try:
            out.append(recover(p))
        except (McapReadError, InputError, OSError, struct.error) as exc:
            out.append((p, str(exc)))
    return out
