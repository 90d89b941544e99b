"""``twin_node``: the rclpy node around :class:`gerotor_twin.twin.TwinCore` (thin).

Run::

    twin_node --ros-args --params-file config/twin.yaml [-p log_dir:=/data/twin]
    ros2 run gerotor_twin twin_node --ros-args --params-file config/twin.yaml
    gerotor-twin node --ros-args ...

What it does
    * declares its parameters (:mod:`gerotor_twin.ros.params`) with descriptors;
    * subscribes to the bench inputs with ``raw=True`` and sensor-data QoS: the
      CDR bytes are logged to MCAP untouched (receive time = node clock, publish
      time = source time), decoded with :mod:`gerotor_twin.io.decode` and
      handed to the core with the node-clock receive time;
    * ticks the core at the whole multiples of ``1/tick_rate_hz`` on the node
      clock (``use_sim_time`` follows ``/clock``), encodes every output once with
      the project codec, publishes those bytes (reliable QoS) and logs the same
      bytes (``log_time`` = prediction time);
    * at start, after the model is compiled, measures its real-time factor on
      this machine at the pump's top speed (:mod:`gerotor_twin.twin.startup_rtf`,
      ``startup_rtf_threshold``): logged at INFO, a WARN and a persistent WARN
      status ``gerotor_twin: real time`` when below the threshold;
    * publishes ``/diagnostics`` (core statuses + MCAP log status) at
      ``diagnostics_rate_hz``, and once as soon as it is ready; nothing is
      published or logged before the clock is valid (``use_sim_time``: before the
      first ``/clock``); a ``/clock`` that stops is reported on ``/diagnostics`` by a
      wall-clock (steady) timer (``clock stalled``, WARN, stamped with the last
      clock time) and once per stall on the console (WARN);
    * more than one publisher on an input topic: the first source is followed
      (:mod:`gerotor_twin.twin.sources`), the publishers (graph names, GIDs) are
      listed and WARNed on ``/diagnostics``; a publisher of another type on an
      input topic is named with its type and the expected one (WARN on the
      console, once, and on ``/diagnostics``);
    * the MCAP log and its policy (files, decimation, crash recovery at start,
      disk full): :mod:`gerotor_twin.ros.node_log`;
    * threads (docs/node.md has the measurements behind this): the receiving
      thread (:class:`~gerotor_twin.ros.receiver.InputReceiver`, one rcl wait set
      on the input subscriptions of the service-free node ``<name>_inputs``)
      only receives inputs -- stamps them with the node clock, logs the raw
      bytes, books their publisher sequence numbers (gaps = inputs lost before
      reception, counted per input) and hands them over through a lock held for
      microseconds (:class:`~gerotor_twin.twin.inbox.Inbox`); the model thread
      decodes them into the core, ticks it, publishes and logs the outputs and
      ``/diagnostics``; a third thread spins this node (parameter services,
      ``/clock``).  The numba kernels release the GIL, so reception runs beside
      the model advance.  Measurement switches (environment):
      ``GEROTOR_TWIN_MODEL_THREAD=0``, ``GEROTOR_TWIN_INPUT_NODE=0``,
      ``GEROTOR_TWIN_EXECUTOR=waitset|single|events|multi`` (Jazzy's
      EventsExecutor gives callbacks no message info: losses not countable);
    * SIGINT / SIGTERM: stop the model, keep receiving and logging inputs until
      none came for 0.2 s (at most 3 s), write ``gerotor_twin.input_accounting``,
      close the MCAP log (drained and finalised), exit 0.  Any exception escaping
      a callback is logged and counted; the log is closed in a ``finally`` and at
      interpreter exit.
"""
from __future__ import annotations

import functools
import gc
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
from gerotor_twin.io.fastcdr import encode  # noqa: E402
from gerotor_twin.twin import INPUTS, TwinCore  # noqa: E402
from gerotor_twin.twin.clockwatch import ClockWatch  # noqa: E402
from gerotor_twin.io.decode import decode  # noqa: E402
from gerotor_twin.twin.inbox import Inbox  # noqa: E402
from gerotor_twin.twin.sequence import ACCOUNTING_METADATA, accounting_metadata  # noqa: E402
from gerotor_twin.twin.outputs import DIAGNOSTICS_TOPIC, log_topics, output_topics  # noqa: E402
from gerotor_twin.ros import params as P  # noqa: E402

__all__ = ["TwinNode", "main", "wrong_type_text"]

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

    def __init__(self, param_values: dict | None = None, param_warnings: list[str] | None = None, **kwargs):
        super().__init__("twin_node", **kwargs)
        from gerotor_twin.config import default_config_path, load_config
        from gerotor_twin.model.pump import Inputs, PumpModel

        self.prm = P.declare(self, param_values)
        self.start_warnings: list[str] = []      # params-file sections not applied, config notes (WARN)
        for text in param_warnings or ():
            self._start_warning(text)
        prm = self.prm
        cfg_path = prm["pump_config"] or str(default_config_path())
        self.config = load_config(cfg_path, "pump_config", warn=self._start_warning)
        self.config_text = Path(cfg_path).read_text()
        self.model = PumpModel(self.config, prm["bearing_model"])
        self.settings = P.twin_settings(prm)
        self.core = TwinCore(self.model, self.settings, health=P.health_settings(prm),
                             diagnosis_in_background=prm["diagnosis_in_background"])
        self.core.residual.meter_topic = prm["delivery_flow_topic"]     # named in the residual's status
        self._warm_up(Inputs)
        self._check_real_time(prm["startup_rtf_threshold"])
        self.stopping = False
        self.callback_errors = 0
        self.last_callback_error = ""
        self.log = None
        self._init_threads(prm)

        sensor_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=prm["input_queue_depth"],
                                reliability=ReliabilityPolicy.BEST_EFFORT, durability=DurabilityPolicy.VOLATILE)
        out_qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=10, reliability=ReliabilityPolicy.RELIABLE,
                             durability=DurabilityPolicy.VOLATILE)
        self._in_group = MutuallyExclusiveCallbackGroup()     # one input callback at a time (SequenceGaps)
        self._tick_group = MutuallyExclusiveCallbackGroup()
        self.outputs = output_topics(self.model.N)          # topic -> type, per-chamber topics included
        self.pubs = {t: self.create_publisher(_msg_class(mt), t, out_qos) for t, mt in self.outputs.items()}
        self.pubs[DIAGNOSTICS_TOPIC] = self.create_publisher(_msg_class(m.DIAGNOSTIC_ARRAY), DIAGNOSTICS_TOPIC,
                                                             out_qos)
        self.fq = {t: p.topic_name for t, p in self.pubs.items()}     # fully qualified (remapped) names
        self.subs = {}
        self.input_callbacks = {}
        self.input_node = self._make_input_node()
        for kind, spec in INPUTS.items():
            topic = prm[f"{kind}_topic"]
            if not topic:
                continue
            cb = self.input_callbacks[kind] = self._input_cb(kind, spec.msgtype)
            if self.executor_kind == "events":   # Jazzy's EventsExecutor passes no message info:
                cb = functools.partial(lambda c, data: c(data, None), cb)     # losses cannot be counted
            group = self._in_group if self.input_node is self else None   # (input node: its default group)
            sub = self.input_node.create_subscription(_msg_class(spec.msgtype), topic, cb, sensor_qos,
                                                      callback_group=group, raw=True)
            self.subs[kind] = sub
        self._open_log()
        self.tick_timer = self._start_ticking()
        self.clock_watch = ClockWatch(prm["clock_stall_s"])
        self.clock_timer = self._watch_clock_timer()
        self.startup_s = time.monotonic() - _T_START
        with self._step_lock:
            self._diagnostics(self.get_clock().now().nanoseconds)   # a first /diagnostics right away: "ready"
        if self.model_thread is not None:
            self.model_thread.start()
        self.get_logger().info(
            f"ready in {self.startup_s:.2f} s (process start to first tick possible): {prm['bearing_model']} "
            f"model, {self.model.N} chambers, inputs {sorted(s.topic_name for s in self.subs.values())}, "
            f"log {self.log.log.path if self.log else 'off'}")

    # ---------------------------------------------------------------- set-up
    def _start_warning(self, text: str) -> None:
        """A problem found at start that does not stop the node: WARN now and on every /diagnostics."""
        self.start_warnings.append(text)
        self.get_logger().warning(text)

    def _warm_up(self, Inputs) -> None:
        """Compile / load the JIT kernels now, not in the first tick."""
        inp = Inputs(100.0, self.config.boundary.suction_pressure_pa, self.config.boundary.suction_pressure_pa)
        st = self.model.initial_state(inp)
        self.model.advance(st, 1e-3, inp)

    def _check_real_time(self, threshold: float) -> None:
        """Start-up real-time check (twin/startup_rtf.py): log the figures; WARN and a persistent status below."""
        res = self.core.measure_startup_rtf(threshold)
        if res is not None:
            self.get_logger().info(res.summary())
            self._log_events()

    def _log_events(self) -> None:
        logger = self.get_logger()
        for level, text in self.core.pop_events():
            (logger.error if level >= 2 else logger.warning)(text)

    def _open_log(self) -> None:
        """The MCAP log and its policy (files, crash recovery, decimation, status): ros/node_log.py."""
        from gerotor_twin.ros.node_log import NodeLogFiles
        self.log_files = NodeLogFiles(self.prm, self.get_logger(), self._log_metadata)
        inputs = {sub.topic_name: INPUTS[kind].msgtype for kind, sub in self.subs.items()}
        self.log = self.log_files.open(log_topics(inputs, self.fq, self.log_files.logged, self.outputs))

    def _log_metadata(self) -> dict:
        from gerotor_twin.io.mcap_log import twin_log_metadata
        return twin_log_metadata(self.config_text, str(self.config.source), P.values(self), {
            "gerotor_twin.twin_settings": {k: str(v) for k, v in self.settings.as_dict().items()}})

    def _clock_valid(self, now_ns: int) -> bool:
        """False before the node clock is valid (use_sim_time and no /clock yet: time 0)."""
        return now_ns > 0

    def _init_threads(self, prm) -> None:
        """Inbox, tick grid and the measurement switches (environment; docs/node.md)."""
        self.model_thread_on = os.environ.get("GEROTOR_TWIN_MODEL_THREAD", "1") != "0"
        self.executor_kind = os.environ.get("GEROTOR_TWIN_EXECUTOR", "waitset")
        if self.executor_kind not in _EXECUTORS:
            raise InputError("GEROTOR_TWIN_EXECUTOR", self.executor_kind, " | ".join(_EXECUTORS))
        if self.executor_kind == "waitset" and os.environ.get("GEROTOR_TWIN_INPUT_NODE") == "0":
            raise InputError("GEROTOR_TWIN_INPUT_NODE", "0", "1 with GEROTOR_TWIN_EXECUTOR=waitset")
        self.received = dict.fromkeys(INPUTS, 0)
        self.log_refused = dict.fromkeys(INPUTS, 0)      # write_raw raised: received, not logged
        self._wrong_type_said: set = set()               # wrong-type publishers already logged (topic, gids)
        self._wrong_type_seen: dict = {}                 # ... and when first seen [s, monotonic]
        self.drain_batch = int(os.environ.get("GEROTOR_TWIN_DRAIN_BATCH", "256"))
        self.count_losses = self.executor_kind != "events"   # sequence numbers from every message, or none
        self.inbox = Inbox((lambda: self.get_clock().now().nanoseconds) if prm["use_sim_time"] else time.time_ns)
        self._tick_ns = max(1, int(round(1e9 / prm["tick_rate_hz"])))
        self._diag_ns = max(1, int(round(1e9 / prm["diagnostics_rate_hz"])))
        self._next_diag: int | None = None
        self._wake = threading.Event()
        self._step_lock = threading.Lock()       # one step at a time (model thread vs shutdown)
        self.model_thread = None

    def _make_input_node(self) -> Node:
        """The node that holds the input subscriptions: ``<name>_inputs``, without services.

        rclpy's executor walks every entity of its nodes at each wake-up; the
        parameter and type-description services of this node made that cost
        about 20 % of a core at 1 kHz inputs (docs/node.md).  The inputs live
        on a service-free node, spun alone on the receiving thread; this node
        (parameters, sim-time clock, publishers) is spun on a second, mostly
        idle thread.  ``GEROTOR_TWIN_INPUT_NODE=0``: inputs on this node.
        """
        if os.environ.get("GEROTOR_TWIN_INPUT_NODE") == "0":
            return self
        from rclpy.parameter import Parameter
        return rclpy.create_node(
            f"{self.get_name()}_inputs", namespace=self.get_namespace(), context=self.context,
            start_parameter_services=False, enable_rosout=False,
            parameter_overrides=[Parameter("start_type_description_service", value=False),
                                 Parameter("use_sim_time", value=False)])

    def _start_ticking(self):
        """The tick timer (sim time: wakes the model thread; no model thread: runs the step)."""
        period = 1.0 / self.prm["tick_rate_hz"]
        if not self.model_thread_on:
            return self.create_timer(period, self._safe(self._step), callback_group=self._tick_group)
        self.model_thread = threading.Thread(target=self._model_loop, name="twin-model", daemon=True)
        if self.prm["use_sim_time"]:
            return self.create_timer(period, self._wake.set, callback_group=self._tick_group)
        return None

    def _model_loop(self) -> None:
        """Model thread: a step at every whole multiple of the tick period (wall) or timer wake (sim)."""
        _name_os_thread(b"twin-model")
        sim = self.prm["use_sim_time"]
        while not self.stopping:
            if sim:
                if not self._wake.wait(0.1):
                    continue
            else:
                now = time.time_ns()
                self._wake.wait(((now // self._tick_ns + 1) * self._tick_ns - now) / 1e9)
            self._wake.clear()
            try:
                self._step()
            except Exception as exc:  # noqa: BLE001 - the node must keep running
                self._callback_error(exc)

    def stop_model(self, timeout_s: float = 5.0) -> None:
        """Stop ticking (inputs are still received and logged); idempotent."""
        self.stopping = True
        self._wake.set()
        if self.model_thread is not None and self.model_thread.is_alive():
            self.model_thread.join(timeout_s)

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
        topic = None

        def cb(data: bytes, info: dict) -> None:
            nonlocal topic
            info = info if isinstance(info, dict) else {}
            seq = info.get("publication_sequence_number") if self.count_losses else None
            seq = seq if isinstance(seq, int) and 0 < seq < 2**63 else None     # per publisher; None: unknown
            if self.prm["use_sim_time"] and not self._clock_valid(self.get_clock().now().nanoseconds):
                self.log_files.before_clock += 1       # no /clock yet: nothing stamped 0
                return
            recv = self.inbox.put(kind, data, seq)     # decoded and added to the core by the model thread
            self.received[kind] += 1
            log = self.log
            if log is not None:
                topic = topic or self.subs[kind].topic_name
                src = info.get("source_timestamp")
                try:
                    log.write_raw(topic, data, recv, src or recv,
                                  sequence=seq if seq is not None and seq < 2**32 else None)
                except Exception as exc:  # noqa: BLE001 - counted as not logged; reception goes on
                    self.log_refused[kind] += 1
                    self._callback_error(exc)
            self.core.note_sequence(kind, seq, recv)

        def wrapped(data, info):        # two parameters: rclpy passes (bytes, message info)
            try:
                cb(data, info)
                if self.drain_batch > 1 and self.executor_kind != "waitset":   # (waitset: the receiver does)
                    self._drain_subscription(kind, cb)
            except Exception as exc:  # noqa: BLE001 - the node must keep running
                self._callback_error(exc)
        return wrapped

    def _drain_subscription(self, kind: str, cb) -> None:
        """Take the messages waiting in ``kind``'s history now (up to ``drain_batch``), not one per wait.

        rclpy's executor takes one message per wake-up (wait set rebuilt each
        time); at 1 kHz that overhead dominates the node's CPU (docs/node.md).
        """
        sub = self.subs[kind]
        for _ in range(self.drain_batch - 1):
            with sub.handle:
                got = sub.handle.take_message(sub.msg_type, True)
            if got is None:
                return
            cb(got[0], got[1])

    def _step(self) -> None:
        """Inputs received so far into the core, one tick, outputs out, /diagnostics when due."""
        with self._step_lock:
            if self.stopping:
                return
            now, items = self.inbox.take()
            if not self._clock_valid(now):
                return
            self._to_core(items)
            self._tick(now)
            if self._next_diag is None or now >= self._next_diag or now < self._next_diag - self._diag_ns:
                self._diagnostics(now)

    def _to_core(self, items) -> None:
        for kind, data, recv, seq in items:
            try:
                msg = decode(INPUTS[kind].msgtype, data)
            except InputError as exc:
                self.core.reject(kind, str(exc), recv)
                continue
            self.core.add_message(kind, msg, recv, sequence=seq)

    def _tick(self, now: int) -> None:
        res = self.core.tick(now)
        for out in res.messages:
            data = encode(out.msgtype, out.msg)
            self.pubs[out.topic].publish(data)
            if self.log is not None and self.log_files.due(out.topic):
                self.log.write_raw(self.fq[out.topic], data, out.stamp_ns, out.stamp_ns)
        self._log_events()

    def _watch_clock_timer(self):
        """Under use_sim_time: a steady (wall) timer that reports a stalled /clock on /diagnostics."""
        if not self.prm["use_sim_time"]:
            return None
        from rclpy.clock import Clock, ClockType
        return self.create_timer(1.0 / self.prm["diagnostics_rate_hz"], self._safe(self._watch_clock),
                                 callback_group=self._tick_group, clock=Clock(clock_type=ClockType.STEADY_TIME))

    def _watch_clock(self) -> None:
        """Steady timer: /diagnostics from here while the clock is stalled (the model thread waits for it)."""
        with self._step_lock:
            if self.stopping:
                return
            now = self.get_clock().now().nanoseconds
            if self._watch_update(now).status == "stalled":
                self._diagnostics(now)

    def _watch_update(self, now: int):
        """The clock watch at ``now``; a stall that begins is said once on the console (WARN)."""
        clock = self.clock_watch.update(now, time.monotonic())
        if clock.started:
            self.get_logger().warning(f"{clock.describe()} (clock_stall_s = {self.prm['clock_stall_s']:g} s)")
        return clock

    def _diagnostics(self, now: int) -> None:
        """Publish (and log when due) /diagnostics stamped ``now``; caller holds ``_step_lock``."""
        clock = self._watch_update(now)
        if clock.status == "waiting" or not self._clock_valid(now):
            return                               # no valid time to stamp it with yet (sim time before /clock)
        self._next_diag = (now // self._diag_ns + 1) * self._diag_ns
        diag = self.core.diagnostics(now, [self._node_status(clock)])
        data = encode(m.DIAGNOSTIC_ARRAY, diag)
        self.pubs[DIAGNOSTICS_TOPIC].publish(data)
        if self.log is not None and self.log_files.due(DIAGNOSTICS_TOPIC, diag):
            self.log.write_raw(self.fq[DIAGNOSTICS_TOPIC], data, now, now)

    def _node_status(self, clock=None) -> dict:
        values = {"startup_s": round(self.startup_s, 3), "callback_errors": self.callback_errors,
                  "last_callback_error": self.last_callback_error,
                  "use_sim_time": self.prm["use_sim_time"], "bearing_model": self.prm["bearing_model"],
                  "executor": self.executor_kind, "model_thread": self.model_thread_on,
                  "input_losses_counted": self.count_losses,
                  "model_inbox_dropped": self.inbox.dropped}
        level = m.DIAG_WARN if self.callback_errors else m.DIAG_OK
        msg = "ok"
        if self.start_warnings:
            values["start_warnings"] = clip(" | ".join(self.start_warnings), 1200)
            level, msg = m.DIAG_WARN, clip(self.start_warnings[0], 600)
        many, wrong = self._input_publishers(values)
        if many:
            level, msg = m.DIAG_WARN, "more than one publisher on " + "; ".join(many)
        if wrong:
            level, msg = m.DIAG_WARN, "; ".join(wrong)
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

    def _input_publishers(self, values: dict) -> tuple[list[str], list[str]]:
        """Publishers of each input topic from the ROS graph into ``values``.

        Returns the topics with more than one publisher of the input's type, and one text per
        publisher of another type (DDS never delivers its messages: the input only looks stale),
        each said once on the console (WARN).
        """
        many, wrong = [], []
        for kind, sub in self.subs.items():
            try:
                infos = self.get_publishers_info_by_topic(sub.topic_name)
            except Exception:  # noqa: BLE001 - graph query during shutdown
                continue
            expected = INPUTS[kind].msgtype
            names = [_publisher_name(i) for i in infos if i.topic_type == expected]
            values[f"publishers.{kind}"] = clip(f"{len(names)}: {', '.join(names)}", 300)
            if len(names) > 1:
                many.append(clip(f"{sub.topic_name} ({', '.join(names)})", 200))
            text = wrong_type_text(sub.topic_name, expected, [(i.topic_type, _publisher_name(i)) for i in infos])
            if text:
                wrong.append(text)
                values[f"wrong_type_publishers.{kind}"] = text
                key = (sub.topic_name, frozenset(bytes(i.endpoint_gid) for i in infos if i.topic_type != expected))
                if say_once(self._wrong_type_seen, self._wrong_type_said, key, text, time.monotonic()):
                    self.get_logger().warning(text)
        return many, wrong

    # -------------------------------------------------------------- shutdown
    def _log_drops(self, log) -> dict[str, int]:
        """Inputs received but not logged, per topic: writer queue full, not on disk after a write error
        (disk full), or refused by ``write_raw``."""
        st = log.stats()
        out = dict(st.dropped_queue_full)
        for topic, n in st.lost_by_topic.items():
            out[topic] = out.get(topic, 0) + n
        for kind, n in self.log_refused.items():
            if n and kind in self.subs:
                out[self.subs[kind].topic_name] = out.get(self.subs[kind].topic_name, 0) + n
        return out

    def close_log(self) -> None:
        """Drain and finalise the MCAP log (idempotent, signal-safe)."""
        log = self.log
        if log is not None:
            if not log.closed:
                log.add_metadata(ACCOUNTING_METADATA, accounting_metadata(
                    self.core.input_accounting(), self.core.input_report(0), self._log_drops(log),
                    {k: s.topic_name for k, s in self.subs.items()}, self.inbox.dropped))
            st = log.close(timeout_s=30.0)
            self.get_logger().info(f"MCAP log closed: {st.written} messages written, {st.dropped} dropped")


#: rmw's names of a graph endpoint whose node is not discovered yet (rmw_dds_common)
UNKNOWN_NODE_NAMES = ("_NODE_NAME_UNKNOWN_", "_NODE_NAMESPACE_UNKNOWN_")
#: how long [s] a wrong-type publisher whose node is not discovered yet waits before it is said anyway
NAME_GRACE_S = 3.0


def say_once(seen: dict, said: set, key, text: str, now: float, grace_s: float = NAME_GRACE_S) -> bool:
    """True the one time the publishers ``key`` (a topic and their endpoint gids) are to be said on the console:
    once ``text`` names their nodes (DDS discovers an endpoint before its node's name: rmw says
    :data:`UNKNOWN_NODE_NAMES` meanwhile), or ``grace_s`` [s] after ``now`` first saw them (a DDS writer without a
    ROS node is never named).  ``seen``: first-seen times [s] by key; ``said``: the keys said, both updated."""
    if key in said:
        return False
    first = seen.setdefault(key, now)
    if any(u in text for u in UNKNOWN_NODE_NAMES) and now - first < grace_s:
        return False
    said.add(key)
    return True


def _publisher_name(info) -> str:
    """``/ns/node (gid 0123abcd...)`` of a graph endpoint."""
    return f"{info.node_namespace.rstrip('/')}/{info.node_name} (gid {bytes(info.endpoint_gid)[:8].hex()})"


def wrong_type_text(topic: str, expected: str, publishers: list[tuple[str, str]]) -> str:
    """One line naming the publishers of ``topic`` whose type is not ``expected``; '' if none.

    Parameters
    ----------
    topic : str
        The input topic (as subscribed).
    expected : str
        The input's type, ``pkg/msg/Type``.
    publishers : list of (type, name)
        Every publisher of the topic in the ROS graph.
    """
    by_type: dict[str, list[str]] = {}
    for msgtype, name in publishers:
        if msgtype != expected:
            by_type.setdefault(msgtype, []).append(name)
    if not by_type:
        return ""
    parts = [f"{t} by {', '.join(n)}" for t, n in sorted(by_type.items())]
    return clip(f"{topic.lstrip('/')} is published as {'; as '.join(parts)}; expected {expected} "
                "(its messages never reach the node)", 400)


def _name_os_thread(name: bytes) -> None:
    """Name the calling thread for the OS (``top -H``, /proc/<pid>/task/*/comm); Linux only, best effort."""
    try:
        import ctypes
        ctypes.CDLL(None).prctl(15, ctypes.c_char_p(name[:15]), 0, 0, 0)   # PR_SET_NAME
    except (OSError, AttributeError):
        pass


def _spin_main_node(node: TwinNode, stop: threading.Event) -> threading.Thread:
    """Spin the main node (parameter services, /clock, sim-time tick timer) on its own thread."""
    ex = SingleThreadedExecutor()
    ex.add_node(node)

    def spin():
        try:
            while not stop.is_set() and rclpy.ok():
                ex.spin_once(timeout_sec=0.1)
        except Exception:  # noqa: BLE001 - context shut down
            pass
        finally:
            ex.shutdown(timeout_sec=1.0)

    t = threading.Thread(target=spin, name="twin-main-node", daemon=True)
    t.start()
    return t


def _drain_inputs(node: TwinNode, executor, idle_s: float = 0.2, max_s: float = 3.0) -> None:
    """After a stop: keep receiving (and logging) until no input came for ``idle_s``, at most ``max_s``."""
    t_end = time.monotonic() + max_s
    last, t_last = -1, time.monotonic()
    while time.monotonic() < t_end and time.monotonic() - t_last < idle_s:
        n = sum(node.received.values())
        if n != last:
            last, t_last = n, time.monotonic()
        try:
            executor.spin_once(timeout_sec=0.02)
        except Exception:  # noqa: BLE001 - shutting down anyway
            break


_EXECUTORS = ("waitset", "single", "events", "multi")


def _executor(node: TwinNode):
    """The receiving loop over the input node (docs/node.md compares them).

    ``waitset`` (default): :class:`~gerotor_twin.ros.receiver.InputReceiver`;
    ``single`` / ``multi`` / ``events``: rclpy's executors.
    """
    kind = node.executor_kind
    if kind == "waitset":
        from gerotor_twin.ros.receiver import InputReceiver
        return InputReceiver(node.context, node.subs, node.input_callbacks, node.drain_batch,
                             coalesce_s=node.prm["input_coalesce_s"])
    ex = _rclpy_executor(kind)
    ex.add_node(node.input_node)
    return ex


def _rclpy_executor(kind: str):
    if kind == "events":
        from rclpy.experimental import EventsExecutor
        return EventsExecutor()
    if kind == "multi":
        return MultiThreadedExecutor(num_threads=2)
    return SingleThreadedExecutor()


def _validated_parameters(args: list[str]) -> tuple[dict, list[str]] | None:
    """Every parameter the command line gives (params files and ``-p``), validated, and the warnings about
    params-file sections that do not apply to this node; None after printing why.

    Done before ``rclpy.init`` so a missing or malformed params file, an
    unknown name or a bad value is one line and exit 2 (rcl would print a
    traceback or silently drop it, see :mod:`gerotor_twin.ros.param_args`).
    """
    from gerotor_twin.ros.param_args import overrides_from_args, unapplied_sections
    try:
        return (P.check_overrides(overrides_from_args(list(args), "twin_node")),
                unapplied_sections(list(args), "twin_node"))
    except InputError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return None


def main(argv=None) -> int:
    """Console entry point ``twin_node`` (also ``ros2 run gerotor_twin twin_node``)."""
    args = sys.argv if argv is None else argv
    validated = _validated_parameters(args)
    if validated is None:
        return 2
    param_values, param_warnings = validated
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
    main_spin = None
    try:
        try:
            node = TwinNode(param_values, param_warnings)
        except Exception as exc:  # noqa: BLE001 - one line for the user, exit 2
            from rclpy.exceptions import InvalidParameterValueException, ParameterException
            if isinstance(exc, (InputError, InvalidParameterValueException, ParameterException, OSError)):
                print(f"error: {one_line(exc)}", file=sys.stderr)
                return 2
            raise
        executor = _executor(node)
        # Everything built so far (modules, numba's dispatchers, the model) lives as long as the node: out of the
        # cyclic collector's reach, a full collection no longer walks it (≈ 30 ms with the GIL held, which stalls
        # the model thread and the executor alike; docs/performance.md, "Why the node is built as it is").
        gc.freeze()
        main_spin = _spin_main_node(node, stop) if node.input_node is not node else None
        while not stop.is_set() and rclpy.ok():
            executor.spin_once(timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        if node is not None:
            node.stop_model()                    # ticks stop; inputs still received and logged
            if executor is not None and rclpy.ok():
                _drain_inputs(node, executor)
            if executor is not None:
                executor.shutdown(timeout_sec=2.0)
            stop.set()
            if main_spin is not None:
                main_spin.join(2.0)
            node.close_log()
            if node.input_node is not node:
                node.input_node.destroy_node()
            node.destroy_node()
        rclpy.try_shutdown()
        for sig, h in signals.items():
            signal.signal(sig, h)
    return code


if __name__ == "__main__":
    sys.exit(main())
