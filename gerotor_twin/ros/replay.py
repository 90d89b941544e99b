"""``gerotor-twin replay``: play a recorded bag into ROS 2 with its original timing, and ``/clock``.

The messages' recorded CDR bytes are published untouched (rclpy 7.1.6
``Publisher.publish(bytes)`` publishes raw serialized data), at their log
times relative to the first message, divided by ``--rate``.  ``/clock``
(rosgraph_msgs/Clock) carries the bag time that has elapsed, at
``--clock-rate`` Hz of wall time, so a node with ``use_sim_time`` runs on the
bag's time base (its MCAP log then aligns with the bag).  ``--loop`` starts
over at the end (the clock jumps back; the twin resets on that).  SIGINT or
SIGTERM stops it cleanly (exit 0).  Publishers are reliable, volatile, depth
100: they match both reliable and sensor-data (best-effort) subscribers.

rclpy is imported inside :func:`replay` only, so the CLI can register this
command without ROS.
"""
from __future__ import annotations

import importlib
import signal
import sys
import threading
import time
from typing import IO

from gerotor_twin.errors import InputError, one_line
from gerotor_twin.io import McapReadError, open_mcap

__all__ = ["load_messages", "replay", "add_parser"]

NS = 1_000_000_000


def load_messages(bag, topics=None) -> tuple[dict[str, str], list[tuple[int, str, bytes]]]:
    """``({topic: pkg/msg/Type}, [(log_time_ns, topic, cdr_bytes), ...] sorted by log time)``.

    Raises
    ------
    McapReadError
        Unreadable bag, a requested topic absent or empty, or no messages.
    """
    f = open_mcap(bag)
    types = f.topic_types()
    if topics:
        want = ["/" + t.lstrip("/") for t in topics]
        absent = [t for t in want if t not in types]
        if absent:
            raise McapReadError(f.path, f"topic(s) {', '.join(absent)} not in the bag; it has: "
                                        f"{', '.join(sorted(types))}")
    else:
        want = sorted(t for t in types if t != "/clock")
    rows = [(msg.log_time, ch.topic, bytes(msg.data)) for ch, msg in f.iter_raw(want)]
    if not rows:
        raise McapReadError(f.path, "no messages to replay on " + ", ".join(want))
    if topics:
        have = {t for _, t, _ in rows}
        empty = [t for t in want if t not in have]
        if empty:
            raise McapReadError(f.path, f"topic(s) {', '.join(empty)} are in the bag but hold no messages")
    rows.sort(key=lambda r: r[0])
    return {t: types[t] for t in want}, rows


def _msg_class(msgtype: str):
    pkg, _, name = msgtype.partition("/msg/")
    try:
        return getattr(importlib.import_module(f"{pkg}.msg"), name)
    except (ImportError, AttributeError):
        raise InputError("message type", msgtype, "a type installed in this environment") from None


def replay(bag, *, rate: float = 1.0, loop: bool = False, topics=None, clock_rate: float = 50.0,
           delay_s: float = 1.0, progress: IO[str] | None = sys.stderr, stop: threading.Event | None = None,
           wait_subscribers: int = 0, wait_timeout_s: float = 15.0) -> dict:
    """Publish a bag's messages with their recorded timing (÷ ``rate``) and ``/clock``.

    Parameters
    ----------
    bag : path
        MCAP recording.
    rate : float
        Playback speed factor (> 0; 2 = twice as fast).
    loop : bool
        Start over at the end until stopped.
    topics : list of str, optional
        Topics to play (default: all but ``/clock``).
    clock_rate : float
        ``/clock`` publications per second of wall time [Hz] (0: no ``/clock``).
    delay_s : float
        Wait after creating the publishers (discovery) [s].
    wait_subscribers : int
        Before playing, wait until every played topic has at least this many matched
        subscriptions (up to ``wait_timeout_s``), so that a volatile subscriber started
        beside the replay misses no message to discovery (0: do not wait).
    wait_timeout_s : float
        Longest wait for the subscribers [s]; then play anyway, with a warning.
    stop : threading.Event, optional
        Set to stop; SIGINT/SIGTERM set it when called from the main thread.

    Returns
    -------
    dict
        Messages and clock ticks published, loops done, whether it was interrupted.
    """
    if not (rate > 0 and rate < 1e3):
        raise InputError("--rate", rate, "(0, 1000)")
    if not 0 <= clock_rate <= 1e4:
        raise InputError("--clock-rate", clock_rate, "[0, 10000] Hz")
    types, rows = load_messages(bag, topics)
    import rclpy
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from rclpy.signals import SignalHandlerOptions
    from rosgraph_msgs.msg import Clock

    stop = stop or threading.Event()
    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGINT, signal.SIGTERM):
            signal.signal(sig, lambda *_: stop.set())
    ctx = rclpy.Context()
    rclpy.init(context=ctx, signal_handler_options=SignalHandlerOptions.NO)
    node = rclpy.create_node("gerotor_twin_replay", context=ctx)
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.RELIABLE,
                     durability=DurabilityPolicy.VOLATILE)
    pubs = {t: node.create_publisher(_msg_class(ty), t, qos) for t, ty in types.items()}
    clock_pub = node.create_publisher(Clock, "/clock", qos) if clock_rate > 0 else None
    t_first, t_last = rows[0][0], rows[-1][0]
    span_s = (t_last - t_first) / NS
    sent = ticks = loops = 0
    try:
        stop.wait(delay_s)
        if wait_subscribers > 0:
            t_wait = time.monotonic() + wait_timeout_s
            while not stop.is_set() and any(p.get_subscription_count() < wait_subscribers for p in pubs.values()):
                if time.monotonic() > t_wait:
                    missing = sorted(t for t, p in pubs.items() if p.get_subscription_count() < wait_subscribers)
                    print(f"replay: warning: no {wait_subscribers} subscriber(s) on {missing} after "
                          f"{wait_timeout_s:g} s; playing anyway", file=sys.stderr)
                    break
                stop.wait(0.05)
            stop.wait(0.2)       # the subscriber side of the match completes shortly after ours
        while not stop.is_set():
            w0 = time.monotonic()
            next_clock = w0
            last_show = 0.0
            for log_ns, topic, data in rows:
                due = w0 + (log_ns - t_first) / NS / rate
                while not stop.is_set():
                    now = time.monotonic()
                    if clock_pub is not None and next_clock <= min(now, due):
                        bag_ns = t_first + int((next_clock - w0) * rate * NS)
                        clock_pub.publish(Clock(clock=_stamp(bag_ns)))
                        ticks += 1
                        next_clock += 1.0 / clock_rate
                        continue
                    if now >= due:
                        break
                    wake = due if clock_pub is None else min(due, next_clock)
                    stop.wait(min(0.05, max(0.0, wake - now)))
                if stop.is_set():
                    break
                pubs[topic].publish(data)
                sent += 1
                now = time.monotonic()
                if progress is not None and now - last_show >= 1.0:
                    last_show = now
                    el = (log_ns - t_first) / NS
                    print(f"\rreplay {el:7.1f}/{span_s:.1f} s of bag ({100 * el / max(span_s, 1e-9):5.1f} %), "
                          f"{sent} messages, rate {rate:g}x, loop {loops + 1} ", end="", file=progress, flush=True)
            if stop.is_set():
                break
            if clock_pub is not None:
                clock_pub.publish(Clock(clock=_stamp(t_last)))
                ticks += 1
            loops += 1
            if not loop:
                break
    finally:
        from rclpy.duration import Duration
        for pub in list(pubs.values()) + ([clock_pub] if clock_pub is not None else []):
            pub.wait_for_all_acked(Duration(seconds=2.0))   # reliable: let the last messages arrive
        node.destroy_node()
        rclpy.shutdown(context=ctx)
    interrupted = stop.is_set()
    if progress is not None:
        print(f"\nreplay {'stopped' if interrupted else 'finished'}: {sent} messages, {ticks} /clock, "
              f"{loops} complete pass(es)", file=progress, flush=True)
    return {"messages": sent, "clock_ticks": ticks, "loops": loops, "interrupted": interrupted,
            "span_s": span_s}


def _stamp(ns: int):
    from builtin_interfaces.msg import Time
    return Time(sec=ns // NS, nanosec=ns % NS)


def cmd_replay(args) -> int:
    try:
        replay(args.bag, rate=args.rate, loop=args.loop, topics=args.topics, clock_rate=args.clock_rate,
               delay_s=args.delay, progress=None if args.quiet else sys.stderr,
               wait_subscribers=args.wait_subscribers)
    except McapReadError as exc:
        print(f"error: {one_line(exc)}", file=sys.stderr)
        return 2
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("replay", help="publish a recorded bag into ROS 2 with its timing, and /clock",
                       description="Publish the recorded CDR bytes of a bag at their original times "
                                   "(scaled by --rate) and /clock on the bag's time base.")
    p.add_argument("bag", help="MCAP recording")
    p.add_argument("--rate", type=float, default=1.0, help="speed factor (default 1.0)")
    p.add_argument("--loop", action="store_true", help="start over at the end until stopped")
    p.add_argument("--topics", nargs="+", help="topics to play (default: all but /clock)")
    p.add_argument("--clock-rate", type=float, default=50.0, help="/clock rate [Hz of wall time], 0 = off (default 50)")
    p.add_argument("--delay", type=float, default=1.0, help="wait before playing (discovery) [s] (default 1)")
    p.add_argument("--wait-subscribers", type=int, default=0, metavar="N",
                   help="wait (up to 15 s) until every played topic has N matched subscribers (default 0)")
    p.add_argument("--quiet", action="store_true", help="no progress line")
    p.set_defaults(func=cmd_replay)
