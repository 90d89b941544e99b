"""Every MCAP the project ships or writes opens in ``rosbags`` (an independent reader) (behaviour).

For the bundled bags (``bags/``), a ``run-bag`` output and a live node log:
``rosbags`` decodes every message of every topic; the summary's Statistics
start/end times are the first/last message log times (and rosbags reports the
same span, its end being exclusive); message counts agree.  Files written by
the project also carry the ``rosbag2`` metadata record with ``ros_distro: jazzy``.
"""
from __future__ import annotations

import time
from pathlib import Path

import pytest
import yaml
from mcap.reader import make_reader
from rosbags.highlevel import AnyReader

from gerotor_twin.bench_emulator import BenchSpec, Profile, Segment, synthesize
from gerotor_twin.offline import run_bag as rb

ROOT = Path(__file__).resolve().parent.parent
BAGS = sorted((ROOT / "bags").glob("*.mcap"))


def check_file(path: Path, *, rosbag2_record: bool) -> dict[str, int]:
    """Decode everything with rosbags; compare summary times/counts with the messages themselves."""
    counts: dict[str, int] = {}
    times = []
    with AnyReader([path]) as reader:
        for conn, t, raw in reader.messages():
            msg = reader.deserialize(raw, conn.msgtype)
            assert msg is not None
            counts[conn.topic] = counts.get(conn.topic, 0) + 1
            times.append(t)
        assert reader.start_time == min(times) and reader.end_time == max(times) + 1
        assert {c.topic: c.msgcount for c in reader.connections if c.msgcount} == counts
    with open(path, "rb") as f:
        r = make_reader(f)
        stats = r.get_summary().statistics
        meta = {m.name: m.metadata for m in r.iter_metadata()}
    assert stats.message_start_time == min(times) and stats.message_end_time == max(times)
    assert stats.message_count == len(times)
    if rosbag2_record:
        bag = yaml.safe_load(meta["rosbag2"]["serialized_metadata"])
        assert bag["ros_distro"] == "jazzy" and bag["message_count"] == len(times)
        assert bag["starting_time"]["nanoseconds_since_epoch"] == min(times)
        assert bag["duration"]["nanoseconds"] == max(times) - min(times)
        assert {t["topic_metadata"]["name"]: t["message_count"] for t in bag["topics_with_message_count"]
                if t["message_count"]} == counts
    return counts


@pytest.mark.parametrize("bag", BAGS, ids=[b.name for b in BAGS])
def test_bundled_bags(bag):
    counts = check_file(bag, rosbag2_record=False)    # recorded before the record was written
    assert counts["/bench/shaft_speed"] > 100


def test_run_bag_output(tmp_path):
    bench = tmp_path / "bench.mcap"
    synthesize(Profile("t", (Segment(0.6, 1500, 15),)), bench, BenchSpec(bearing="fixed"), progress=None)
    out = tmp_path / "twin.mcap"
    rb.run_bag(bench, out, progress=None, model="fixed")
    counts = check_file(out, rosbag2_record=True)
    assert counts["/twin/flow_summary"] > 5 and counts["/bench/shaft_speed"] > 10
    check_file(bench, rosbag2_record=True)


@pytest.mark.slow
def test_node_log(tmp_path):
    pytest.importorskip("rclpy")
    from gerotor_twin.ros.domain import claim_domain
    from ros_peer import Peer, kill_node, start_node, stop_node
    d = claim_domain()
    proc = start_node(d, tmp_path)
    peer = Peer(d)
    try:
        peer.wait_matched(proc=proc)
        deadline = time.monotonic() + 60
        while len(peer.get("twin/flow_summary")) < 20:
            assert time.monotonic() < deadline and proc.poll() is None
            t = time.time_ns()
            peer.send("shaft_speed", 2000 * 3.141592653589793 / 30, t)
            peer.send("delivery_pressure", 101325.0 + 20e5, t)
            time.sleep(0.005)
        assert stop_node(proc) == 0
    finally:
        kill_node(proc)
        peer.close()
    (log,) = sorted(tmp_path.glob("*.mcap"))
    counts = check_file(log, rosbag2_record=True)
    assert counts["/twin/flow_summary"] >= 20 and counts["/diagnostics"] >= 1
