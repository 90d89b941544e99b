"""A bench in its own process: shaft speed and delivery pressure at a fixed rate (for benchmarks/tests).

Run::

    python -m gerotor_twin.ros.bench_publisher --rate 1000 --seconds 5 --rpm 3000 --bar 27.5 \\
        --out pub.json [--settle 1.0] [--domain D]

Waits until both topics have a subscriber, then ``--settle`` seconds more (so
discovery has completed both ways), prints ``publishing`` and publishes
``bench/shaft_speed`` (sensor_msgs/JointState) and ``bench/delivery_pressure``
(sensor_msgs/FluidPressure, absolute) with best-effort sensor QoS on an
absolute schedule (no drift), prints ``published``, stays ``--linger`` s, writes
``--out`` and prints ``done``.  Each pair carries the publish time (wall clock,
ns) as header stamp.  At the end it writes ``--out`` (JSON): ``published``
(per input, the DDS writer numbers its samples 1..n), ``stamps`` (publish
times [ns], one per pair), ``late`` (periods started more than one period late).
"""
from __future__ import annotations

import argparse
import json
import math
import sys
import time

from gerotor_twin.units import bar_gauge_to_pa_abs, rpm_to_rad_s

__all__ = ["main"]


def _parse(argv):
    ap = argparse.ArgumentParser(prog="bench_publisher", description=__doc__.splitlines()[0])
    ap.add_argument("--rate", type=float, default=1000.0, help="publish rate per input [Hz]")
    ap.add_argument("--seconds", type=float, default=5.0, help="publishing time [s]")
    ap.add_argument("--rpm", type=float, default=3000.0, help="shaft speed [rpm]")
    ap.add_argument("--bar", type=float, default=27.5, help="delivery pressure, gauge [bar]")
    ap.add_argument("--settle", type=float, default=1.0, help="wait after the subscriptions matched [s]")
    ap.add_argument("--linger", type=float, default=1.0,
                    help="stay matched after the last message [s] (a writer that leaves at once may take "
                         "its undelivered samples with it)")
    ap.add_argument("--domain", type=int, default=None, help="ROS_DOMAIN_ID (default: environment)")
    ap.add_argument("--out", required=True, help="JSON file written at the end")
    a = ap.parse_args(argv)
    for name, lo, hi in (("rate", 1.0, 20000.0), ("seconds", 0.0, 86400.0), ("settle", 0.0, 60.0),
                         ("linger", 0.0, 60.0)):
        v = getattr(a, name)
        if not (lo <= v <= hi and math.isfinite(v)):
            ap.error(f"--{name} = {v!r}; allowed: [{lo:g}, {hi:g}]")
    return a


def main(argv=None) -> int:
    a = _parse(sys.argv[1:] if argv is None else argv)
    import rclpy
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import FluidPressure, JointState

    from gerotor_twin.io import messages as m
    from gerotor_twin.io.codec import encode

    ctx = rclpy.Context()
    rclpy.init(context=ctx, domain_id=a.domain)
    node = rclpy.create_node("bench_publisher", context=ctx)
    qos = QoSProfile(history=HistoryPolicy.KEEP_LAST, depth=100, reliability=ReliabilityPolicy.BEST_EFFORT,
                     durability=DurabilityPolicy.VOLATILE)
    pub_w = node.create_publisher(JointState, "bench/shaft_speed", qos)
    pub_p = node.create_publisher(FluidPressure, "bench/delivery_pressure", qos)
    try:
        deadline = time.monotonic() + 60.0
        while pub_w.get_subscription_count() == 0 or pub_p.get_subscription_count() == 0:
            if time.monotonic() > deadline:
                print("error: no subscriber on bench/shaft_speed and bench/delivery_pressure within 60 s",
                      file=sys.stderr)
                return 3
            time.sleep(0.02)
        time.sleep(a.settle)
        print("publishing", flush=True)
        w, pd = rpm_to_rad_s(a.rpm), bar_gauge_to_pa_abs(a.bar)
        period = int(round(1e9 / a.rate))
        n = int(round(a.seconds * a.rate))
        stamps, late = [], 0
        t_next = time.time_ns()
        for _ in range(n):
            now = time.time_ns()
            if now < t_next:
                time.sleep((t_next - now) / 1e9)
            elif now - t_next > period:
                late += 1
            t = time.time_ns()
            pub_w.publish(encode(m.JOINT_STATE, m.joint_state(t, name=["shaft"], velocity=[w])))
            pub_p.publish(encode(m.FLUID_PRESSURE, m.fluid_pressure(t, pd)))
            stamps.append(t)
            t_next += period
        print("published", flush=True)
        time.sleep(a.linger)
        with open(a.out, "w") as fh:
            json.dump({"published": {"shaft_speed": n, "delivery_pressure": n}, "stamps": stamps, "late": late,
                       "rate_hz": a.rate, "rpm": a.rpm, "bar": a.bar}, fh)
        print("done", flush=True)
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
    return 0


if __name__ == "__main__":
    sys.exit(main())
