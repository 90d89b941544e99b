"""A full disk: what the MCAP writer counts as written is what a recovery of the file finds.

Tier: behaviour (faults).  The write error comes from a file that takes at most N bytes (injected
at the writer: a short write, then ENOSPC, as a full disk does) or from a small tmpfs the test
mounts (skipped where it cannot).  Every message offered to the writer ends written (found by
``gerotor-twin log recover``) or dropped (counted, per topic), never both and never neither.
"""
from __future__ import annotations

import errno
import io
import os
import random
import time
from pathlib import Path

import pytest

from gerotor_twin.io import mcap_log
from gerotor_twin.io import messages as m
from gerotor_twin.io.background import BackgroundMcapLog, Reopen
from gerotor_twin.io.mcap_log import McapLog
from gerotor_twin.io.reader import open_mcap
from gerotor_twin.io.recover import is_finalised, recover

TOPICS = ("/bench/shaft_speed", "/twin/delivery_flow")


class SmallDisk(io.FileIO):
    """A file on a disk with ``room`` bytes: the write that reaches it is short, the next one fails."""

    def __init__(self, path, mode: str, room: int):
        super().__init__(path, mode)
        self.room = room

    def write(self, b) -> int:
        left = self.room - self.tell()
        if left <= 0:
            raise OSError(errno.ENOSPC, "No space left on device")
        return super().write(memoryview(b)[:left])


def small_disk_open(monkeypatch, room: int, first_only: bool = False, full_from: int = 0) -> None:
    """McapLog opens its files on a disk of ``room`` bytes each (only its first file with ``first_only``;
    files before the ``full_from``-th are not limited)."""
    opened = []

    def fake_open(path, mode="r", *args, **kwargs):
        if "b" not in mode or "r" in mode or (first_only and opened):
            return open(path, mode, *args, **kwargs)
        opened.append(path)
        if len(opened) <= full_from:
            return open(path, mode, *args, **kwargs)
        return io.BufferedWriter(SmallDisk(path, mode.replace("b", ""), room))
    monkeypatch.setattr(mcap_log, "open", fake_open, raising=False)


def offer(bg: BackgroundMcapLog, n: int, seed: int) -> dict[str, int]:
    """``n`` messages of random size (incompressible) over two topics; returns how many were offered per topic."""
    rng = random.Random(seed)
    sent = dict.fromkeys(TOPICS, 0)
    for i in range(n):
        topic = TOPICS[rng.random() < 0.3]
        bg.write_raw(topic, b"\x00\x01\x00\x00" + rng.randbytes(rng.randint(4, 300)), 1_000_000 + i)
        sent[topic] += 1
        if i % 97 == 0:
            bg.flush(timeout_s=10)
    return sent


def _count_by_topic(path: Path) -> dict[str, int]:
    f = open_mcap(path)
    counts = dict.fromkeys(TOPICS, 0)
    for ch, _ in f.iter_raw(list(TOPICS)):
        counts[ch.topic] += 1
    return counts


def check_accounting(bg: BackgroundMcapLog, sent: dict[str, int], files: list[Path], tmp: Path) -> None:
    st = bg.close(timeout_s=30)
    assert st.error is not None or st.last_error is not None, "the disk never filled: raise n"
    found = dict.fromkeys(TOPICS, 0)
    for p in files:
        got = _count_by_topic(p if is_finalised(p) else recover(p, tmp / f"{p.stem}.recovered.mcap").output)
        for t in TOPICS:
            found[t] += got[t]
    assert sum(found.values()) == st.written, (found, st)                    # written = readable after recovery
    assert st.dropped == sum(sent.values()) - st.written and st.pending == 0, st
    for t in TOPICS:                                                         # and per topic
        assert found[t] == sent[t] - st.lost_by_topic.get(t, 0) - st.dropped_queue_full.get(t, 0), (t, found, st)


@pytest.mark.parametrize("compression", ["zstd", "none"])
@pytest.mark.parametrize("room", list(range(3_000, 60_000, 2_911)))
def test_written_is_what_recovery_finds_on_a_full_disk(tmp_path, monkeypatch, room, compression):
    """Behaviour: the disk fills anywhere in a chunk, its message indexes or a metadata record: the messages
    counted written are exactly those a recovery finds, the others are counted dropped (lost), per topic."""
    small_disk_open(monkeypatch, room)
    path = tmp_path / "twin.mcap"
    bg = BackgroundMcapLog(McapLog(path, chunk_size=4096, compression=compression), max_queue=100_000,
                           flush_interval_s=None)
    for t in TOPICS:
        bg.add_topic(t, m.FLOAT64)
    sent = offer(bg, 1500, seed=room)
    check_accounting(bg, sent, [path], tmp_path)


@pytest.mark.parametrize("room", list(range(2_000, 12_000, 1_313)))
def test_written_is_what_recovery_finds_with_rotation(tmp_path, monkeypatch, room):
    """Behaviour: the same with a rotating log (the node's default), the disk filling in its third file,
    also while a file is finalised at rotation: the finalised files count whole, the broken one as recovered."""
    from gerotor_twin.io.mcap_log import RotatingMcapLog
    small_disk_open(monkeypatch, room, full_from=2)
    log = RotatingMcapLog(tmp_path / "logs", "twin", max_bytes=8192, chunk_size=2048)
    bg = BackgroundMcapLog(log, max_queue=100_000, flush_interval_s=None)
    for t in TOPICS:
        bg.add_topic(t, m.FLOAT64)
    sent = offer(bg, 1000, seed=room)
    check_accounting(bg, sent, sorted((tmp_path / "logs").glob("twin_*.mcap")), tmp_path)
    assert len(log.paths) >= 3


def test_next_file_cannot_be_created_at_rotation(tmp_path, monkeypatch):
    """Behaviour: the first file is finalised at rotation, the next cannot be created (disk full): the first
    counts whole (once), everything after it is dropped."""
    from gerotor_twin.io.mcap_log import RotatingMcapLog
    opened = []

    def fake_open(path, mode="r", *args, **kwargs):
        if "b" in mode and "r" not in mode:
            opened.append(path)
            if len(opened) > 1:
                raise OSError(errno.ENOSPC, "No space left on device", str(path))
        return open(path, mode, *args, **kwargs)
    monkeypatch.setattr(mcap_log, "open", fake_open, raising=False)
    log = RotatingMcapLog(tmp_path / "logs", "twin", max_bytes=8192, chunk_size=2048)
    bg = BackgroundMcapLog(log, max_queue=100_000, flush_interval_s=None)
    for t in TOPICS:
        bg.add_topic(t, m.FLOAT64)
    sent = offer(bg, 300, seed=3)
    files = sorted((tmp_path / "logs").glob("twin_*.mcap"))
    assert len(files) == 1 and is_finalised(files[0])
    check_accounting(bg, sent, files, tmp_path)


def test_written_counts_both_files_after_a_resume(tmp_path, monkeypatch):
    """Behaviour: disk full, then space again and a new file: written = recovered from the first file +
    read from the second; dropped = offered - written."""
    small_disk_open(monkeypatch, 20_000, first_only=True)
    files = [tmp_path / "twin_0.mcap"]

    def factory():
        files.append(tmp_path / f"twin_r{len(files)}.mcap")
        return McapLog(files[-1], chunk_size=4096)
    bg = BackgroundMcapLog(McapLog(files[0], chunk_size=4096), max_queue=100_000, flush_interval_s=None,
                           poll_s=0.002, reopen=Reopen(factory, tmp_path, min_free_bytes=0, retry_s=0.01))
    for t in TOPICS:
        bg.add_topic(t, m.FLOAT64)
    sent = offer(bg, 400, seed=1)
    deadline = time.monotonic() + 20
    while bg.stats().resumed == 0:                        # the error and the new file
        assert time.monotonic() < deadline
        time.sleep(0.01)
    more = offer(bg, 300, seed=2)
    sent = {t: sent[t] + more[t] for t in TOPICS}
    check_accounting(bg, sent, files, tmp_path)
    assert len(files) == 2


def test_written_is_what_recovery_finds_on_a_small_filesystem(tmp_path, small_filesystem):
    """Behaviour: the same on a real 96 kB tmpfs that fills up (ENOSPC from the kernel)."""
    tmpfs = small_filesystem("96k")
    path = tmpfs / "twin.mcap"
    bg = BackgroundMcapLog(McapLog(path, chunk_size=4096), max_queue=100_000, flush_interval_s=0.01)
    for t in TOPICS:
        bg.add_topic(t, m.FLOAT64)
    sent = offer(bg, 2000, seed=7)
    check_accounting(bg, sent, [path], tmp_path)
    assert os.statvfs(tmpfs).f_bavail * os.statvfs(tmpfs).f_frsize < 8192     # it was full


def test_confirmed_only_once_handed_to_the_os(tmp_path):
    """Behaviour: a message in the open chunk is not counted as in the file; a flush, a full chunk or the
    close count it."""
    log = McapLog(tmp_path / "a.mcap", chunk_size=1000)
    log.add_topic(TOPICS[0], m.FLOAT64)
    for i in range(3):
        log.write_raw(TOPICS[0], b"\x00\x01\x00\x00" + bytes(8), i + 1)
    assert log.confirmed_messages == 0
    log.flush()
    assert log.confirmed_messages == 3 and log.durable.offset == (tmp_path / "a.mcap").stat().st_size
    log.write_raw(TOPICS[0], b"\x00\x01\x00\x00" + bytes(2000), 10)     # fills a chunk: written at once
    assert log.confirmed_messages == 4
    log.write_raw(TOPICS[0], b"\x00\x01\x00\x00" + bytes(8), 11)
    assert log.confirmed_messages == 4
    log.close()
    assert log.confirmed_messages == 5 and log.durable.complete
