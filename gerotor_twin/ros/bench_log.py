"""Log size of ``twin_node`` per hour at 1 kHz inputs (a measurement, printed; never a test).

::

    python -m gerotor_twin.ros.bench_log [--seconds 40] [--rpm 3000] [--rate 1000] [-p name:=value ...]

Starts ``twin_node`` (config/twin.yaml, log in a temporary directory, extra
``-p`` overrides) on a private ``ROS_DOMAIN_ID``, publishes shaft speed,
delivery pressure (``--inputs``: also suction pressure) at ``--rate`` each (constant ``--rpm``, 20 bar)
with sensor noise (0.1 % speed, 2 kPa pressure: real values do not compress away) for
``--seconds``, stops the node with SIGTERM and measures the log.

Extrapolation to one hour
    The publisher may not reach the nominal rate on a loaded machine, so the
    log is split by what scales with the input rate: the input messages are
    re-written alone (same compression, chunks cut every ``log_flush_s`` of
    log time, as the node does) to get their bytes ``B_in``, and once more
    re-timed to exactly ``--rate`` (same payloads) to get their bytes per
    second at that rate ``b_nom``; then
    ``MB/h = ((total - B_in) / T + b_nom) * 3600 / 1e6`` with ``T`` the logged
    span.  Printed with the per-topic message rates and sizes.
"""
from __future__ import annotations

import argparse
import json
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from gerotor_twin.resources import resource_path
from gerotor_twin.units import P_ATM, bar_gauge_to_pa_abs, rpm_to_rad_s

__all__ = ["run", "main", "topic_bytes"]

_INPUTS = ("shaft_speed", "delivery_pressure")      # the bench's two required inputs


def _start_node(tmp: Path, domain: int, overrides: list[str]) -> subprocess.Popen:
    args = [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file",
            str(resource_path("config", "twin.yaml")), "-p", f"log_dir:={tmp / 'log'}"]
    for o in overrides:
        args += ["-p", o]
    env = dict(os.environ, ROS_DOMAIN_ID=str(domain), PYTHONUNBUFFERED="1")
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    return subprocess.Popen(args, stdout=open(tmp / "node.txt", "w"), stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)


def _publish(domain: int, rpm: float, rate: float, seconds: float, proc, kinds=_INPUTS,
             noise: bool = True) -> dict[str, int]:
    """Publish the inputs at ``rate`` each for ``seconds`` (after the node subscribed); counts sent."""
    import rclpy
    from rclpy.qos import qos_profile_sensor_data

    from gerotor_twin.io import messages as m
    from gerotor_twin.io.codec import encode
    from gerotor_twin.twin import INPUTS
    from gerotor_twin.ros.node import _msg_class

    ctx = rclpy.Context()
    rclpy.init(args=[], context=ctx, domain_id=domain)
    node = rclpy.create_node("bench_log_peer", context=ctx)
    pubs = {k: node.create_publisher(_msg_class(INPUTS[k].msgtype), INPUTS[k].topic, qos_profile_sensor_data)
            for k in kinds}
    sent = {k: 0 for k in kinds}
    try:
        deadline = time.monotonic() + 120
        while not all(p.get_subscription_count() for p in pubs.values()):
            if proc.poll() is not None or time.monotonic() > deadline:
                raise RuntimeError("twin_node did not subscribe (see node.txt)")
            time.sleep(0.05)
        w, pd, ps = rpm_to_rad_s(rpm), bar_gauge_to_pa_abs(20.0), P_ATM
        rng = np.random.default_rng(0)      # sensor noise, as on a bench: values do not compress away
        t0 = time.monotonic()
        k = 0
        while (now := time.monotonic()) - t0 < seconds:
            due = t0 + k / rate
            if now < due:
                time.sleep(min(due - now, 0.001))
                continue
            ns = time.time_ns()
            n1, n2, n3 = rng.standard_normal(3) if noise else (0.0, 0.0, 0.0)
            for kind, msg in (("shaft_speed", m.joint_state(ns, name=["shaft"], velocity=[w * (1 + 1e-3 * n1)])),
                              ("delivery_pressure", m.fluid_pressure(ns, pd + 2e3 * n2)),
                              ("suction_pressure", m.fluid_pressure(ns, ps + 5e2 * n3))):
                if kind not in pubs:
                    continue
                pubs[kind].publish(encode(INPUTS[kind].msgtype, msg))
                sent[kind] += 1
            k += 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown(context=ctx)
    return sent


def topic_bytes(paths, input_topics: set[str], flush_s: float, compression: str,
                rate_hz: float | None = None) -> int:
    """Bytes of some topics alone, written like the node writes them (chunks every flush_s).

    With ``rate_hz`` the messages of each topic are re-timed to exactly that rate
    (log and publish time; the payload, with its header stamp, is unchanged).
    """
    k_of: dict[str, int] = {}
    t0: list = []
    import io

    from mcap.writer import Writer

    from gerotor_twin.io.mcap_log import COMPRESSIONS
    from gerotor_twin.io.reader import open_mcap

    buf = io.BytesIO()
    w = Writer(buf, chunk_size=1 << 30, compression=COMPRESSIONS[compression])
    w.start("ros2", "")
    ids: dict[int, int] = {}
    last_flush = None
    for p in paths:
        f = open_mcap(p)
        for ch, msg in f.iter_raw(input_topics):
            if ch.id not in ids:
                sid = w.register_schema(f.schemas[ch.schema_id].name, "ros2msg", f.schemas[ch.schema_id].data)
                ids[ch.id] = w.register_channel(ch.topic, "cdr", sid, dict(ch.metadata))
            log_t, pub_t = msg.log_time, msg.publish_time
            if rate_hz is not None:
                t0 = t0 or [log_t]
                k = k_of[ch.topic] = k_of.get(ch.topic, -1) + 1
                log_t, pub_t = t0[0] + int(k * 1e9 / rate_hz), t0[0] + int(k * 1e9 / rate_hz) - (log_t - pub_t)
            if last_flush is None or log_t - last_flush >= flush_s * 1e9:
                w.flush()
                last_flush = log_t
            w.add_message(ids[ch.id], log_t, msg.data, pub_t, msg.sequence)
    w.finish()
    return len(buf.getvalue())


def run(seconds: float = 40.0, rpm: float = 3000.0, rate: float = 1000.0, overrides=(), out=print,
        kinds=_INPUTS, noise: bool = True) -> dict:
    """Measure; returns the figures (also printed through ``out``)."""
    from gerotor_twin.io.reader import open_mcap
    from gerotor_twin.ros.domain import claim_domain
    from gerotor_twin.ros.params import PARAMETERS

    defaults = {p.name: p.default for p in PARAMETERS}
    with tempfile.TemporaryDirectory(prefix="bench_log_") as tmp_s:
        tmp = Path(tmp_s)
        domain = claim_domain()
        proc = _start_node(tmp, domain, list(overrides))
        try:
            sent = _publish(domain, rpm, rate, seconds, proc, kinds, noise)
            time.sleep(0.5)
        finally:
            if proc.poll() is None:
                proc.send_signal(signal.SIGTERM)
                try:
                    proc.wait(60)
                except subprocess.TimeoutExpired:
                    proc.kill()
                    proc.wait(10)
        paths = sorted((tmp / "log").glob("*.mcap"))
        total = sum(p.stat().st_size for p in paths)
        counts: dict[str, int] = {}
        first = last = None
        for p in paths:
            f = open_mcap(p)
            for ch, msg in f.iter_raw():
                counts[ch.topic] = counts.get(ch.topic, 0) + 1
                first = msg.log_time if first is None else min(first, msg.log_time)
                last = msg.log_time if last is None else max(last, msg.log_time)
        span_s = (last - first) * 1e-9
        prm = dict(defaults, **{o.split(":=")[0]: o.split(":=")[1] for o in overrides})
        inputs = {"/bench/" + k for k in kinds} & set(counts)
        flush_s, comp = float(prm["log_flush_s"]), str(prm["log_compression"])
        in_bytes = topic_bytes(paths, inputs, flush_s, comp)
        achieved = sum(counts[t] for t in inputs) / len(inputs) / span_s
        # the same input messages re-timed to the nominal rate: their bytes per message at that rate
        in_nominal_per_s = topic_bytes(paths, inputs, flush_s, comp, rate) / (span_s * achieved / rate)
        mb_h = ((total - in_bytes) / span_s + in_nominal_per_s) * 3600 / 1e6
        res = {"per_topic_bytes": {t: topic_bytes(paths, {t}, float(prm["log_flush_s"]),
                                                  str(prm["log_compression"])) for t in counts},
               "files": len(paths), "bytes": total, "input_bytes": in_bytes, "span_s": span_s,
               "achieved_input_rate_hz": achieved, "nominal_input_rate_hz": rate, "rpm": rpm,
               "sent": sent, "rates_hz": {t: n / span_s for t, n in sorted(counts.items())},
               "mb_per_hour_at_nominal_rate": mb_h, "overrides": list(overrides), "noise": noise}
    out(f"log: {len(paths)} file(s), {total / 1e6:.2f} MB over {span_s:.1f} s "
        f"(inputs {in_bytes / 1e6:.2f} MB at {achieved:.0f} Hz each)")
    for t, r in res["rates_hz"].items():
        out(f"  {t:45s} {r:9.1f} msg/s  {res['per_topic_bytes'][t] / span_s * 3.6e-3:7.1f} MB/h alone")
    out(f"extrapolated to {rate:g} Hz inputs at {rpm:g} rpm: {mb_h:.0f} MB/h")
    return res


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m gerotor_twin.ros.bench_log", description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=40.0)
    ap.add_argument("--rpm", type=float, default=3000.0)
    ap.add_argument("--rate", type=float, default=1000.0, help="publish rate of each input [Hz]")
    ap.add_argument("--inputs", default=",".join(_INPUTS),
                    help="inputs published at --rate (of shaft_speed, delivery_pressure, suction_pressure)")
    ap.add_argument("--no-noise", action="store_true", help="constant set-points (no sensor noise)")
    ap.add_argument("-p", dest="overrides", action="append", default=[], help="node parameter name:=value")
    ap.add_argument("--json", help="write the figures to this file")
    args = ap.parse_args(argv)
    res = run(args.seconds, args.rpm, args.rate, args.overrides, kinds=tuple(args.inputs.split(",")),
              noise=not args.no_noise)
    if args.json:
        Path(args.json).write_text(json.dumps(res, indent=2))
    return 0


if __name__ == "__main__":
    sys.exit(main())
