"""Round-trip and fault tests of the background writer (gerotor_twin.io.background).

Many messages from several threads must all reach the file when ``close()``
drains the queue; with a stalled disk the bounded queue must drop (and count)
instead of blocking; a writer-thread error must be reported, not hang;
``close()`` must be idempotent and work from a signal handler and at
interpreter exit, always leaving a complete, readable file.
"""
from __future__ import annotations

import io
import signal
import subprocess
import sys
import textwrap
import threading
from pathlib import Path

import pytest

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.io.background import STATS_METADATA, BackgroundMcapLog
from gerotor_twin.io.mcap_log import McapLog
from gerotor_twin.io.reader import TruncatedMcapWarning, open_mcap, read_topics

TOPIC = "/twin/delivery_flow"


def make(output, **kw) -> BackgroundMcapLog:
    bg = BackgroundMcapLog(McapLog(output), **kw)
    bg.add_topic(TOPIC, m.FLOAT64)
    return bg


def test_many_messages_from_threads_all_written():
    buf = io.BytesIO()
    bg = make(buf, max_queue=100_000)
    bg.add_metadata("gerotor_twin.node_parameters", {"bearing_model": "fixed"})
    n, threads = 1500, 3

    def produce(k: int) -> None:
        for i in range(n):
            assert bg.write(TOPIC, m.float64(k * n + i), (k * n + i) * 1000)

    workers = [threading.Thread(target=produce, args=(k,)) for k in range(threads)]
    for w in workers:
        w.start()
    for w in workers:
        w.join()
    stats = bg.close()
    assert stats.queued == stats.written == n * threads and stats.dropped == 0
    assert bg.close() == stats  # idempotent
    series = read_topics(buf)[TOPIC]
    assert sorted(msg.data for msg in series.messages) == [float(i) for i in range(n * threads)]
    meta = open_mcap(buf).metadata
    assert meta[STATS_METADATA]["written"] == str(n * threads)
    assert meta["gerotor_twin.node_parameters"] == {"bearing_model": "fixed"}


class StalledLog(McapLog):
    """An McapLog whose disk 'hangs' until ``gate`` is set."""

    gate: threading.Event

    def write_raw(self, *args, **kwargs):
        self.gate.wait(10.0)
        super().write_raw(*args, **kwargs)


def test_queue_full_drops_and_counts(caplog: pytest.LogCaptureFixture):
    buf = io.BytesIO()
    log = StalledLog(buf)
    log.gate = threading.Event()
    bg = BackgroundMcapLog(log, max_queue=20, block_s=0.0)
    bg.add_topic(TOPIC, m.FLOAT64)
    accepted = [bg.write(TOPIC, m.float64(i), i) for i in range(200)]
    assert not all(accepted) and sum(accepted) <= 21  # 20 queued (+1 possibly in the writer's hand)
    stats = bg.stats()
    assert stats.dropped_queue_full == {TOPIC: 200 - sum(accepted)}
    assert any("queue full" in r.message for r in caplog.records)
    bg2_blocked = BackgroundMcapLog(StalledLog(io.BytesIO()), max_queue=1, block_s=0.02)
    bg2_blocked.log.gate = log.gate
    bg2_blocked.add_topic(TOPIC, m.FLOAT64)
    results = [bg2_blocked.write(TOPIC, m.float64(i), i) for i in range(4)]
    assert results[-1] is False  # waited at most block_s, then dropped
    log.gate.set()
    bg2_blocked.close()
    stats = bg.close()
    assert stats.written == sum(accepted) == stats.queued
    assert not bg.write(TOPIC, m.float64(0.0), 1)  # after close: refused and counted
    assert bg.stats().dropped_after_close == 1
    f = open_mcap(buf)
    assert f.complete and f.message_count == sum(accepted)
    assert f.metadata[STATS_METADATA]["dropped_queue_full"] == str(200 - sum(accepted))


class FailingLog(McapLog):
    def write_raw(self, *args, **kwargs):
        raise OSError(28, "No space left on device")


def test_writer_thread_error_reported_not_hung(caplog: pytest.LogCaptureFixture):
    buf = io.BytesIO()
    bg = BackgroundMcapLog(FailingLog(buf))
    bg.add_topic(TOPIC, m.FLOAT64)
    for i in range(5):
        assert bg.write(TOPIC, m.float64(i), i)
    stats = bg.close(timeout_s=10)
    assert stats.lost == 5 and stats.written == 0 and "No space left" in stats.error
    assert isinstance(bg.error, OSError)
    assert any("No space left" in r.message for r in caplog.records)
    with pytest.warns(TruncatedMcapWarning):   # left unfinalised at the error, readable up to it
        f = open_mcap(buf)
    assert not f.complete and f.profile == "ros2"


def test_producer_errors_raised_in_caller():
    bg = make(io.BytesIO())
    with pytest.raises(InputError, match="registered with add_topic"):
        bg.write_raw("/nope", b"\x00\x01\x00\x00", 1)
    with pytest.raises(InputError, match="dat"):
        bg.write(TOPIC, {"dat": 1.0}, 1)
    with pytest.raises(InputError, match="log_time_ns"):
        bg.write(TOPIC, m.float64(1.0), -5)
    with pytest.raises(InputError, match="max_queue"):
        BackgroundMcapLog(McapLog(io.BytesIO()), max_queue=0)
    assert bg.close().queued == 0


def test_flush_makes_data_durable(tmp_path: Path):
    path = tmp_path / "live.mcap"
    bg = make(path, flush_interval_s=None)
    for i in range(50):
        bg.write(TOPIC, m.float64(i), i)
    assert bg.flush(timeout_s=10)
    with pytest.warns(TruncatedMcapWarning, match=r"live.mcap.*recovered 50 messages"):
        assert len(read_topics(path)[TOPIC]) == 50  # what a crash now would leave
    bg.close()
    assert open_mcap(path).complete


@pytest.mark.skipif(not hasattr(signal, "setitimer"), reason="needs POSIX timers")
@pytest.mark.parametrize("background", [False, True])
def test_close_from_signal_handler(tmp_path: Path, background: bool):
    path = tmp_path / "sig.mcap"
    # a queue the 50 ms of writes cannot fill (≈ 3 µs per write with the fast encoders): a full queue drops by
    # design (counted: test_queue_full_drops_and_counts); here only the close is under test
    log = make(path, max_queue=10**6) if background else McapLog(path)
    if not background:
        log.add_topic(TOPIC, m.FLOAT64)
    old = signal.signal(signal.SIGALRM, lambda *_: log.close())
    try:
        signal.setitimer(signal.ITIMER_REAL, 0.05)
        i = 0
        while not log.closed and i < 10**7:  # the handler fires in the middle of writes
            try:
                log.write(TOPIC, m.float64(i), i)
            except Exception as exc:  # a McapLog refuses writes once closed
                assert type(exc).__name__ == "McapLogClosed"
            i += 1
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)
    log.close()
    f = open_mcap(path)
    assert f.complete and 0 < f.message_count <= i
    values = [msg.data for msg in read_topics(path)[TOPIC].messages]
    assert values == [float(k) for k in range(len(values))]


@pytest.mark.parametrize("rotating", [False, True])
def test_unclosed_log_finalised_at_exit(tmp_path: Path, rotating: bool):
    path = tmp_path / "exit.mcap"
    make_log = (f"RotatingMcapLog({str(tmp_path)!r}, 'exit', max_duration_s=1e-7)" if rotating
                else f"McapLog({str(path)!r})")
    code = textwrap.dedent(f"""
        from gerotor_twin.io import messages as m
        from gerotor_twin.io.background import BackgroundMcapLog
        from gerotor_twin.io.mcap_log import McapLog, RotatingMcapLog
        bg = BackgroundMcapLog({make_log})
        bg.add_topic("/twin/delivery_flow", m.FLOAT64)
        for i in range(300):
            bg.write("/twin/delivery_flow", m.float64(i), i * 100)
        # no close(): the interpreter exits with messages still queued
    """)
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)
    files = sorted(tmp_path.glob("exit*.mcap"))
    assert len(files) == (300 if rotating else 1)  # rotating: one message per file
    counts = [open_mcap(f).message_count for f in files]  # each one complete (no warning)
    assert sum(counts) == 300


def test_close_inside_a_write_is_deferred_to_its_end():
    """What a signal handler calling close() in the middle of a write of the same thread does."""
    buf = io.BytesIO()
    log = McapLog(buf)
    log.add_topic(TOPIC, m.FLOAT64)
    writer = log._sink.writer
    add_message = writer.add_message
    seen = []

    def interrupted(*args, **kwargs):
        log.close()  # the "signal handler"
        seen.append(log.closed)
        return add_message(*args, **kwargs)

    writer.add_message = interrupted
    log.write(TOPIC, m.float64(1.0), 5)
    assert seen == [False] and log.closed  # not closed mid-write, closed right after it
    f = open_mcap(buf)
    assert f.complete and f.message_count == 1


class SlowLog(McapLog):
    """A slow disk: 1 ms per message, so the writer thread's queue stays full."""

    def write_raw(self, *args, **kwargs):
        import time
        time.sleep(0.001)
        super().write_raw(*args, **kwargs)


def test_periodic_flush_while_busy():
    """With chunks never full (huge chunk_size) and the queue never empty, the file still grows
    before the queue drains: the open chunk is written every flush_interval_s, busy or idle."""
    import time
    buf = io.BytesIO()
    bg = BackgroundMcapLog(SlowLog(buf, chunk_size=1 << 30), flush_interval_s=0.05, poll_s=0.001)
    bg.add_topic(TOPIC, m.FLOAT64)
    start = len(buf.getvalue())
    for k in range(3000):                            # about 3 s of work for the writer thread
        assert bg.write(TOPIC, m.float64(float(k)), k + 1)
    while len(buf.getvalue()) <= start + 100:       # grows only if a chunk was flushed
        assert bg.queue_depth > 0, "the queue drained before any periodic flush"
        time.sleep(0.001)
    assert bg.queue_depth > 0                        # still busy when the chunk went to the file
    with pytest.warns(TruncatedMcapWarning):
        f = open_mcap(io.BytesIO(buf.getvalue()))   # the file as a kill would leave it
    assert 0 < f.message_count < 3000
    assert bg.close().written == 3000
