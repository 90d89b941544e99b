"""twin_node in real processes: node subprocess on a private ROS_DOMAIN_ID, a bench peer in this process.

Domain ids come from ``claim_domain()``.  Every node process is killed in a
``finally`` / fixture teardown.  No wall-clock time is asserted.
"""
import math
import signal
import threading
import time
from pathlib import Path

import numpy as np
import pytest

rclpy = pytest.importorskip("rclpy")

from gerotor_twin.ros.domain import claim_domain  # noqa: E402
from ros_peer import MS, Peer, kill_node, latest_diag, start_node, stop_node  # noqa: E402

pytestmark = pytest.mark.slow

W = 2000 * math.pi / 30
PD = 101325.0 + 20e5


def _numbers(x):
    if isinstance(x, (list, tuple, np.ndarray)):
        for v in x:
            yield from _numbers(v)
    elif isinstance(x, float):
        yield x
    elif hasattr(x, "__dict__") or hasattr(x, "__slots__"):
        for name in getattr(x, "__slots__", ()) or vars(x):
            v = getattr(x, name.lstrip("_"), None) if not hasattr(x, name) else getattr(x, name)
            if not callable(v):
                yield from _numbers(v)


def assert_no_nan(peer):
    for topic in ("twin/chamber_pressures", "twin/delivery_flow", "twin/flow_summary", "twin/tooth_gaps",
                  "twin/chamber_waveform"):
        for msg in peer.get(topic):
            data = np.asarray(msg.data, dtype=float)
            assert np.all(np.isfinite(data)), topic
    for msg in peer.get("twin/eccentricity"):
        assert all(math.isfinite(v) for v in (msg.vector.x, msg.vector.y, msg.vector.z))


def feed_until_outputs(peer, proc, stamp=time.time_ns, timeout=30.0):
    """Warm-up: send inputs until the node predicts (DDS discovery drops the first messages)."""
    deadline = time.monotonic() + timeout
    while not peer.get("twin/delivery_flow"):
        assert time.monotonic() < deadline, "no output from the node"
        assert proc.poll() is None, "node exited"
        t = stamp()
        peer.send("shaft_speed", W, t)
        peer.send("delivery_pressure", PD, t)
        time.sleep(0.005)


@pytest.fixture(scope="module")
def reference_flow():
    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.model.steady import run_steady
    return run_steady(PumpModel(load_config(), "mobility"), 2000, 20).mean_delivery_flow_m3s


def test_node_predicts_offline_flow_and_sigterm_accounts_every_input(tmp_path, reference_flow):
    """Behaviour (+ literature: offline steady model): mean flow, bounds, and every best-effort input
    sent (warm-up, 2.5 s at 200 Hz, SIGTERM after) is either logged or counted lost by the node."""
    from gerotor_twin.config import load_config
    from rosbags.highlevel import AnyReader
    c = load_config().clearances.housing_radial_m
    d = claim_domain()
    proc = start_node(d, tmp_path)
    peer = Peer(d)
    try:
        peer.wait_matched(proc=proc)
        feed_until_outputs(peer, proc)
        t_end = time.monotonic() + 2.5
        while time.monotonic() < t_end:          # bench at 200 Hz, then SIGTERM mid-stream
            t = time.time_ns()
            peer.send("shaft_speed", W, t)
            peer.send("delivery_pressure", PD, t)
            time.sleep(0.005)
        sent = {k: list(v) for k, v in peer.sent.items()}
        assert stop_node(proc, signal.SIGTERM) == 0
        flows = np.array([msg.data for msg in peer.get("twin/flow_summary")])
        ecc = [(msg.vector.x, msg.vector.y) for msg in peer.get("twin/eccentricity")]
        pres = np.array([msg.data for msg in peer.get("twin/chamber_pressures")])
    finally:
        kill_node(proc)
        peer.close()
    log = (tmp_path / "node.log").read_text()
    assert "ready in" in log and "MCAP log closed" in log, log
    assert len(flows) >= 20
    assert np.mean(flows[-10:, 0]) == pytest.approx(reference_flow, rel=0.01)
    assert all(math.hypot(*e) <= c for e in ecc)
    assert pres.shape[1] == 7 and pres.min() >= 2000.0 and pres.max() <= 1.2 * PD
    files = list(tmp_path.glob("*.mcap"))
    assert len(files) == 1
    got = {"/bench/shaft_speed": set(), "/bench/delivery_pressure": set()}
    topics = set()
    with AnyReader(files) as reader:                 # independent reader
        for conn, _t, raw in reader.messages():
            topics.add(conn.topic)
            if conn.topic in got:
                msg = reader.deserialize(raw, conn.msgtype)
                got[conn.topic].add(msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec)
    assert {"/twin/flow_summary", "/twin/chamber_waveform", "/diagnostics", "/twin/eccentricity"} <= topics
    from gerotor_twin.io import metadata
    from gerotor_twin.twin.sequence import ACCOUNTING_METADATA
    meta = metadata(files[0])
    acct = meta[ACCOUNTING_METADATA]
    for kind in ("shaft_speed", "delivery_pressure"):     # best effort: logged + counted lost = sent
        logged = [s for s in sent[kind] if s in got[f"/bench/{kind}"]]
        lost = sum(int(acct[f"{kind}.{c}"]) for c in ("lost", "missed_at_start", "log_dropped"))
        assert len(logged) + lost == len(sent[kind]), (
            f"{kind}: sent {len(sent[kind])} (warm-up + 2.5 s burst, SIGTERM after), logged {len(logged)}, "
            f"counted lost {lost}")
    assert "chambers: 7" in meta["gerotor_twin.pump_config"]["yaml"]
    assert meta["gerotor_twin.node_parameters"]["bearing_model"] == "'mobility'"


def test_sim_time_coarse_clock_same_mean_flow(tmp_path, reference_flow):
    """/clock at 40 Hz, then at 1 kHz: same revolution-mean flow (the node integrates the real Δt)."""
    d = claim_domain()
    proc = start_node(d, tmp_path, "use_sim_time:=true")
    peer = Peer(d, clock=True)
    sim = [10 * 1_000_000_000]
    try:
        peer.wait_matched(proc=proc)

        def phase(clock_hz, seconds, enough=None):
            """Clock and inputs for ``seconds``, or until ``enough`` revolution summaries came (after 1 s)."""
            peer.clear()
            step = int(1e9 / clock_hz)
            t0 = time.monotonic()
            t_end = t0 + seconds
            next_input = 0
            while time.monotonic() < t_end:
                sim[0] += step
                peer.send_clock(sim[0])
                if sim[0] >= next_input:
                    peer.send("shaft_speed", W, sim[0])
                    peer.send("delivery_pressure", PD, sim[0])
                    next_input = sim[0] + 5 * MS
                time.sleep(step / 1e9)
                if enough and time.monotonic() - t0 > 1.0 and len(peer.get("twin/flow_summary")) >= enough:
                    break
            return np.array([msg.data for msg in peer.get("twin/flow_summary")])

        phase(200, 1.5)                                       # start-up transient
        coarse = phase(40, 3.0, enough=24)
        fine = phase(1000, 2.0, enough=24)
        assert stop_node(proc, signal.SIGINT) == 0
    finally:
        kill_node(proc)
        peer.close()
    assert len(coarse) >= 10 and len(fine) >= 10
    q_coarse, q_fine = np.mean(coarse[-8:, 0]), np.mean(fine[-8:, 0])
    assert q_coarse == pytest.approx(q_fine, rel=2e-3)
    assert q_coarse == pytest.approx(reference_flow, rel=0.01)


def test_bad_parameters_refused(tmp_path):
    for param, needle in (("bearing_model:=foo", "mobility | short | fdm | fixed"),
                          ("tick_rate_hz:=5000.0", "tick_rate_hz")):
        d = claim_domain()
        proc = start_node(d, tmp_path, param)
        try:
            code = proc.wait(60)
        finally:
            kill_node(proc)
        out = (tmp_path / "node.log").read_text()
        assert code == 2, out
        assert needle in out and "Traceback" not in out, out


# ----------------------------------------------------------------------------- bad inputs
class Bench:
    """Background feeder: /clock (sim time) and good inputs at 200 Hz, pausable, with a clock offset."""

    def __init__(self, peer):
        self.peer = peer
        self.offset = 100 * 1_000_000_000 - time.time_ns()
        self.inputs_on = threading.Event()
        self.inputs_on.set()
        self.running = True
        self.lock = threading.Lock()
        self.thread = threading.Thread(target=self.run, daemon=True)
        self.thread.start()

    def now(self):
        return time.time_ns() + self.offset

    def run(self):
        while self.running:
            with self.lock:
                t = self.now()
                self.peer.send_clock(t)
                if self.inputs_on.is_set():
                    self.peer.send("shaft_speed", W, t)
                    self.peer.send("delivery_pressure", PD, t)
            time.sleep(0.005)

    def stop(self):
        self.running = False
        self.thread.join(2)


@pytest.fixture(scope="module")
def bad_node(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("bad")
    d = claim_domain()
    proc = start_node(d, tmp, "use_sim_time:=true", "stale_timeout_s:=0.5")
    peer = Peer(d, clock=True)
    bench = None
    try:
        peer.wait_matched(proc=proc)
        bench = Bench(peer)
        peer.wait_for(lambda: len(peer.get("twin/flow_summary")) > 3, 30, "first predictions", proc)
        yield proc, peer, bench
        bench.stop()
        bench = None
        assert_no_nan(peer)
        assert stop_node(proc, signal.SIGINT) == 0
        from rosbags.highlevel import AnyReader
        with AnyReader(list(tmp.glob("*.mcap"))) as reader:
            assert sum(1 for _ in reader.messages()) > 100
    finally:
        if bench is not None:
            bench.stop()
        kill_node(proc)
        peer.close()


def _input_counter(peer, key):
    d = latest_diag(peer, "gerotor_twin: inputs")
    return int(d.get(key, 0))


def _wait_counter(peer, proc, key, before, what):
    peer.wait_for(lambda: _input_counter(peer, key) > before, 10, what, proc)


def _still_predicting(peer, proc):
    n = len(peer.get("twin/delivery_flow"))
    peer.wait_for(lambda: len(peer.get("twin/delivery_flow")) > n + 5, 10, "predictions to continue", proc)
    assert proc.poll() is None
    assert_no_nan(peer)


@pytest.mark.parametrize("kind,value,reason", [
    ("shaft_speed", float("nan"), "nonfinite"),
    ("shaft_speed", float("inf"), "nonfinite"),
    ("delivery_pressure", float("nan"), "nonfinite"),
    ("shaft_speed", -100.0, "negative"),
    ("delivery_pressure", 1e7, "out_of_range"),
    ("shaft_speed", 1000.0, "out_of_range"),
])
def test_bad_value_reported_node_keeps_running(bad_node, kind, value, reason):
    proc, peer, bench = bad_node
    key = f"{kind}.rejected.{reason}"
    before = _input_counter(peer, key)
    with bench.lock:
        peer.send(kind, value, bench.now())
    _wait_counter(peer, proc, key, before, f"{key} on /diagnostics")
    d = latest_diag(peer, "gerotor_twin: inputs")
    assert kind in d[f"{kind}.last_error"]
    _still_predicting(peer, proc)


@pytest.mark.parametrize("reason", ["duplicate_stamp", "out_of_order_stamp"])
def test_bad_stamps_reported(bad_node, reason):
    proc, peer, bench = bad_node
    key = f"shaft_speed.rejected.{reason}"
    before = _input_counter(peer, key)
    with bench.lock:
        t = bench.now()
        peer.send("shaft_speed", W, t)
        time.sleep(0.05)
        peer.send("shaft_speed", W, t if reason == "duplicate_stamp" else t - 100 * MS)
    _wait_counter(peer, proc, key, before, f"{key} on /diagnostics")
    _still_predicting(peer, proc)


def test_clock_jump_back_resets_model(bad_node):
    proc, peer, bench = bad_node
    before = int(latest_diag(peer, "gerotor_twin: model").get("resets_clock_jump_back", 0))
    with bench.lock:
        bench.offset -= 3_000_000_000                  # bag loop: /clock and stamps 3 s back
    peer.wait_for(lambda: int(latest_diag(peer, "gerotor_twin: model").get("resets_clock_jump_back", 0))
                  > before, 10, "clock jump reported", proc)
    _still_predicting(peer, proc)


def _quiet_count(peer, topic, quiet_s=0.3, timeout_s=5.0):
    """The number of ``topic`` messages received once none has arrived for ``quiet_s`` [s]: what the node had
    published before it stopped, delivered late on a loaded machine; fails if the topic never goes quiet."""
    n, t_end = len(peer.get(topic)), time.monotonic() + timeout_s
    while time.monotonic() < t_end:
        time.sleep(quiet_s)
        m = len(peer.get(topic))
        if m == n:
            return n
        n = m
    raise AssertionError(f"{topic} still arriving {timeout_s} s after the model was held")


def test_inputs_stop_model_held_then_resumes(bad_node):
    """Behaviour: inputs stop while /clock goes on: the model is held (ERROR, "stale" on /diagnostics), nothing
    is predicted from the stale inputs (the flow topic goes quiet once what was published before the hold has
    arrived, and stays so), and predictions resume with the inputs."""
    proc, peer, bench = bad_node
    bench.inputs_on.clear()                            # /clock goes on, inputs stop
    try:
        peer.wait_for(lambda: latest_diag(peer, "gerotor_twin: model").get("status") == "held", 10,
                      "model held on /diagnostics", proc)
        d = latest_diag(peer, "gerotor_twin: model")
        assert d["_level"] == 3 and "stale" in d["_message"]
        n = _quiet_count(peer, "twin/delivery_flow")
        time.sleep(0.5)
        assert len(peer.get("twin/delivery_flow")) <= n + 1   # nothing predicted from stale inputs
    finally:
        bench.inputs_on.set()
    peer.wait_for(lambda: latest_diag(peer, "gerotor_twin: model").get("status") == "running", 10,
                  "model running again", proc)
    _still_predicting(peer, proc)


def test_burst_of_10000_messages(bad_node):
    proc, peer, bench = bad_node
    before = _input_counter(peer, "shaft_speed.accepted")
    with bench.lock:
        t = bench.now()
        for k in range(10_000):
            peer.send("shaft_speed", W, t + k * 1000)
    peer.wait_for(lambda: _input_counter(peer, "shaft_speed.accepted") > before + 1000, 15,
                  "the burst to be taken", proc)
    _still_predicting(peer, proc)


def test_family_pump_startup_rtf_warned_on_diagnostics_and_logged(tmp_path):
    """Behaviour (real process): a pump with another range (4500 rpm / 25 bar) and a threshold no machine
    meets (1000): the node logs its start-up RTF, WARNs, and /diagnostics carries a WARN status with the
    figure and the operating point (top speed), repeated while the node runs.  No input needed."""
    from gerotor_twin.twin.startup_rtf import STATUS_NAME
    text = (Path(__file__).resolve().parent.parent / "config" / "pump.yaml").read_text()
    f = tmp_path / "family.yaml"
    f.write_text(text.replace("max_speed_rpm: 3000.0", "max_speed_rpm: 4500.0")
                 .replace("max_delivery_bar: 27.5", "max_delivery_bar: 25.0"))
    d = claim_domain()
    proc = start_node(d, tmp_path, f"pump_config:={f}", "startup_rtf_threshold:=1000.0")
    peer = Peer(d)
    try:
        peer.wait_for(lambda: len([msg for msg in peer.get("/diagnostics")
                                   if any(st.name == STATUS_NAME for st in msg.status)]) >= 2, 60,
                      "two /diagnostics with the real-time status", proc)
        rt = latest_diag(peer, STATUS_NAME)
        assert stop_node(proc, signal.SIGINT) == 0
    finally:
        kill_node(proc)
        peer.close()
    rtf = float(rt["startup_rtf"])
    assert rt["_level"] == 1 and math.isfinite(rtf) and rtf > 0, rt
    assert float(rt["startup_rtf_speed_rpm"]) == 4500.0 and float(rt["startup_rtf_delivery_bar"]) in (2.0, 25.0)
    assert f"RTF {rtf:.2g} at 4500 rpm" in rt["_message"] and "real time" in rt["_message"], rt["_message"]
    log = (tmp_path / "node.log").read_text()
    assert "start-up real-time check" in log and "[WARN]" in log and f"RTF {rtf:.2g} at 4500 rpm" in log, log
