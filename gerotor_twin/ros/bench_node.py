"""``gerotor-twin bench node``: startup time and node-level real-time factor of ``twin_node``.

Starts the node as a subprocess on a private ``ROS_DOMAIN_ID`` (twice: the
first start may fill JIT / table caches, the second is "warm"), measures the
time from ``Popen`` to its ``ready`` log line, then feeds bench inputs at
200 Hz at 1000 / 2000 / 3000 rpm (27.5 bar) and reads ``/diagnostics``.

Figures (printed, never asserted)
    startup_s         Popen -> "ready" (interpreter, imports, tables, JIT load, DDS)
    core_rtf          simulated time / compute time inside the ticks (from /diagnostics)
    node_rtf          simulated time / CPU time of the whole node process (all threads:
                      decode, tick, encode, DDS, MCAP writer) over the window
    skips             lag-policy skips in the window (0 = kept up)
"""
from __future__ import annotations

import json
import math
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

__all__ = ["cmd_bench_node", "run"]



def _domain() -> int:
    """This run's private ROS_DOMAIN_ID (claimed once, held until exit)."""
    global _DOMAIN
    if _DOMAIN is None:
        from gerotor_twin.ros.domain import claim_domain
        _DOMAIN = claim_domain()
    return _DOMAIN


_DOMAIN: int | None = None


def _cpu_s(pid: int) -> float:
    with open(f"/proc/{pid}/stat") as fh:
        f = fh.read().rsplit(")", 1)[1].split()
    return (int(f[11]) + int(f[12])) / os.sysconf("SC_CLK_TCK")


def _start(tmp: Path, model: str, log_name: str) -> tuple[subprocess.Popen, float, Path]:
    root = Path(__file__).resolve().parents[2]
    log = tmp / log_name
    args = [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file",
            str(root / "config" / "twin.yaml"), "-p", f"log_dir:={tmp}", "-p", f"bearing_model:={model}"]
    env = dict(os.environ, ROS_DOMAIN_ID=str(_domain()), PYTHONUNBUFFERED="1")
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    t0 = time.monotonic()
    proc = subprocess.Popen(args, stdout=open(log, "w"), stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)
    while time.monotonic() - t0 < 120:
        if "ready in" in log.read_text():
            return proc, time.monotonic() - t0, log
        if proc.poll() is not None:
            raise RuntimeError(f"twin_node exited ({proc.returncode}): {log.read_text()[-2000:]}")
        time.sleep(0.01)
    proc.kill()
    raise RuntimeError("twin_node not ready within 120 s")


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


def run(model: str = "mobility", rpms=(1000, 2000, 3000), seconds: float = 4.0, bar: float = 27.5,
        out=print) -> dict:
    """Measure and print; returns the figures as a dict."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from diagnostic_msgs.msg import DiagnosticArray
    from sensor_msgs.msg import FluidPressure, JointState

    from gerotor_twin.io import messages as m
    from gerotor_twin.io.codec import encode
    from gerotor_twin.twin.decode import decode

    result: dict = {"model": model, "startup_s": [], "rows": []}
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        for k in range(2):
            proc, t, _ = _start(tmp, model, f"start{k}.log")
            _stop(proc)
            result["startup_s"].append(t)
        out(f"twin_node startup (Popen -> ready): first {result['startup_s'][0]:.2f} s, "
            f"warm {result['startup_s'][1]:.2f} s")

        proc, _, log = _start(tmp, model, "run.log")
        ctx = rclpy.Context()
        rclpy.init(context=ctx, domain_id=_domain())
        node = rclpy.create_node("bench_node_peer", context=ctx)
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.BEST_EFFORT)
        pub_w = node.create_publisher(JointState, "bench/shaft_speed", qos)
        pub_p = node.create_publisher(FluidPressure, "bench/delivery_pressure", qos)
        diags: list = []
        lock = threading.Lock()

        def on_diag(data, _info):
            msg = decode(m.DIAGNOSTIC_ARRAY, data)
            vals = {kv.key: kv.value for st in msg.status if st.name == "gerotor_twin: model" for kv in st.values}
            with lock:
                diags.append((time.monotonic(), vals))

        node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, 10, raw=True)
        ex = SingleThreadedExecutor(context=ctx)
        ex.add_node(node)
        spin = threading.Thread(target=lambda: [ex.spin_once(timeout_sec=0.05) for _ in iter(ctx.ok, False)],
                                daemon=True)
        spin.start()
        try:
            pd = 101325.0 + bar * 1e5
            out(f"node-level real-time factor ({model}, {bar:g} bar, inputs at 200 Hz, {seconds:g} s per speed)")
            out(f"  {'rpm':>5s} {'core RTF':>9s} {'node RTF':>9s} {'node CPU':>9s} {'skips':>6s} {'lag [s]':>8s}")
            for rpm in rpms:
                w = rpm * math.pi / 30

                def feed(duration):
                    t_end = time.monotonic() + duration
                    while time.monotonic() < t_end:
                        t = time.time_ns()
                        pub_w.publish(encode(m.JOINT_STATE, m.joint_state(t, name=["shaft"], velocity=[w])))
                        pub_p.publish(encode(m.FLUID_PRESSURE, m.fluid_pressure(t, pd)))
                        time.sleep(0.005)

                feed(1.5)                                  # settle, diagnostics window boundary
                with lock:
                    n0 = len(diags)
                c0, t0 = _cpu_s(proc.pid), time.monotonic()
                feed(seconds)
                c1, t1 = _cpu_s(proc.pid), time.monotonic()
                time.sleep(1.1)
                with lock:
                    window = [v for (tt, v) in diags[n0:] if tt <= t1 + 1.05]
                if len(window) < 2:
                    out(f"  {rpm:5d}  (no diagnostics received)")
                    continue
                sim = float(window[-1]["simulated_s"]) - float(window[0]["simulated_s"])
                skips = int(window[-1]["skips"]) - int(window[0]["skips"])
                rtfs = [float(v["real_time_factor"]) for v in window[1:] if v["real_time_factor"] != "n/a"]
                core_rtf = sorted(rtfs)[len(rtfs) // 2] if rtfs else float("nan")
                cpu = c1 - c0
                node_rtf = sim / cpu if cpu > 0 else float("nan")
                row = {"rpm": rpm, "core_rtf": core_rtf, "node_rtf": node_rtf,
                       "node_cpu_fraction": cpu / (t1 - t0), "skips": skips,
                       "lag_s": float(window[-1]["lag_s"]) if window[-1]["lag_s"] != "n/a" else None}
                result["rows"].append(row)
                out(f"  {rpm:5d} {core_rtf:9.2f} {node_rtf:9.2f} {100 * row['node_cpu_fraction']:8.0f}% "
                    f"{skips:6d} {row['lag_s'] if row['lag_s'] is not None else float('nan'):8.3f}")
        finally:
            _stop(proc)
            ex.shutdown(timeout_sec=1.0)
            node.destroy_node()
            rclpy.try_shutdown(context=ctx)
    return result


def cmd_bench_node(args) -> int:
    """Handler of ``gerotor-twin bench node``."""
    from gerotor_twin.errors import InputError
    try:
        rpms = tuple(int(float(r)) for r in str(args.node_rpms).split(","))
    except ValueError:
        raise InputError("--node-rpms", args.node_rpms, "comma-separated speeds [rpm]") from None
    res = run(model=args.node_model, rpms=rpms, seconds=args.node_seconds)
    if args.json:
        Path(args.json).write_text(json.dumps({"node": res}, indent=2))
        print(f"wrote {args.json}")
    return 0
