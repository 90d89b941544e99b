"""``gerotor-twin replay``: real processes on a private ROS_DOMAIN_ID (claimed with gerotor_twin.ros.domain)."""
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from gerotor_twin.io import McapReadError
from gerotor_twin.ros.domain import claim_domain
from gerotor_twin.ros.replay import load_messages
from report_helpers import write_bench

ROOT = Path(__file__).resolve().parent.parent

SUBSCRIBER = r"""
import json, sys, threading, time
import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy, HistoryPolicy
from sensor_msgs.msg import JointState, FluidPressure
from std_msgs.msg import Float64
from rosgraph_msgs.msg import Clock
out, seconds = sys.argv[1], float(sys.argv[2])
rclpy.init()
node = rclpy.create_node("replay_probe")
qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.RELIABLE)
got = {"/bench/shaft_speed": [], "/bench/delivery_pressure": [], "/bench/delivery_flow": [], "/clock": []}
def raw_cb(topic):
    return lambda data, info: got[topic].append(data.hex())
for t, ty in (("/bench/shaft_speed", JointState), ("/bench/delivery_pressure", FluidPressure),
              ("/bench/delivery_flow", Float64)):
    node.create_subscription(ty, t, raw_cb(t), qos, raw=True)
node.create_subscription(Clock, "/clock", lambda msg: got["/clock"].append(msg.clock.sec * 10**9 + msg.clock.nanosec), qos)
ex = SingleThreadedExecutor(); ex.add_node(node)
t_end = [time.monotonic() + seconds]
def _finished():             # a line on stdin: the replay has exited; take what is still in flight, then stop
    sys.stdin.readline()
    t_end[0] = min(t_end[0], time.monotonic() + 1.0)
threading.Thread(target=_finished, daemon=True).start()
print("ready", flush=True)
while time.monotonic() < t_end[0]:
    ex.spin_once(timeout_sec=0.05)
json.dump(got, open(out, "w"))
node.destroy_node(); rclpy.shutdown()
"""


def _env(domain):
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), PYTHONPATH=str(ROOT))
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    return env


def _start(args, domain, **kw):
    return subprocess.Popen(args, env=_env(domain), cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, **kw)


def _stop(proc):
    if proc.poll() is None:
        proc.kill()
    proc.communicate(timeout=10)


@pytest.fixture
def bag(tmp_path):
    return write_bench(tmp_path / "bench.mcap", duration=2.0, rate=50.0)


def test_load_messages_and_bad_topics(bag):
    types, rows = load_messages(bag, ["bench/shaft_speed"])
    assert types == {"/bench/shaft_speed": "sensor_msgs/msg/JointState"} and len(rows) == 100
    with pytest.raises(McapReadError, match="/bench/nothing"):
        load_messages(bag, ["/bench/nothing"])


@pytest.mark.slow
def test_subscriber_gets_the_recorded_bytes_and_clock(bag, tmp_path):
    out = tmp_path / "got.json"
    dom = claim_domain()
    sub = _start([sys.executable, "-c", SUBSCRIBER, str(out), "12"], dom, stdin=subprocess.PIPE)
    rep = None
    try:
        assert sub.stdout.readline().strip() == "ready"
        rep = _start([sys.executable, "-m", "gerotor_twin", "replay", str(bag), "--rate", "2", "--clock-rate", "40",
                      "--delay", "0.5", "--wait-subscribers", "1"], dom)
        _, err = rep.communicate(timeout=60)
        assert rep.returncode == 0, err
        assert "finished: 300 messages" in err
        sub.communicate("replay exited\n", timeout=30)     # the subscriber listens 1 s more (12 s at most)
    finally:
        _stop(sub)
        if rep is not None:
            _stop(rep)
    got = json.loads(out.read_text())
    _, rows = load_messages(bag)
    for topic in ("/bench/shaft_speed", "/bench/delivery_pressure", "/bench/delivery_flow"):
        want = [d.hex() for _, t, d in rows if t == topic]
        assert got[topic] == want, topic                          # every message, untouched, in order
    clock = got["/clock"]
    assert len(clock) >= 10 and clock == sorted(clock)
    assert clock[0] >= rows[0][0] and clock[-1] == rows[-1][0]    # bag time base, ends at the last message


@pytest.mark.slow
def test_sigterm_stops_a_looping_replay(bag):
    rep = _start([sys.executable, "-m", "gerotor_twin", "replay", str(bag), "--loop", "--rate", "5",
                  "--delay", "0.2"], claim_domain())
    try:
        deadline = time.monotonic() + 60
        line = ""
        while "replay" not in line and time.monotonic() < deadline:   # progress line appears once playing
            line = rep.stderr.read(40) or ""
            if rep.poll() is not None:
                break
        rep.send_signal(signal.SIGTERM)
        _, err = rep.communicate(timeout=30)
    finally:
        _stop(rep)
    assert rep.returncode == 0
    assert "stopped" in err


def test_cli_bad_bag(tmp_path, capsys):
    from gerotor_twin.cli import main
    assert main(["replay", str(tmp_path / "none.mcap")]) == 2
    assert "does not exist" in capsys.readouterr().err
