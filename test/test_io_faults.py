"""Fault tests of the MCAP reader (gerotor_twin.io.reader).

Every bad file gives a :class:`McapReadError` whose message names the file
and what is wrong (missing, directory, empty, random bytes, magic only,
corrupt chunk, missing topic, wrong type); a truncated file (a real log cut in
the middle, as a crash or an interrupted copy leaves it) is read as far as
valid with a warning naming the file and the number of messages recovered,
and the recovered messages are exactly the first ones written.  Closed logs
refuse writes.
"""
from __future__ import annotations

import os
from pathlib import Path

import numpy as np
import pytest
from mcap.reader import make_reader

from gerotor_twin.io import messages as m
from gerotor_twin.io.mcap_log import McapLog, McapLogClosed
from gerotor_twin.io.reader import (McapReadError, TruncatedMcapWarning, metadata, open_mcap,
                                    read_topics, require, scalar_series, topic_types)

N = 400


@pytest.fixture
def log_file(tmp_path: Path) -> Path:
    """A real log: two topics, N messages each, small chunks (many of them)."""
    path = tmp_path / "bench.mcap"
    with McapLog(path, chunk_size=1024, metadata={"gerotor_twin.pump_config": {"yaml": "x: 1"}}) as log:
        log.add_topic("/bench/shaft_speed", m.JOINT_STATE, "sensor")
        log.add_topic("/bench/delivery_pressure", m.FLUID_PRESSURE, "sensor")
        for i in range(N):
            t = 1_000_000 * i
            log.write("/bench/shaft_speed", m.joint_state(t, name=["shaft"], velocity=[float(i)]), t)
            log.write("/bench/delivery_pressure", m.fluid_pressure(t, 1e5 + i), t)
    return path


def write(tmp_path: Path, data: bytes, name: str = "bad.mcap") -> Path:
    p = tmp_path / name
    p.write_bytes(data)
    return p


def test_missing_directory_empty_random(tmp_path: Path):
    cases = {
        tmp_path / "nope.mcap": "file does not exist",
        tmp_path: "is a directory",
        write(tmp_path, b"", "empty.mcap"): "empty file",
        write(tmp_path, os.urandom(4096), "random.mcap"): "not an MCAP file",
        write(tmp_path, b"ROSBAG V2.0\n" + bytes(100), "ros1.bag"): "not an MCAP file",
        write(tmp_path, b"\x89MCAP0\r\n", "magic.mcap"): "no complete MCAP header",
    }
    for path, what in cases.items():
        with pytest.raises(McapReadError, match=what) as err:
            read_topics(path)
        assert str(path) in str(err.value) and err.value.path == str(path)
        assert isinstance(err.value, ValueError)


def test_truncated_file_recovers_first_messages(log_file: Path, tmp_path: Path):
    data = log_file.read_bytes()
    cut = write(tmp_path, data[: len(data) // 2], "cut.mcap")
    with pytest.warns(TruncatedMcapWarning, match=r"cut\.mcap.*recovered (\d+) messages") as rec:
        series = read_topics(cut)
    n_warned = int(str(rec[0].message).rsplit("recovered ", 1)[1].split()[0])
    n = {t: len(s) for t, s in series.items()}
    assert 0 < n["/bench/shaft_speed"] < N and sum(n.values()) == n_warned
    _, v = scalar_series(series["/bench/shaft_speed"], "velocity[0]")
    np.testing.assert_array_equal(v, np.arange(n["/bench/shaft_speed"]))  # the first ones, intact
    with pytest.warns(TruncatedMcapWarning):
        f = open_mcap(cut)
    assert not f.complete and f.truncated_at <= len(data) // 2
    assert f.metadata == {"gerotor_twin.pump_config": {"yaml": "x: 1"}}
    # cut inside the summary only: every message is recovered
    summary_start = data.rindex(b"\x89MCAP0\r\n") - 200
    with pytest.warns(TruncatedMcapWarning, match=f"recovered {2 * N} messages"):
        assert len(read_topics(write(tmp_path, data[:summary_start], "tail.mcap"))) == 2


@pytest.mark.parametrize("compression", ["zstd", "none"])
def test_corrupt_chunk_named(tmp_path: Path, compression: str):
    path = tmp_path / f"corrupt_{compression}.mcap"
    with McapLog(path, chunk_size=1024, compression=compression) as log:
        log.add_topic("/twin/delivery_flow", m.FLOAT64)
        for i in range(300):
            log.write("/twin/delivery_flow", m.float64(i * 1e-6), i)
    with open(path, "rb") as f:
        chunk = make_reader(f).get_summary().chunk_indexes[2]
    data = bytearray(path.read_bytes())
    data[chunk.chunk_start_offset + chunk.chunk_length - 20] ^= 0xFF  # inside the chunk's data
    path.write_bytes(bytes(data))
    assert open_mcap(path).complete  # the summary is intact...
    with pytest.raises(McapReadError, match=rf"corrupt_{compression}\.mcap: corrupt chunk at byte "
                                            rf"{chunk.chunk_start_offset}"):
        read_topics(path)  # ...but the data are not


def test_missing_topic_and_wrong_type(log_file: Path):
    assert require(log_file, {"/bench/shaft_speed": "sensor_msgs/JointState"}) == topic_types(log_file)
    with pytest.raises(McapReadError, match=r"bench\.mcap: topic /bench/oil_temperature "
                                            r"\(sensor_msgs/msg/Temperature\) is missing.*"
                                            r"topics present: /bench/delivery_pressure"):
        require(log_file, {"/bench/oil_temperature": m.TEMPERATURE})
    with pytest.raises(McapReadError, match=r"topic /bench/delivery_pressure is "
                                            r"sensor_msgs/msg/FluidPressure, expected std_msgs/msg/Float64"):
        require(log_file, {"/bench/delivery_pressure": m.FLOAT64, "/bench/shaft_speed": m.JOINT_STATE})
    with pytest.raises(McapReadError, match=r"bench\.mcap: topic\(s\) /twin/x not in file"):
        read_topics(log_file, ["/bench/shaft_speed", "/twin/x"])
    assert metadata(log_file)["gerotor_twin.pump_config"] == {"yaml": "x: 1"}


def test_closed_log_refuses_writes(tmp_path: Path):
    log = McapLog(tmp_path / "c.mcap")
    log.add_topic("/twin/delivery_flow", m.FLOAT64)
    log.close()
    log.close()
    with pytest.raises(McapLogClosed, match=r"c\.mcap"):
        log.write("/twin/delivery_flow", m.float64(0.0), 1)
    assert open_mcap(tmp_path / "c.mcap").message_count == 0
