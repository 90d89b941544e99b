"""Test helpers for the real-process node tests: start ``twin_node``, and a bench peer.

The node runs as a separate process (``python -m gerotor_twin.ros.node``) on a
private ``ROS_DOMAIN_ID``; the :class:`Peer` is a second rclpy participant in
the test process (its own ``Context`` on the same domain) that plays bench
inputs (CDR from the project's codec, published as raw bytes), optionally a
``/clock``, and records every output and ``/diagnostics`` message.
"""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import rclpy
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy

from gerotor_twin.io import messages as m
from gerotor_twin.io.codec import encode
from gerotor_twin.twin import INPUTS, OUTPUT_TOPICS
from gerotor_twin.io.decode import decode

ROOT = Path(__file__).resolve().parent.parent
MS = 1_000_000


def start_node(domain_id: int, tmp: Path, *params: str, env: dict | None = None,
               remaps: tuple[str, ...] = ()) -> subprocess.Popen:
    """twin_node as a subprocess; ``params`` are ``name:=value`` strings, ``remaps`` ``from:=to`` rules (``-r``)."""
    args = [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args",
            "--params-file", str(ROOT / "config" / "twin.yaml"), "-p", f"log_dir:={tmp}"]
    for p in params:
        args += ["-p", p]
    for r in remaps:
        args += ["-r", r]
    e = dict(os.environ, ROS_DOMAIN_ID=str(domain_id), PYTHONUNBUFFERED="1",
             AMENT_PREFIX_PATH=os.environ.get("AMENT_PREFIX_PATH", str(ROOT / ".venv")))
    e.update(env or {})
    out = open(tmp / "node.log", "w")
    return subprocess.Popen(args, stdout=out, stderr=subprocess.STDOUT, env=e, cwd=str(tmp),
                            start_new_session=True)


def stop_node(proc: subprocess.Popen, sig=signal.SIGTERM, timeout: float = 30.0) -> int:
    """Signal the node and wait; kill it if it does not exit.  Returns the exit code."""
    if proc.poll() is None:
        proc.send_signal(sig)
        try:
            return proc.wait(timeout)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)
            raise AssertionError(f"node did not exit within {timeout} s of {sig!r}")
    return proc.returncode


def kill_node(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.kill()
        proc.wait(10)


class Peer:
    """Bench-side rclpy participant in its own context."""

    def __init__(self, domain_id: int, clock: bool = False, outputs: dict[str, str] | None = None):
        """``outputs``: output topic -> type to record (default ``OUTPUT_TOPICS``; ``output_topics(N)`` adds
        the per-chamber topics)."""
        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx, domain_id=domain_id)
        self.node = rclpy.create_node("bench_peer", context=self.ctx)
        sensor = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT,
                            durability=DurabilityPolicy.VOLATILE)
        reliable = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=1000,
                              reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Vector3Stamped
        from rosgraph_msgs.msg import Clock
        from sensor_msgs.msg import FluidPressure, JointState, Temperature
        from std_msgs.msg import Float64, Float64MultiArray
        cls = {m.JOINT_STATE: JointState, m.FLUID_PRESSURE: FluidPressure, m.TEMPERATURE: Temperature,
               m.FLOAT64: Float64, m.FLOAT64_MULTIARRAY: Float64MultiArray, m.VECTOR3_STAMPED: Vector3Stamped,
               m.DIAGNOSTIC_ARRAY: DiagnosticArray}
        self.pubs = {k: self.node.create_publisher(cls[s.msgtype], s.topic, sensor) for k, s in INPUTS.items()}
        self.clock_pub = self.node.create_publisher(Clock, "/clock", 10) if clock else None
        self.lock = threading.Lock()
        outputs = outputs or OUTPUT_TOPICS
        self.received: dict[str, list] = {t: [] for t in [*outputs, "/diagnostics"]}
        types = dict(outputs, **{"/diagnostics": m.DIAGNOSTIC_ARRAY})
        for topic, mt in types.items():
            self.node.create_subscription(cls[mt], topic, self._cb(topic, mt), reliable, raw=True)
        self.sent: dict[str, list[int]] = {k: [] for k in INPUTS}
        self.executor = SingleThreadedExecutor(context=self.ctx)
        self.executor.add_node(self.node)
        self._thread = threading.Thread(target=self._spin, daemon=True)
        self._thread.start()

    def _spin(self):
        try:
            while self.ctx.ok():
                self.executor.spin_once(timeout_sec=0.05)
        except Exception:  # noqa: BLE001 - context shut down
            pass

    def _cb(self, topic, mt):
        def cb(data, _info):
            msg = decode(mt, data)
            with self.lock:
                self.received[topic].append(msg)
        return cb

    def get(self, topic) -> list:
        with self.lock:
            return list(self.received[topic])

    def clear(self):
        with self.lock:
            for v in self.received.values():
                v.clear()

    def wait_for(self, pred, timeout: float, what: str, proc=None):
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if pred():
                return
            if proc is not None and proc.poll() is not None:
                raise AssertionError(f"node exited ({proc.returncode}) while waiting for {what}")
            time.sleep(0.05)
        raise AssertionError(f"timed out after {timeout} s waiting for {what}")

    def wait_matched(self, kinds=("shaft_speed", "delivery_pressure"), timeout=20.0, proc=None):
        self.wait_for(lambda: all(self.pubs[k].get_subscription_count() > 0 for k in kinds), timeout,
                      "the node's subscriptions", proc)

    def send(self, kind: str, value: float, stamp_ns: int):
        if kind == "shaft_speed":
            msg = m.joint_state(stamp_ns, name=["shaft"], velocity=[value])
        elif kind in ("delivery_pressure", "suction_pressure"):
            msg = m.fluid_pressure(stamp_ns, value)
        elif kind == "oil_temperature":
            msg = m.temperature(stamp_ns, value)
        else:
            msg = m.float64(value)
        self.pubs[kind].publish(encode(INPUTS[kind].msgtype, msg))
        self.sent[kind].append(stamp_ns)

    def send_clock(self, t_ns: int):
        self.clock_pub.publish(encode(m.CLOCK, m.clock(t_ns)))

    def close(self):
        try:
            self.executor.shutdown(timeout_sec=1.0)
            self.node.destroy_node()
        finally:
            rclpy.try_shutdown(context=self.ctx)
            self._thread.join(2.0)


def diag_values(diag_msg, name_prefix: str) -> dict[str, str]:
    for st in diag_msg.status:
        if st.name.startswith(name_prefix):
            return {kv.key: kv.value for kv in st.values} | {"_level": st.level, "_message": st.message}
    return {}


def latest_diag(peer, name_prefix: str) -> dict[str, str]:
    msgs = peer.get("/diagnostics")
    return diag_values(msgs[-1], name_prefix) if msgs else {}
