"""Recovery of unfinalised MCAP logs (gerotor_twin.io.recover, ``gerotor-twin log recover``) (behaviour).

A real log is cut at many byte offsets (what a crash leaves on disk); the
recovered copy must open in ``rosbags`` (independent reader) and hold exactly
the messages written before the cut: at least every message of the chunks
that lie wholly before it (taken from the uncut file's own chunk index), in
the order written, none invented.  A chunk with a damaged byte is skipped and
the scan goes on.  A live writer's file is never touched; a killed writer's
file is found and recovered once.
"""
from __future__ import annotations

import io
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from mcap.records import Chunk, Message
from mcap.stream_reader import StreamReader, breakup_chunk
from rosbags.highlevel import AnyReader

from gerotor_twin.cli import main as cli
from gerotor_twin.io import messages as m
from gerotor_twin.io.mcap_log import McapLog
from gerotor_twin.io.recover import (is_finalised, is_locked, recover, recover_directory, recovered_path,
                                     unfinalised_logs)

N = 300
T0 = 1_700_000_000_000_000_000


def write_log(path: Path, n: int = N) -> None:
    with McapLog(path, chunk_size=1024, metadata={"gerotor_twin.pump_config": {"yaml": "x: 1"}}) as log:
        log.add_topic("/bench/shaft_speed", m.JOINT_STATE, "sensor")
        log.add_topic("/bench/delivery_pressure", m.FLUID_PRESSURE, "sensor")
        for i in range(n):
            t = T0 + 1_000_000 * i
            log.write("/bench/shaft_speed", m.joint_state(t, name=["shaft"], velocity=[float(i)]), t)
            log.write("/bench/delivery_pressure", m.fluid_pressure(t, 1e5 + i), t + 1)


def rosbags_values(path: Path) -> list[tuple[str, float]]:
    """(topic, value) of every message in file order, decoded by rosbags; checks its start/end times."""
    out, times = [], []
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            out.append((conn.topic, float(msg.velocity[0]) if conn.topic == "/bench/shaft_speed"
                        else msg.fluid_pressure - 1e5))
            times.append(t)
        if times:
            assert reader.start_time == min(times) and reader.end_time == max(times) + 1  # end: exclusive
    return out


@pytest.fixture
def log_file(tmp_path: Path) -> Path:
    p = tmp_path / "run.mcap"
    write_log(p)
    return p


def chunk_spans(path: Path) -> list[tuple[int, int, int]]:
    """(first byte, end byte incl. its message indexes, messages) of each chunk, from the uncut file."""
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
        out = []
        for ci in summary.chunk_indexes:
            f.seek(ci.chunk_start_offset)
            chunk = next(r for r in StreamReader(io.BytesIO(f.read(ci.chunk_length)), skip_magic=True,
                                                 emit_chunks=True).records if isinstance(r, Chunk))
            out.append((ci.chunk_start_offset, ci.chunk_start_offset + ci.chunk_length + ci.message_index_length,
                        sum(isinstance(r, Message) for r in breakup_chunk(chunk))))
    return out


def expected_values(k: int) -> list[tuple[str, float]]:
    """The first k messages written, in order."""
    rows = []
    for i in range(N):
        rows += [("/bench/shaft_speed", float(i)), ("/bench/delivery_pressure", float(i))]
    return rows[:k]


def test_recover_at_every_cut_leaves_exactly_the_written_prefix(log_file: Path, tmp_path: Path):
    data = log_file.read_bytes()
    spans = chunk_spans(log_file)
    assert len(spans) > 10
    cuts = sorted({int(len(data) * f) for f in [i / 23 for i in range(1, 23)]} | {spans[3][1], spans[3][1] - 1})
    for cut in cuts:
        src = tmp_path / f"cut_{cut}.mcap"
        src.write_bytes(data[:cut])
        assert not is_finalised(src)
        rep = recover(src)
        assert rep.output == tmp_path / f"cut_{cut}.recovered.mcap" and is_finalised(rep.output)
        got = rosbags_values(rep.output)
        whole = sum(n for _, end, n in spans if end <= cut)
        assert len(got) >= whole, (cut, len(got), whole)
        assert got == expected_values(len(got)), cut                 # the written prefix, in order
        assert rep.messages == len(got) and rep.skipped_chunks == 0
        with open(rep.output, "rb") as f:
            reader = make_reader(f)
            stats = reader.get_summary().statistics
            (bag,) = [r.metadata for r in reader.iter_metadata() if r.name == "rosbag2"]
        assert stats.message_count == len(got)
        meta = yaml.safe_load(bag["serialized_metadata"])
        assert meta["ros_distro"] == "jazzy" and meta["message_count"] == len(got)
        if got:
            assert stats.message_start_time == T0
            assert meta["starting_time"]["nanoseconds_since_epoch"] == stats.message_start_time


def test_corrupt_chunk_is_skipped_and_the_rest_kept(log_file: Path, tmp_path: Path):
    spans = chunk_spans(log_file)
    start, end, lost = spans[5]
    data = bytearray(log_file.read_bytes())
    data[start + (end - start) // 2 - 40] ^= 0xFF     # inside the compressed data of chunk 5
    src = tmp_path / "damaged.mcap"
    src.write_bytes(bytes(data[:-500]))                 # and unfinalised
    rep = recover(src)
    assert rep.skipped_chunks == 1
    got = rosbags_values(rep.output)
    before = sum(n for _, _, n in spans[:5])
    assert got[:before] == expected_values(before)
    rest = got[before:]                                 # after the skipped chunk: the next messages on
    assert rest and rest == expected_values(2 * N)[before + lost:before + lost + len(rest)]


def test_finalised_file_is_reindexed_unchanged(log_file: Path, tmp_path: Path):
    rep = recover(log_file, tmp_path / "copy.mcap")
    assert rep.source_complete and rep.stop_reason == "" and rep.messages == 2 * N
    assert rosbags_values(rep.output) == expected_values(2 * N)
    from gerotor_twin.io import metadata
    assert metadata(rep.output)["gerotor_twin.pump_config"] == {"yaml": "x: 1"}


def test_live_file_skipped_killed_writer_found_once(tmp_path: Path):
    done = tmp_path / "done.mcap"
    write_log(done, 10)
    live = McapLog(tmp_path / "live.mcap", chunk_size=256)
    live.add_topic("/bench/delivery_pressure", m.FLUID_PRESSURE, "sensor")
    live.write("/bench/delivery_pressure", m.fluid_pressure(T0, 1e5), T0)
    live.flush()
    killed = tmp_path / "killed.mcap"
    code = textwrap.dedent(f"""
        import os, signal
        from gerotor_twin.io.mcap_log import McapLog
        from gerotor_twin.io import messages as m
        log = McapLog({str(killed)!r}, chunk_size=256)
        log.add_topic("/bench/delivery_pressure", m.FLUID_PRESSURE, "sensor")
        for i in range(50):
            log.write("/bench/delivery_pressure", m.fluid_pressure({T0} + i, 1e5 + i), {T0} + i)
        log.flush()
        os.kill(os.getpid(), signal.SIGKILL)
    """)
    proc = subprocess.run([sys.executable, "-c", code], timeout=60)
    assert proc.returncode == -9
    try:
        assert is_locked(live.path) and not is_locked(killed)
        assert unfinalised_logs(tmp_path) == [killed]
        (rep,) = recover_directory(tmp_path)
        assert rep.output == recovered_path(killed) and rep.messages == 50
        assert [v for _, v in rosbags_values(rep.output)] == [float(i) for i in range(50)]
        assert unfinalised_logs(tmp_path) == []               # recovered once, not again
    finally:
        live.close()


def test_cli(log_file: Path, tmp_path: Path, capsys):
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(log_file.read_bytes()[:5000])
    assert cli(["log", "recover", str(cut), "-o", str(tmp_path / "out.mcap")]) == 0
    assert "recovered (unfinalised)" in capsys.readouterr().out
    assert cli(["log", "recover", str(cut), "-o", str(tmp_path / "out.mcap")]) == 2
    assert "does not exist yet" in capsys.readouterr().err
    assert cli(["log", "recover", str(tmp_path / "nope.mcap")]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "file does not exist" in err
    assert cli(["log", "recover", str(tmp_path)]) == 0          # directory: cut.mcap (unfinalised)
    assert (tmp_path / "cut.recovered.mcap").exists()
    assert cli(["log", "recover", str(tmp_path)]) == 0
    assert "no unfinalised MCAP log" in capsys.readouterr().out
