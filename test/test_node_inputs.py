"""twin_node in real processes: one bad stamp never blocks good samples, zero stamps and a second publisher
are reported on /diagnostics (the second source followed-not, but logged), a stopped /clock is reported.

Tier: behaviour (real peers).  Domain ids from claim_domain(); every node process is stopped by PID.
"""
import contextlib
import math
import signal
import time

import pytest

rclpy = pytest.importorskip("rclpy")

from gerotor_twin.ros.domain import claim_domain  # noqa: E402
from ros_peer import MS, Peer, kill_node, latest_diag, start_node, stop_node  # noqa: E402
from test_ros_node import Bench  # noqa: E402  - /clock + good inputs at 200 Hz, stamps = bench.now()

pytestmark = pytest.mark.slow

W = 2000 * math.pi / 30
PD = 101325.0 + 20e5
INPUTS = "gerotor_twin: inputs"
NODE = "gerotor_twin: node"


def counter(peer, key, name=INPUTS):
    return int(latest_diag(peer, name).get(key, 0))


def send_until_counted(peer, proc, send, key, what, tries=5):
    """Send one sample (best effort: a lone message can be lost under load) until ``key`` counts it."""
    before = counter(peer, key)
    for _ in range(tries):
        send()
        try:
            peer.wait_for(lambda: counter(peer, key) > before, 4, what, proc)
            return
        except AssertionError:
            if proc.poll() is not None:
                raise
    raise AssertionError(f"{what}: not counted after {tries} single samples")


@contextlib.contextmanager
def node_and_bench(tmp, *params):
    """twin_node (params) + a peer + Bench feeding it; yields (proc, peer, bench, domain); stops all by PID."""
    d = claim_domain()
    proc = start_node(d, tmp, *params)
    peer = Peer(d, clock=True)
    bench = None
    try:
        peer.wait_matched(proc=proc)
        bench = Bench(peer)
        peer.wait_for(lambda: latest_diag(peer, "gerotor_twin: model").get("status") == "running", 30,
                      "the model running", proc)
        yield proc, peer, bench, d
        bench.stop()
        bench = None
        if proc.poll() is None:
            assert stop_node(proc, signal.SIGINT) == 0
    finally:
        if bench is not None:
            bench.stop()
        kill_node(proc)
        peer.close()


@pytest.fixture(scope="module")
def wall_node(tmp_path_factory):
    """Wall clock (no use_sim_time): the bench's stamps are 55 years behind, a constant offset (allowed)."""
    tmp = tmp_path_factory.mktemp("inputs")
    with node_and_bench(tmp) as (proc, peer, bench, d):
        yield proc, peer, bench, d, tmp


def test_one_future_stamp_rejected_alone_stream_continues(wall_node):
    """The issue's case: one speed sample stamped 0.9 s ahead; before the fix the next 0.9 s were rejected."""
    proc, peer, bench, _, _ = wall_node
    before = {k: counter(peer, f"shaft_speed.rejected.{k}") for k in ("future_stamp", "out_of_order_stamp")}
    acc = counter(peer, "shaft_speed.accepted")

    def send():
        with bench.lock:
            peer.send("shaft_speed", W, bench.now() + 900 * MS)
    send_until_counted(peer, proc, send, "shaft_speed.rejected.future_stamp", "future_stamp on /diagnostics")
    peer.wait_for(lambda: counter(peer, "shaft_speed.accepted") > acc + 300, 10, "good samples accepted", proc)
    assert counter(peer, "shaft_speed.rejected.out_of_order_stamp") == before["out_of_order_stamp"]
    assert latest_diag(peer, "gerotor_twin: model")["status"] == "running"
    assert "ahead" in latest_diag(peer, INPUTS)["shaft_speed.last_error"]


def test_zero_stamp_counted_and_said(wall_node):
    proc, peer, bench, _, _ = wall_node

    def send():
        with bench.lock:
            peer.send("delivery_pressure", PD, 0)
    send_until_counted(peer, proc, send, "delivery_pressure.zero_stamps", "zero stamp counted")
    peer.wait_for(lambda: any("delivery_pressure: 1 header stamps = 0" in st.message
                              for msg in peer.get("/diagnostics") for st in msg.status), 5,
                  "the zero stamp named in a /diagnostics message", proc)


def test_second_publisher_warned_followed_not_and_logged(wall_node):
    """Two publishers on bench/shaft_speed (B at half the speed, stamps 2 ms older): WARN, A followed, no
    stamp rejections, and every B sample the node received is in the log (counted = logged)."""
    proc, peer, bench, d, tmp = wall_node
    rej0 = counter(peer, "shaft_speed.rejected.out_of_order_stamp")
    seen0 = counter(peer, "shaft_speed.other_source_samples")
    b = Peer(d)
    b_sent = []
    try:
        b.wait_matched(kinds=("shaft_speed",), proc=proc)
        t_end = time.monotonic() + 10.0          # B publishes until the node has counted 100 of its samples
        while time.monotonic() < t_end:
            t = bench.now() - 2 * MS
            b.send("shaft_speed", 0.5 * W, t)
            b_sent.append(t)
            time.sleep(0.005)
            if len(b_sent) % 50 == 0 and counter(peer, "shaft_speed.other_source_samples") > seen0 + 100:
                break
        peer.wait_for(lambda: counter(peer, "shaft_speed.other_source_samples") > seen0 + 100, 10,
                      "other-source samples counted", proc)
        inp, node = latest_diag(peer, INPUTS), latest_diag(peer, NODE)
    finally:
        b.close()
    assert inp["_level"] == 1 and "2 sources publishing" in inp["_message"], inp["_message"]
    assert float(inp["shaft_speed.value_rad/s"]) == pytest.approx(W)
    assert counter(peer, "shaft_speed.rejected.out_of_order_stamp") == rej0
    assert node["_level"] == 1 and "more than one publisher" in node["_message"] and "gid" in node["_message"]
    assert node["publishers.shaft_speed"].startswith("2: ")
    n = len(peer.get("/diagnostics"))                       # two more reports: every B sample processed
    peer.wait_for(lambda: len(peer.get("/diagnostics")) >= n + 2, 10, "/diagnostics", proc)
    received = counter(peer, "shaft_speed.other_source_samples") - seen0
    from rosbags.highlevel import AnyReader
    logged = []
    proc.send_signal(signal.SIGINT)            # finalise the log (the fixture's stop then sees the exit)
    proc.wait(30)
    with AnyReader(list(tmp.glob("*.mcap"))) as reader:
        for conn, _t, raw in reader.messages():
            if conn.topic == "/bench/shaft_speed":
                msg = reader.deserialize(raw, conn.msgtype)
                if msg.velocity[0] == pytest.approx(0.5 * W):
                    logged.append(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec)
    assert len(logged) == received, f"{received} second-source samples received, {len(logged)} logged"
    assert set(logged) <= set(b_sent) and received >= 100
    print(f"second source: {len(b_sent)} sent, {received} received and logged")


def test_clock_stall_reported_on_wall_timer(tmp_path):
    """Behaviour: use_sim_time, /clock stops -> /diagnostics keeps coming (wall timer) and says the clock is
    stalled; the console says it once per stall (WARN)."""
    with node_and_bench(tmp_path, "use_sim_time:=true", "clock_stall_s:=0.5") as (proc, peer, bench, _):
        peer.wait_for(lambda: latest_diag(peer, NODE).get("clock_status") == "ok", 30, "clock ok", proc)
        with bench.lock:                                    # the bench thread blocks: /clock and inputs stop
            peer.wait_for(lambda: latest_diag(peer, NODE).get("clock_status") == "stalled", 10,
                          "clock stalled on /diagnostics", proc)
            n = len(peer.get("/diagnostics"))
            peer.wait_for(lambda: len(peer.get("/diagnostics")) >= n + 2, 10, "/diagnostics while stalled", proc)
            node = latest_diag(peer, NODE)
            said = [ln for ln in (tmp_path / "node.log").read_text().splitlines() if "clock stalled" in ln]
        assert node["_level"] == 1 and "clock stalled" in node["_message"] and int(node["clock_stalls"]) == 1
        # ... and on the console: once for the stall (not at each /diagnostics), at WARN
        assert len(said) == 1 and "WARN" in said[0] and "clock_stall_s = 0.5 s" in said[0], said
        peer.wait_for(lambda: latest_diag(peer, NODE).get("clock_status") == "ok", 10, "clock ok again", proc)


def test_wrong_type_publisher_named_on_console_and_diagnostics(tmp_path):
    """Behaviour: a std_msgs/Float64 publisher on bench/shaft_speed (DDS never delivers it to the JointState
    subscription) is named with its type, its node and the expected type: WARN on /diagnostics and once on the
    console; it is not counted as a second publisher."""
    from std_msgs.msg import Float64
    with node_and_bench(tmp_path) as (proc, peer, bench, d):
        ctx = rclpy.Context()
        rclpy.init(context=ctx, domain_id=d)
        other = rclpy.create_node("wrong_bench", context=ctx)          # its own participant
        try:
            pub = other.create_publisher(Float64, "bench/shaft_speed", 10)
            peer.wait_for(lambda: "wrong_type_publishers.shaft_speed" in latest_diag(peer, NODE), 30,
                          "the wrong-type publisher on /diagnostics", proc)
            pub.publish(Float64(data=1.0))
            n = len(peer.get("/diagnostics"))
            peer.wait_for(lambda: len(peer.get("/diagnostics")) >= n + 2, 10, "more /diagnostics", proc)
            node = latest_diag(peer, NODE)
        finally:
            other.destroy_node()
            rclpy.try_shutdown(context=ctx)
    assert node["_level"] == 1, node
    assert node["_message"].startswith("bench/shaft_speed is published as std_msgs/msg/Float64 by /wrong_bench "
                                       "(gid "), node["_message"]
    assert "; expected sensor_msgs/msg/JointState" in node["_message"]
    assert node["publishers.shaft_speed"].startswith("1: /bench_peer")            # one publisher of the type
    said = [ln for ln in (tmp_path / "node.log").read_text().splitlines() if "is published as" in ln]
    assert len(said) == 1 and "WARN" in said[0] and "/wrong_bench" in said[0], said


def test_wrong_type_text():
    """Behaviour: the line names each other type with its publishers, and the expected type; none: ''."""
    from gerotor_twin.ros.node import wrong_type_text
    js, f64 = "sensor_msgs/msg/JointState", "std_msgs/msg/Float64"
    assert wrong_type_text("/bench/shaft_speed", js, [(js, "/bench")]) == ""
    assert wrong_type_text("/bench/shaft_speed", js, [(js, "/bench"), (f64, "/a"), (f64, "/b")]) == (
        "bench/shaft_speed is published as std_msgs/msg/Float64 by /a, /b; expected sensor_msgs/msg/JointState "
        "(its messages never reach the node)")


def test_a_wrong_type_publisher_is_said_once_and_by_its_name():
    """Behaviour (``node.say_once``): DDS discovers a publisher before its node's name, and rmw names it
    ``_NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_`` meanwhile: the console line waits for the name (up to
    ``NAME_GRACE_S``), is said once per publisher (topic and endpoint gids), not again when the name resolves, and
    is said after the grace for a writer whose node is never named."""
    from gerotor_twin.ros.node import NAME_GRACE_S, say_once
    seen, said = {}, set()
    key = ("/bench/shaft_speed", frozenset({b"\x01" * 16}))
    unknown = "bench/shaft_speed is published as std_msgs/msg/Float64 by _NODE_NAMESPACE_UNKNOWN_/_NODE_NAME_UNKNOWN_"
    named = "bench/shaft_speed is published as std_msgs/msg/Float64 by /wrong_bench"
    assert not say_once(seen, said, key, unknown, 10.0)
    assert not say_once(seen, said, key, unknown, 10.0 + 0.5 * NAME_GRACE_S)
    assert say_once(seen, said, key, named, 10.0 + 0.6 * NAME_GRACE_S)
    assert not say_once(seen, said, key, named, 20.0)
    other = ("/bench/shaft_speed", frozenset({b"\x02" * 16}))
    assert not say_once(seen, said, other, unknown, 30.0)
    assert say_once(seen, said, other, unknown, 30.0 + NAME_GRACE_S)
    assert not say_once(seen, said, other, unknown, 40.0)
