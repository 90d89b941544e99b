"""``twin_node``: the rclpy node around :class:`gerotor_twin.twin.TwinCore` (thin).

Run::

    twin_node --ros-args --params-file config/twin.yaml [-p log_dir:=/data/twin]
    ros2 run gerotor_twin twin_node --ros-args --params-file config/twin.yaml
    gerotor-twin node --ros-args ...

What it does
    * declares its parameters (:mod:`gerotor_twin.ros.params`) with descriptors;
    * subscribes to the bench inputs with ``raw=True`` and sensor-data QoS: the
      CDR bytes are logged to MCAP untouched (receive time = node clock, publish
      time = source time), decoded with :mod:`gerotor_twin.twin.decode` and
      handed to the core with the node-clock receive time;
    * ticks the core on a node-clock timer (``use_sim_time`` follows ``/clock``),
      encodes every output once with the project codec, publishes those bytes
      (reliable QoS) and logs the same bytes (``log_time`` = prediction time);
    * publishes ``/diagnostics`` (core statuses + MCAP log status) at
      ``diagnostics_rate_hz``, and once as soon as it is ready; under
      ``use_sim_time`` on a wall-clock (steady) timer, so a ``/clock`` that
      stops is reported (``clock stalled``, WARN, stamped with the last clock
      time); nothing is published before the first ``/clock``;
    * more than one publisher on an input topic: the first source is followed
      (:mod:`gerotor_twin.twin.sources`), the publishers (graph names, GIDs)
      are listed and WARNed on ``/diagnostics``;
    * one single-threaded executor: a tick integrates at most ``max_span_s``
      (lag policy), inputs wait in the subscription history
      (``input_queue_depth``) meanwhile; rclpy's multi-threaded executor was
      measured slower (``GEROTOR_TWIN_EXECUTOR=multi`` selects it);
    * SIGINT / SIGTERM: stop spinning, close the MCAP log (drained and
      finalised), exit 0.  Any exception escaping a callback is logged and
      counted; the log is closed in a ``finally`` and at interpreter exit.
"""
from __future__ import annotations

import os
import signal
import sys
import threading
import time
import traceback
from pathlib import Path

_T_START = time.monotonic()

import rclpy  # noqa: E402
from rclpy.callback_groups import MutuallyExclusiveCallbackGroup  # noqa: E402
from rclpy.executors import ExternalShutdownException, MultiThreadedExecutor, SingleThreadedExecutor  # noqa: E402,E501
from rclpy.node import Node  # noqa: E402
from rclpy.qos import (HistoryPolicy, QoSProfile, ReliabilityPolicy, DurabilityPolicy)  # noqa: E402
from rclpy.signals import SignalHandlerOptions  # noqa: E402

from gerotor_twin.errors import InputError, clip, one_line  # noqa: E402
from gerotor_twin.io import messages as m  # noqa: E402
from gerotor_twin.twin.fastcdr import encode  # noqa: E402
from gerotor_twin.twin import INPUTS, OUTPUT_TOPICS, TwinCore, TwinSettings  # noqa: E402
from gerotor_twin.twin.clockwatch import ClockWatch  # noqa: E402
from gerotor_twin.twin.decode import decode  # noqa: E402
from gerotor_twin.twin.outputs import DIAGNOSTICS_TOPIC  # noqa: E402
from gerotor_twin.ros import params as P  # noqa: E402

__all__ = ["TwinNode", "main"]

_MSG_CLASSES = {
    m.JOINT_STATE: ("sensor_msgs.msg", "JointState"), m.FLUID_PRESSURE: ("sensor_msgs.msg", "FluidPressure"),
    m.TEMPERATURE: ("sensor_msgs.msg", "Temperature"), m.FLOAT64: ("std_msgs.msg", "Float64"),
    m.FLOAT64_MULTIARRAY: ("std_msgs.msg", "Float64MultiArray"),
    m.VECTOR3_STAMPED: ("geometry_msgs.msg", "Vector3Stamped"),
    m.DIAGNOSTIC_ARRAY: ("diagnostic_msgs.msg", "DiagnosticArray"),
}


def _msg_class(msgtype: str):
    import importlib
    mod, name = _MSG_CLASSES[msgtype]
    return getattr(importlib.import_module(mod), name)


class TwinNode(Node):
    """The digital-twin node; see the module docstring."""

    def __init__(self, param_values: dict | None = None, **kwargs):
        super().__init__("twin_node", **kwargs)
        from gerotor_twin.config import default_config_path, load_config
        from gerotor_twin.model.pump import Inputs, PumpModel

        self.prm = P.declare(self, param_values)
        prm = self.prm
        cfg_path = prm["pump_config"] or str(default_config_path())
        self.config = load_config(cfg_path)
        self.config_text = Path(cfg_path).read_text()
        self.model = PumpModel(self.config, prm["bearing_model"])
        sp = prm["sample_period_s"]
        every = max(1, round(1.0 / (prm["publish_rate_hz"] * sp)))
        self.settings = TwinSettings(
            sample_period_s=sp, publish_period_s=every * sp, max_span_s=prm["max_span_s"],
            stale_timeout_s=prm["stale_timeout_s"], filter_tau_s=prm["input_filter_tau_s"],
            stamp_restart_s=prm["stamp_restart_s"], stamp_ahead_s=prm["stamp_ahead_s"],
            stamp_rebase_samples=prm["stamp_rebase_samples"], waveform_every=prm["waveform_every"],
            waveform_samples=prm["waveform_samples"])
        self.core = TwinCore(self.model, self.settings)
        self._warm_up(Inputs)
        self.stopping = False
        self.callback_errors = 0
        self.last_callback_error = ""
        self._log_lock = threading.Lock()
        self.log = None

        sensor_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=prm["input_queue_depth"],
                                reliability=ReliabilityPolicy.BEST_EFFORT, durability=DurabilityPolicy.VOLATILE)
        out_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.VOLATILE)
        self._in_group = MutuallyExclusiveCallbackGroup()
        self._tick_group = MutuallyExclusiveCallbackGroup()
        self._diag_group = MutuallyExclusiveCallbackGroup()
        self._core_lock = threading.Lock()       # tick and diagnostics never overlap
        self.pubs = {t: self.create_publisher(_msg_class(mt), t, out_qos) for t, mt in OUTPUT_TOPICS.items()}
        self.pubs[DIAGNOSTICS_TOPIC] = self.create_publisher(_msg_class(m.DIAGNOSTIC_ARRAY), DIAGNOSTICS_TOPIC,
                                                             out_qos)
        self.fq = {t: p.topic_name for t, p in self.pubs.items()}     # fully qualified (remapped) names
        self.subs = {}
        for kind, spec in INPUTS.items():
            topic = prm[f"{kind}_topic"]
            if not topic:
                continue
            sub = self.create_subscription(_msg_class(spec.msgtype), topic, self._input_cb(kind, spec.msgtype),
                                           sensor_qos, callback_group=self._in_group, raw=True)
            self.subs[kind] = sub
        self._open_log()
        self.tick_timer = self.create_timer(1.0 / prm["tick_rate_hz"], self._safe(self._tick),
                                            callback_group=self._tick_group)
        self.clock_watch = ClockWatch(prm["clock_stall_s"])
        self.diag_timer = self.create_timer(1.0 / prm["diagnostics_rate_hz"], self._safe(self._diagnostics),
                                            callback_group=self._diag_group, clock=self._diagnostics_clock())
        self.startup_s = time.monotonic() - _T_START
        self._diagnostics()                      # a first /diagnostics right away: "ready"
        self.get_logger().info(
            f"ready in {self.startup_s:.2f} s (process start to first tick possible): {prm['bearing_model']} "
            f"model, {self.model.N} chambers, inputs {sorted(s.topic_name for s in self.subs.values())}, "
            f"log {self.log.log.path if self.log else 'off'}")

    # ---------------------------------------------------------------- set-up
    def _warm_up(self, Inputs) -> None:
        """Compile / load the JIT kernels now, not in the first tick."""
        inp = Inputs(100.0, self.config.boundary.suction_pressure_pa, self.config.boundary.suction_pressure_pa)
        st = self.model.initial_state(inp)
        self.model.advance(st, 1e-3, inp)

    def _open_log(self) -> None:
        """The MCAP log and its policy (files, crash recovery, decimation, status): ros/node_log.py."""
        from gerotor_twin.ros.node_log import NodeLogFiles
        self.log_files = NodeLogFiles(self.prm, self.get_logger(), self._log_metadata)
        topics = [(sub.topic_name, INPUTS[kind].msgtype, "sensor") for kind, sub in self.subs.items()]
        topics += [(self.fq[t], mt, "reliable") for t, mt in OUTPUT_TOPICS.items() if self.log_files.logged(t)]
        topics.append((self.fq[DIAGNOSTICS_TOPIC], m.DIAGNOSTIC_ARRAY, "reliable"))
        self.log = self.log_files.open(topics)

    def _log_metadata(self) -> dict:
        from gerotor_twin.io.mcap_log import PUMP_CONFIG_METADATA
        return {PUMP_CONFIG_METADATA: {"yaml": self.config_text, "path": str(self.config.source)},
                "gerotor_twin.node_parameters": {k: repr(v) if isinstance(v, str) else str(v)
                                                 for k, v in P.values(self).items()},
                "gerotor_twin.twin_settings": {k: str(v) for k, v in self.settings.as_dict().items()}}

    def _clock_valid(self, now_ns: int) -> bool:
        """False before the node clock is valid (use_sim_time and no /clock yet: time 0)."""
        return now_ns > 0

    def _callback_error(self, exc: Exception) -> None:
        self.callback_errors += 1
        self.last_callback_error = clip(f"{type(exc).__name__}: {exc}", 300)
        if self.callback_errors in (1, 10, 100, 1000) or self.callback_errors % 10000 == 0:
            self.get_logger().error(f"callback error #{self.callback_errors}: {self.last_callback_error}\n"
                                    + traceback.format_exc(limit=5))

    def _safe(self, fn):
        """Wrap a timer callback: an exception is logged and counted, never kills the executor."""
        def wrapped():
            try:
                fn()
            except Exception as exc:  # noqa: BLE001 - the node must keep running
                self._callback_error(exc)
        return wrapped

    # ------------------------------------------------------------- callbacks
    def _input_cb(self, kind: str, msgtype: str):
        def cb(data: bytes, info: dict) -> None:
            recv = self.get_clock().now().nanoseconds
            if not self._clock_valid(recv):     # use_sim_time, no /clock yet: nothing stamped 0
                self.log_files.before_clock += 1
                return
            log = self.log
            seq = info.get("publication_sequence_number") if isinstance(info, dict) else None
            seq = seq if isinstance(seq, int) and 0 < seq < 2**63 else None     # per publisher; None: unknown
            if log is not None:
                src = info.get("source_timestamp") if isinstance(info, dict) else None
                log.write_raw(self.subs[kind].topic_name, data, recv, src or recv,
                              sequence=seq if seq is not None and seq < 2**32 else None)
            try:
                msg = decode(msgtype, data)
            except InputError as exc:
                self.core.reject(kind, str(exc), recv)
                return
            self.core.add_message(kind, msg, recv, sequence=seq)

        def wrapped(data, info):        # two parameters: rclpy passes (bytes, message info)
            try:
                cb(data, info)
            except Exception as exc:  # noqa: BLE001 - the node must keep running
                self._callback_error(exc)
        return wrapped

    def _tick(self) -> None:
        if self.stopping:
            return
        with self._core_lock:
            now = self.get_clock().now().nanoseconds
            if not self._clock_valid(now):
                return
            res = self.core.tick(now)
        for out in res.messages:
            data = encode(out.msgtype, out.msg)
            self.pubs[out.topic].publish(data)
            if self.log is not None and self.log_files.due(out.topic):
                self.log.write_raw(self.fq[out.topic], data, out.stamp_ns, out.stamp_ns)
        logger = self.get_logger()
        for level, text in self.core.pop_events():
            (logger.error if level >= 2 else logger.warning)(text)

    def _diagnostics_clock(self):
        """Wall (steady) clock for /diagnostics under use_sim_time, so a stopped /clock is reported."""
        if not self.prm["use_sim_time"]:
            return None
        from rclpy.clock import Clock, ClockType
        return Clock(clock_type=ClockType.STEADY_TIME)

    def _diagnostics(self) -> None:
        if self.stopping:
            return
        now = self.get_clock().now().nanoseconds
        clock = self.clock_watch.update(now, time.monotonic())
        if clock.status == "waiting" or not self._clock_valid(now):
            return                               # no valid time to stamp it with yet (sim time before /clock)
        extra = [self._node_status(clock)]
        with self._core_lock:
            diag = self.core.diagnostics(now, extra)
        data = encode(m.DIAGNOSTIC_ARRAY, diag)
        self.pubs[DIAGNOSTICS_TOPIC].publish(data)
        if self.log is not None and self.log_files.due(DIAGNOSTICS_TOPIC, diag):
            self.log.write_raw(self.fq[DIAGNOSTICS_TOPIC], data, now, now)

    def _node_status(self, clock=None) -> dict:
        values = {"startup_s": round(self.startup_s, 3), "callback_errors": self.callback_errors,
                  "last_callback_error": self.last_callback_error,
                  "use_sim_time": self.prm["use_sim_time"], "bearing_model": self.prm["bearing_model"]}
        level = m.DIAG_WARN if self.callback_errors else m.DIAG_OK
        msg = "ok"
        many = self._input_publishers(values)
        if many:
            level, msg = m.DIAG_WARN, "more than one publisher on " + "; ".join(many)
        if clock is not None:
            values.update({"clock_status": clock.status, "clock_unchanged_s": round(clock.unchanged_s, 3),
                           "clock_stalls": self.clock_watch.stalls})
            if clock.status == "stalled":
                level, msg = m.DIAG_WARN, clock.describe()
        log_level, log_msg, log_values = self.log_files.status(self.log)
        values.update(log_values)
        if log_level >= level and log_msg:
            level, msg = log_level, log_msg
        return m.diagnostic_status(level, "gerotor_twin: node", msg, hardware_id="gerotor_twin", values=values)

    def _input_publishers(self, values: dict) -> list[str]:
        """Publishers of each input topic from the ROS graph into ``values``; topics with more than one."""
        many = []
        for kind, sub in self.subs.items():
            try:
                infos = self.get_publishers_info_by_topic(sub.topic_name)
            except Exception:  # noqa: BLE001 - graph query during shutdown
                continue
            names = [f"{i.node_namespace.rstrip('/')}/{i.node_name} (gid {bytes(i.endpoint_gid)[:8].hex()})"
                     for i in infos]
            values[f"publishers.{kind}"] = clip(f"{len(names)}: {', '.join(names)}", 300)
            if len(names) > 1:
                many.append(clip(f"{sub.topic_name} ({', '.join(names)})", 200))
        return many

    # -------------------------------------------------------------- shutdown
    def close_log(self) -> None:
        """Drain and finalise the MCAP log (idempotent, signal-safe)."""
        log = self.log
        if log is not None:
            st = log.close(timeout_s=30.0)
            self.get_logger().info(f"MCAP log closed: {st.written} messages written, {st.dropped} dropped")


def _validated_parameters(args: list[str]) -> dict | None:
    """Every parameter the command line gives (params files and ``-p``), validated; None after printing why.

    Done before ``rclpy.init`` so a missing or malformed params file, an
    unknown name or a bad value is one line and exit 2 (rcl would print a
    traceback or silently drop it, see :mod:`gerotor_twin.ros.param_args`).
    """
    from gerotor_twin.ros.param_args import overrides_from_args
    try:
        return P.check_overrides(overrides_from_args(list(args), "twin_node"))
    except InputError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return None


def main(argv=None) -> int:
    """Console entry point ``twin_node`` (also ``ros2 run gerotor_twin twin_node``)."""
    args = sys.argv if argv is None else argv
    param_values = _validated_parameters(args)
    if param_values is None:
        return 2
    try:
        rclpy.init(args=args, signal_handler_options=SignalHandlerOptions.NO)
    except Exception as exc:  # noqa: BLE001 - rcl refused the command line (RCLError): one line, exit 2
        print(f"error: {one_line(str(exc).split(', at /')[0])}", file=sys.stderr)
        return 2
    stop = threading.Event()
    node = None
    executor = None
    signals = {}

    def on_signal(signum, _frame):
        if stop.is_set():               # second signal: finalise the log now and leave
            if node is not None:
                node.close_log()
            os._exit(128 + signum)
        stop.set()
        if executor is not None:
            executor.wake()  # noqa: SLF001 - leave the wait set promptly

    for sig in (signal.SIGINT, signal.SIGTERM):
        signals[sig] = signal.signal(sig, on_signal)
    code = 0
    try:
        try:
            node = TwinNode(param_values)
        except Exception as exc:  # noqa: BLE001 - one line for the user, exit 2
            from rclpy.exceptions import InvalidParameterValueException, ParameterException
            if isinstance(exc, (InputError, InvalidParameterValueException, ParameterException, OSError)):
                print(f"error: {one_line(exc)}", file=sys.stderr)
                return 2
            raise
        # rclpy's MultiThreadedExecutor costs more than it gains here (measured: node RTF 0.8 vs 1.8
        # at 2000 rpm); ticks are bounded by max_span_s and inputs wait in the DDS history meanwhile.
        executor = (MultiThreadedExecutor(num_threads=2) if os.environ.get("GEROTOR_TWIN_EXECUTOR") == "multi"
                    else SingleThreadedExecutor())
        executor.add_node(node)
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.stopping = True                 # ticks become no-ops; inputs still logged
            if executor is not None and rclpy.ok():
                deadline = time.monotonic() + 0.3    # drain inputs already delivered to the readers
                while time.monotonic() < deadline:
                    try:
                        executor.spin_once(timeout_sec=0.05)
                    except Exception:  # noqa: BLE001 - shutting down anyway
                        break
            if executor is not None:
                executor.shutdown(timeout_sec=2.0)
            node.close_log()
            node.destroy_node()
        rclpy.try_shutdown()
        for sig, h in signals.items():
            signal.signal(sig, h)
    return code


if __name__ == "__main__":
    sys.exit(main())
