"""twin_node's named, stamped outputs and live flow residual, live and in its MCAP log (behaviour, real processes).

The node runs as a subprocess on a private ``ROS_DOMAIN_ID`` (``claim_domain``); a bench peer in this
process plays shaft speed and delivery pressure, then a flow meter, and records the outputs.  The MCAP
file is read back with ``rosbags`` (independent reader).  No wall-clock time is asserted.
"""
import math
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from gerotor_twin.io import messages as m  # noqa: E402
from gerotor_twin.ros.domain import claim_domain  # noqa: E402
from gerotor_twin.twin.outputs import (RESIDUAL_FIELDS, SUMMARY_FIELDS, chamber_names,  # noqa: E402
                                       chamber_pressure_topics, output_topics, sample_names)
from ros_peer import Peer, kill_node, latest_diag, start_node, stop_node  # noqa: E402

pytestmark = pytest.mark.slow

W = 2000 * math.pi / 30
PD = 101325.0 + 20e5
N = 7                                  # chambers of the packaged pump
Q_METER = 5.0e-4                       # what the emulated flow meter reads [m³/s]


def _bench(peer, proc, until, flow=None, timeout=30.0):
    """Play the bench at 200 Hz (and a 100 Hz flow meter) until ``until()`` or fail."""
    deadline = time.monotonic() + timeout
    k = 0
    while not until():
        assert time.monotonic() < deadline, "the node did not produce what the test waits for"
        assert proc.poll() is None, "node exited"
        t = time.time_ns()
        peer.send("shaft_speed", W, t)
        peer.send("delivery_pressure", PD, t)
        if flow is not None and k % 2 == 0:
            peer.send("delivery_flow", flow, t)
        k += 1
        time.sleep(0.005)


def _stamp(msg) -> int:
    return m.ns_from_stamp(msg.header.stamp)


def test_named_stamped_outputs_and_residual_live_and_logged(tmp_path):
    """Chambers by name, twin/sample and twin/revolution stamped with model time; without a flow meter the
    residual is absent and /diagnostics says so; with one it is published per revolution; all in the log."""
    from rosbags.highlevel import AnyReader
    d = claim_domain()
    proc = start_node(d, tmp_path, "log_outputs_every:=1", "log_summary_values:=true")
    peer = Peer(d, outputs=output_topics(N))
    try:
        peer.wait_matched(proc=proc)
        _bench(peer, proc, lambda: len(peer.get("twin/revolution")) >= 5 and peer.get("/diagnostics"))
        _bench(peer, proc, lambda: "flow_residual" in latest_diag(peer, "gerotor_twin: model"))
        before = latest_diag(peer, "gerotor_twin: model")
        assert before["flow_residual"].startswith(
            "not published: no measured delivery flow received on bench/delivery_flow"), before
        assert peer.get("twin/flow_residual") == []
        peer.wait_matched(("delivery_flow",), proc=proc)
        _bench(peer, proc, lambda: len(peer.get("twin/flow_residual")) >= 10, flow=Q_METER)
        assert stop_node(proc) == 0
    finally:
        kill_node(proc)
        peer.close()
    live = {t: peer.get(t) for t in (*chamber_pressure_topics(N), "twin/sample", "twin/revolution",
                                     "twin/flow_residual", "twin/chamber_pressures")}
    for k, topic in enumerate(chamber_pressure_topics(N)):
        assert len(live[topic]) > 20, topic
        for msg in live[topic][-20:]:
            assert msg.header.frame_id == "pump_housing" and 2000.0 < msg.fluid_pressure < 1.2 * PD
    for msg in live["twin/sample"]:
        assert tuple(msg.name) == sample_names(N)
    for msg in live["twin/revolution"]:
        assert tuple(msg.name) == SUMMARY_FIELDS
    res = live["twin/flow_residual"]
    for msg in res:
        v = dict(zip(msg.name, msg.position))
        assert tuple(msg.name) == RESIDUAL_FIELDS and v["measured_delivery_m3s"] == pytest.approx(Q_METER)
        assert v["delivery_residual_m3s"] == pytest.approx(Q_METER - v["predicted_delivery_m3s"], rel=1e-9)
    rev_by_stamp = {_stamp(r): dict(zip(r.name, r.position)) for r in live["twin/revolution"]}
    paired = [r for r in res if _stamp(r) in rev_by_stamp]          # residual stamp = its revolution's stamp
    assert len(paired) == len(res)
    for r in paired:
        assert dict(zip(r.name, r.position))["predicted_delivery_m3s"] == \
            rev_by_stamp[_stamp(r)]["mean_delivery_m3s"]
    _check_log(tmp_path, AnyReader)


def _check_log(tmp_path, AnyReader):
    """Every new topic is in the MCAP file; each message's header stamp equals its log_time (model time), and
    chamber_0k's pressure is data[k-1] of twin/chamber_pressures logged at that time."""
    files = list(tmp_path.glob("*.mcap"))
    assert len(files) == 1
    wanted = {"/" + t for t in (*chamber_pressure_topics(N), "twin/sample", "twin/revolution", "twin/flow_residual")}
    seen = {t: 0 for t in wanted}
    arrays, chambers = {}, {}
    with AnyReader(files) as reader:
        conns = [c for c in reader.connections if c.topic in wanted | {"/twin/chamber_pressures"}]
        assert {c.topic for c in conns} == wanted | {"/twin/chamber_pressures"}
        types = {c.topic: c.msgtype for c in conns}
        for conn, log_time, raw in reader.messages(connections=conns):
            msg = reader.deserialize(raw, conn.msgtype)
            if conn.topic == "/twin/chamber_pressures":
                arrays[log_time] = list(msg.data)
                continue
            assert _stamp(msg) == log_time, conn.topic
            seen[conn.topic] += 1
            if conn.topic.startswith("/twin/chambers/"):
                chambers[(conn.topic, log_time)] = msg.fluid_pressure
    for k, topic in enumerate(chamber_pressure_topics(N)):
        pairs = [(p, arrays[t]) for (tp, t), p in chambers.items() if tp == "/" + topic and t in arrays]
        assert len(pairs) > 20 and all(p == a[k] for p, a in pairs), topic
    assert types["/twin/chambers/chamber_01/pressure"] == "sensor_msgs/msg/FluidPressure"
    assert types["/twin/flow_residual"] == "sensor_msgs/msg/JointState"
    assert all(n > 0 for n in seen.values()), seen
    assert seen["/twin/flow_residual"] >= 10
    assert chamber_names(N)[0] == "chamber_01"
