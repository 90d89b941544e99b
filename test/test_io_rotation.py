"""Round-trip tests of file rotation (gerotor_twin.io.mcap_log.RotatingMcapLog).

A run split by size or by log-time span must give several files
``<stem>_0000.mcap``, ``<stem>_0001.mcap``...; each one complete and
self-contained (all channels and metadata, readable on its own by our reader
and by ``rosbags``), and no message lost or duplicated across them.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import yaml
from rosbags.highlevel import AnyReader

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.io.mcap_log import RotatingMcapLog
from gerotor_twin.io.reader import open_mcap, read_topics, scalar_series

META = {"gerotor_twin.pump_config": {"yaml": "chambers: 7\n"}}
STEP = 1_000_000  # 1 ms


def fill(log: RotatingMcapLog, n: int) -> None:
    log.add_topic("/bench/shaft_speed", m.JOINT_STATE, "sensor")
    log.add_topic("/twin/chamber_pressures", m.FLOAT64_MULTIARRAY)
    log.add_metadata("gerotor_twin.node_parameters", {"log_dir": "/tmp"})
    rng = np.random.default_rng(1)  # incompressible payload so the size limit is reached
    for i in range(n):
        t = i * STEP
        log.write("/bench/shaft_speed", m.joint_state(t, name=["shaft"], velocity=[float(i)]), t)
        log.write("/twin/chamber_pressures", m.float64_multiarray(rng.random(7)), t)


def check_files(log: RotatingMcapLog, n: int) -> list[Path]:
    paths = log.paths
    assert [p.name for p in paths] == [f"run_{k:04d}.mcap" for k in range(len(paths))]
    assert len(paths) >= 3
    total = 0
    for p in paths:
        f = open_mcap(p)
        assert f.complete
        assert set(f.topic_types()) == {"/bench/shaft_speed", "/twin/chamber_pressures"}
        bag = yaml.safe_load(f.metadata.pop("rosbag2")["serialized_metadata"])
        assert bag["message_count"] == f.message_count and bag["relative_file_paths"] == [p.name]
        assert f.metadata == {**META, "gerotor_twin.node_parameters": {"log_dir": "/tmp"}}
        total += f.message_count
        with AnyReader([p]) as r:
            assert sum(c.msgcount for c in r.connections) == f.message_count
    assert total == 2 * n == log.message_count
    series = read_topics(paths)
    _, speed = scalar_series(series["/bench/shaft_speed"], "velocity[0]")
    np.testing.assert_array_equal(speed, np.arange(n))  # in order, none lost, none repeated
    return paths


def test_rotation_by_size(tmp_path: Path):
    n = 600
    with RotatingMcapLog(tmp_path, "run", max_bytes=8192, chunk_size=2048, metadata=META) as log:
        fill(log, n)
    paths = check_files(log, n)
    for p in paths[:-1]:
        record = len(open_mcap(p).metadata["rosbag2"]["serialized_metadata"])
        assert p.stat().st_size < 8192 + 2048 + 4096 + record  # limit + one chunk + summary + rosbag2


def test_rotation_by_duration(tmp_path: Path):
    n = 500  # 0.5 s of log time, 0.1 s per file
    with RotatingMcapLog(tmp_path, "run", max_duration_s=0.1, metadata=META) as log:
        fill(log, n)
    paths = check_files(log, n)
    assert len(paths) == 5
    for p in paths:
        t = read_topics(p)["/bench/shaft_speed"].log_time_ns
        assert t[-1] - t[0] < 100_000_000


def test_rotation_options_checked(tmp_path: Path):
    with pytest.raises(InputError, match="max_bytes"):
        RotatingMcapLog(tmp_path, "run", max_bytes=10)
    with pytest.raises(InputError, match="max_duration_s"):
        RotatingMcapLog(tmp_path, "run", max_duration_s=0)
    with pytest.raises(InputError, match="stem"):
        RotatingMcapLog(tmp_path, "a/b")
    RotatingMcapLog(tmp_path, "run").close()
    with pytest.raises(InputError, match="does not exist yet"):  # never overwrite a log
        RotatingMcapLog(tmp_path, "run")
