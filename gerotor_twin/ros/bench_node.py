"""``gerotor-twin bench node``: startup time, CPU, real-time factor, latency and input accounting of ``twin_node``.

Starts the node as a subprocess on a private ``ROS_DOMAIN_ID`` (twice: the
first start may fill JIT / table caches, the second is "warm"), measures the
time from ``Popen`` to its ``ready`` log line.  Then, per speed, a fresh node
and a bench publisher in a SEPARATE process (:mod:`gerotor_twin.ros.bench_publisher`,
shaft speed + delivery pressure at ``rate`` Hz, default 1 kHz), optionally
beside ``busy`` CPU-bound processes (a loaded bench PC).

``--config F`` runs the node on that pump (``pump_config``), by default at its
top speed (``range.max_speed_rpm``) and highest delivery pressure
(``range.max_delivery_bar``); without it, the packaged pump.

Figures (printed, never asserted), per speed
    node CPU          CPU time of the node process (all threads) / wall time over the
                      measurement window [% of one core]
    start RTF         the node's start-up real-time check (``startup_rtf`` on /diagnostics:
                      the model alone at the pump's top speed, worst pressure end)
    core_rtf          simulated time / compute time inside the ticks (median of /diagnostics)
    node_rtf          simulated time / CPU time of the whole node process
    latency p50/p99   input publish time -> reception (in this process) of the first
                      ``twin/eccentricity`` stamped at or after it (the instantaneous
                      outputs of one instant share that stamp) [ms]
    published         inputs sent by the publisher (both topics)
    logged            of those, in the node's MCAP file (read back after the run)
    lost              counted lost by the node (MCAP metadata ``gerotor_twin.input_accounting``:
                      sequence gaps + missed at start + MCAP writer drops)
    unaccounted       published - logged - lost (must be 0)
    skips             lag-policy skips in the window (0 = the model kept up with the clock)

With ``repeats`` > 1 each speed is run that many times, each with a fresh node,
and a ``median`` line follows (medians of the rates and latencies, sums of the
counts): on a shared 2-core machine the node CPU of one start differs from the
next by several points.
"""
from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
import threading
import time
from pathlib import Path

from gerotor_twin.resources import resource_path

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


def _thread_cpu_s(pid: int) -> dict[str, float]:
    """CPU time [s] of the node's threads by role: executor (main), model, dds, other (MCAP writer, ...)."""
    out = {"executor": 0.0, "model": 0.0, "dds": 0.0, "other": 0.0}
    for task in Path(f"/proc/{pid}/task").iterdir():
        try:
            comm = (task / "comm").read_text().strip()
            f = (task / "stat").read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        role = ("executor" if task.name == str(pid) else "model" if comm == "twin-model"
                else "dds" if comm.startswith("dds.") else "other")
        out[role] += (int(f[11]) + int(f[12])) / os.sysconf("SC_CLK_TCK")
    return out


def _start(tmp: Path, model: str, log_name: str, params: tuple = ()) -> tuple[subprocess.Popen, float, Path]:
    log = tmp / log_name
    args = [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file",
            str(resource_path("config", "twin.yaml")), "-p", f"log_dir:={tmp}", "-p", f"bearing_model:={model}"]
    for p in params:
        args += ["-p", p]
    env = dict(os.environ, ROS_DOMAIN_ID=str(_domain()), PYTHONUNBUFFERED="1")
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    t0 = time.monotonic()
    proc = subprocess.Popen(args, stdout=open(log, "w"), stderr=subprocess.STDOUT, env=env,
                            start_new_session=True)
    while time.monotonic() - t0 < 300:
        if "ready in" in log.read_text():
            return proc, time.monotonic() - t0, log
        if proc.poll() is not None:
            raise RuntimeError(f"twin_node exited ({proc.returncode}): {log.read_text()[-2000:]}")
        time.sleep(0.01)
    proc.kill()
    raise RuntimeError("twin_node not ready within 300 s")


def _stop(proc: subprocess.Popen) -> None:
    if proc.poll() is None:
        proc.terminate()
        try:
            proc.wait(30)
        except subprocess.TimeoutExpired:
            proc.kill()
            proc.wait(10)


class _Peer:
    """rclpy participant of this process: records /diagnostics and stamped outputs with receive times."""

    def __init__(self):
        import rclpy
        from rclpy.executors import SingleThreadedExecutor
        from rclpy.qos import QoSProfile, ReliabilityPolicy
        from diagnostic_msgs.msg import DiagnosticArray
        from geometry_msgs.msg import Vector3Stamped

        from gerotor_twin.io import messages as m
        from gerotor_twin.io.decode import decode
        from gerotor_twin.twin.diagnostics import MODEL_STATUS_NAME
        from gerotor_twin.twin.startup_rtf import STATUS_NAME as STARTUP_STATUS_NAME

        self.ctx = rclpy.Context()
        rclpy.init(context=self.ctx, domain_id=_domain())
        self.node = rclpy.create_node("bench_node_peer", context=self.ctx)
        self.lock = threading.Lock()
        self.diags: list = []
        self.outputs: list = []
        qos = QoSProfile(depth=1000, reliability=ReliabilityPolicy.RELIABLE)

        def on_diag(data, _info):
            msg = decode(m.DIAGNOSTIC_ARRAY, data)
            vals = {kv.key: kv.value for st in msg.status if st.name in (MODEL_STATUS_NAME, STARTUP_STATUS_NAME)
                    for kv in st.values}
            with self.lock:
                self.diags.append((time.monotonic(), vals))

        def on_output(data, _info):
            recv = time.time_ns()
            msg = decode(m.VECTOR3_STAMPED, data)
            with self.lock:
                self.outputs.append((msg.header.stamp.sec * 1_000_000_000 + msg.header.stamp.nanosec, recv))

        self.node.create_subscription(DiagnosticArray, "/diagnostics", on_diag, qos, raw=True)
        self.node.create_subscription(Vector3Stamped, "twin/eccentricity", on_output, qos, raw=True)
        self.ex = SingleThreadedExecutor(context=self.ctx)
        self.ex.add_node(self.node)
        self.thread = threading.Thread(target=self._spin, daemon=True)
        self.thread.start()

    def _spin(self):
        try:
            while self.ctx.ok():
                self.ex.spin_once(timeout_sec=0.05)
        except Exception:  # noqa: BLE001 - context shut down
            pass

    def reset(self):
        with self.lock:
            self.diags.clear()
            self.outputs.clear()

    def close(self):
        import rclpy
        self.ex.shutdown(timeout_sec=1.0)
        self.node.destroy_node()
        rclpy.try_shutdown(context=self.ctx)
        self.thread.join(2.0)


def start_busy(n: int) -> list[subprocess.Popen]:
    """``n`` CPU-bound processes (a loaded machine); stop them with :func:`stop_busy`."""
    return [subprocess.Popen([sys.executable, "-c", "while True: pass"], start_new_session=True)
            for _ in range(n)]


def stop_busy(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        if p.poll() is None:
            p.kill()
            p.wait(10)


def start_publisher(tmp: Path, rate: float, seconds: float, rpm: float, bar: float, settle: float,
                    name: str, domain: int | None = None) -> tuple[subprocess.Popen, Path, Path]:
    """The bench publisher process; returns (process, its stdout file, its JSON result file)."""
    out, res = tmp / f"{name}.out", tmp / f"{name}.json"
    args = [sys.executable, "-m", "gerotor_twin.ros.bench_publisher", "--rate", str(rate), "--seconds",
            str(seconds), "--rpm", str(rpm), "--bar", str(bar), "--settle", str(settle), "--out", str(res)]
    env = dict(os.environ, ROS_DOMAIN_ID=str(_domain() if domain is None else domain), PYTHONUNBUFFERED="1")
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    proc = subprocess.Popen(args, stdout=open(out, "w"), stderr=subprocess.STDOUT, env=env, start_new_session=True)
    return proc, out, res


def wait_line(proc: subprocess.Popen, path: Path, text: str, timeout: float) -> None:
    t0 = time.monotonic()
    while text not in path.read_text():
        if proc.poll() is not None or time.monotonic() - t0 > timeout:
            raise RuntimeError(f"bench publisher: no {text!r} ({path.read_text()[-1000:]})")
        time.sleep(0.01)


def input_accounting(files: list[Path], stamps: set[int]) -> dict:
    """Read the node's MCAP file(s): inputs logged (by header stamp) and the node's accounting record."""
    from gerotor_twin.io.reader import open_mcap
    from gerotor_twin.io.decode import decode
    from gerotor_twin.twin.sequence import ACCOUNTING_METADATA
    logged, acct = 0, {}
    for f in files:
        mf = open_mcap(f)
        types = mf.topic_types()
        for ch, msg in mf.iter_raw(["/bench/shaft_speed", "/bench/delivery_pressure"]):
            st = decode(types[ch.topic], msg.data).header.stamp
            logged += (st.sec * 1_000_000_000 + st.nanosec) in stamps
        for k, v in mf.metadata.get(ACCOUNTING_METADATA, {}).items():
            if k.split(".", 1)[-1] in ("lost", "missed_at_start", "log_dropped", "received"):
                acct[k] = acct.get(k, 0) + int(v)
    lost = sum(v for k, v in acct.items() if k.endswith((".lost", ".missed_at_start", ".log_dropped")))
    return {"logged": logged, "lost": lost, "record": acct}


def latency_ms(inputs_ns: list[int], outputs: list[tuple[int, int]]) -> tuple[float, float, int]:
    """p50, p99 [ms] of (receive time of the first output stamped >= t) - t, and inputs without one."""
    import bisect
    outs = sorted(outputs)
    stamps = [o[0] for o in outs]
    lat, none = [], 0
    for t in inputs_ns:
        i = bisect.bisect_left(stamps, t)
        if i == len(stamps):
            none += 1
            continue
        lat.append((min(r for _, r in outs[i:i + 50]) - t) / 1e6)
    if not lat:
        return float("nan"), float("nan"), none
    lat.sort()
    return lat[len(lat) // 2], lat[min(len(lat) - 1, int(0.99 * len(lat)))], none


def _one_speed(tmp: Path, model: str, params: tuple, peer: _Peer, rpm: float, bar: float, rate: float,
               seconds: float, settle: float, repeat: int = 0) -> dict:
    run_dir = tmp / f"rpm{rpm:g}" / f"run{repeat}"
    run_dir.mkdir(parents=True)
    proc, _, _ = _start(run_dir, model, "node.log", params)
    pub = None
    try:
        peer.reset()
        pub, pub_out, pub_res = start_publisher(run_dir, rate, settle + seconds, rpm, bar, 1.0, "pub")
        wait_line(pub, pub_out, "publishing", 90)
        time.sleep(settle)
        c0, t0, w0, th0 = _cpu_s(proc.pid), time.monotonic(), time.time_ns(), _thread_cpu_s(proc.pid)
        with peer.lock:
            n0 = len(peer.diags)
        wait_line(pub, pub_out, "published", seconds + 60)
        c1, t1, w1, th1 = _cpu_s(proc.pid), time.monotonic(), time.time_ns(), _thread_cpu_s(proc.pid)
        pub.wait(60)                                  # lingers 1 s: last diagnostics, outputs after the last input
        with peer.lock:
            window = [v for (tt, v) in peer.diags[n0:] if tt <= t1 + 1.05]
            outputs = list(peer.outputs)
            startup = next((v for (_, v) in peer.diags if "startup_rtf" in v), {})
    finally:
        if pub is not None and pub.poll() is None:
            pub.kill()
            pub.wait(10)
        _stop(proc)
    res = json.loads(pub_res.read_text())
    stamps = res["stamps"]
    acc = input_accounting(sorted(run_dir.glob("*.mcap")), set(stamps))
    published = sum(res["published"].values())
    p50, p99, _ = latency_ms([t for t in stamps if w0 <= t <= w1 - 600_000_000], outputs)
    sim = rtfs = None
    if len(window) >= 2:
        sim = float(window[-1]["simulated_s"]) - float(window[0]["simulated_s"])
        rtfs = sorted(float(v["real_time_factor"]) for v in window[1:] if v["real_time_factor"] != "n/a")
    cpu = c1 - c0
    return {"rpm": rpm, "repeat": repeat, "node_cpu_fraction": cpu / (t1 - t0),
            "startup_rtf": float(startup.get("startup_rtf", "nan")),
            "startup_rtf_point": (f"{float(startup['startup_rtf_speed_rpm']):g} rpm / "
                                  f"{float(startup['startup_rtf_delivery_bar']):g} bar" if startup else "n/a"),
            "core_rtf": rtfs[len(rtfs) // 2] if rtfs else float("nan"),
            "node_rtf": sim / cpu if sim is not None and cpu > 0 else float("nan"),
            "latency_p50_ms": p50, "latency_p99_ms": p99, "skips": int(window[-1]["skips"]) if window else None,
            "published": published, "logged": acc["logged"], "lost": acc["lost"],
            "unaccounted": published - acc["logged"] - acc["lost"], "publisher_late": res["late"],
            "accounting": acc["record"],
            "thread_cpu_fraction": {k: (th1[k] - th0[k]) / (t1 - t0) for k in th0}}


_MEDIANS = ("node_cpu_fraction", "startup_rtf", "core_rtf", "node_rtf", "latency_p50_ms", "latency_p99_ms")
_SUMS = ("skips", "published", "logged", "lost", "unaccounted")


def median_row(rows: list[dict]) -> dict:
    """Medians of the rates and latencies, sums of the counts, of one speed's repeated runs."""
    import statistics
    med = {"rpm": rows[0]["rpm"], "repeat": "median", "runs": len(rows)}
    for k in _MEDIANS:
        med[k] = statistics.median(r[k] for r in rows)
    for k in _SUMS:
        med[k] = sum(r[k] or 0 for r in rows)
    med["thread_cpu_fraction"] = {k: statistics.median(r["thread_cpu_fraction"][k] for r in rows)
                                  for k in rows[0]["thread_cpu_fraction"]}
    return med


def _line(r: dict) -> str:
    label = f"{r['rpm']:5g}" if r["repeat"] != "median" else "  med"
    return (f"  {label} {100 * r['node_cpu_fraction']:8.0f}% {r['startup_rtf']:9.2f} {r['core_rtf']:9.2f} "
            f"{r['node_rtf']:9.2f} "
            f"{r['latency_p50_ms']:6.1f}ms {r['latency_p99_ms']:6.1f}ms {r['skips'] or 0:5d} {r['published']:10d} "
            f"{r['logged']:8d} {r['lost']:6d} {r['unaccounted']:7d}   "
            + " ".join(f"{k} {100 * v:.0f}%" for k, v in r["thread_cpu_fraction"].items()))


def run(model: str = "mobility", rpms=(1000, 2000, 3000), seconds: float = 4.0, bar: float = 27.5,
        rate: float = 1000.0, busy: int = 0, params: tuple = (), settle: float = 1.5, out=print,
        repeats: int = 1) -> dict:
    """Measure and print; returns the figures as a dict (``rows``: every run; ``medians``: per speed)."""
    result: dict = {"model": model, "rate_hz": rate, "busy": busy, "params": list(params),
                    "executor": os.environ.get("GEROTOR_TWIN_EXECUTOR", "waitset"),
                    "model_thread": os.environ.get("GEROTOR_TWIN_MODEL_THREAD", "1") != "0",
                    "repeats": repeats, "startup_s": [], "rows": [], "medians": [],
                    "load_average_1min": [os.getloadavg()[0]]}
    with tempfile.TemporaryDirectory() as td:
        tmp = Path(td)
        for k in range(2):
            proc, t, _ = _start(tmp, model, f"start{k}.log", params)
            _stop(proc)
            result["startup_s"].append(t)
        out(f"twin_node startup (Popen -> ready): first {result['startup_s'][0]:.2f} s, "
            f"warm {result['startup_s'][1]:.2f} s")
        busy_procs = start_busy(busy)
        peer = _Peer()
        try:
            pump = next((q.split(":=", 1)[1] for q in params if q.startswith("pump_config:=")),
                        "config/pump.yaml")
            out(f"twin_node ({model}, pump {pump}, {bar:g} bar, inputs at {rate:g} Hz from a separate process, {seconds:g} s "
                f"per speed, {busy} busy process(es), executor {result['executor']}, "
                f"model thread {'on' if result['model_thread'] else 'off'})")
            out(f"  {'rpm':>5s} {'node CPU':>9s} {'start RTF':>9s} {'core RTF':>9s} {'node RTF':>9s} "
                f"{'lat p50':>8s} {'lat p99':>8s} "
                f"{'skips':>5s} {'published':>10s} {'logged':>8s} {'lost':>6s} {'unacc.':>7s}")
            for rpm in rpms:
                runs = []
                for k in range(repeats):
                    runs.append(_one_speed(tmp, model, params, peer, rpm, bar, rate, seconds, settle, k))
                    out(_line(runs[-1]))
                result["rows"].extend(runs)
                if repeats > 1:
                    result["medians"].append(median_row(runs))
                    out(_line(result["medians"][-1]))
        finally:
            peer.close()
            stop_busy(busy_procs)
    if result["rows"]:
        out(f"start RTF: the node's start-up real-time check (model alone, worst point "
            f"{result['rows'][-1]['startup_rtf_point']}, startup_rtf on /diagnostics)")
    result["load_average_1min"].append(os.getloadavg()[0])
    out(f"machine load (1-min average) {result['load_average_1min'][0]:.2f} at the start, "
        f"{result['load_average_1min'][1]:.2f} at the end: the node's CPU on a shared or idling machine moves by "
        "several points between starts (docs/performance.md); compare medians of --node-repeats")
    return result


def plan(args) -> dict:
    """Speeds, delivery pressure and node parameters of a ``bench node`` run, from its arguments.

    ``--config F``: the node runs that pump (``pump_config``); the speeds default
    to its top speed (``range.max_speed_rpm``), the pressure to its highest
    (``range.max_delivery_bar``); each given value must lie in that range.

    Returns
    -------
    dict
        ``rpms`` [rpm], ``bar`` [bar gauge], ``params`` (``name:=value`` strings), ``config`` (path or None).
    """
    from gerotor_twin.config import load_config
    from gerotor_twin.errors import InputError
    cfg = load_config(args.config)
    rng = cfg.range
    try:
        rpms = (tuple(int(float(r)) for r in str(args.node_rpms).split(",")) if args.node_rpms
                else (int(round(rng.max_speed_rpm)),))
    except ValueError:
        raise InputError("--node-rpms", args.node_rpms, "comma-separated speeds [rpm]") from None
    if not all(0 <= r <= rng.max_speed_rpm for r in rpms):
        raise InputError("--node-rpms", args.node_rpms,
                         f"speeds in [0, {rng.max_speed_rpm:g}] rpm (the pump's range)")
    try:
        bar = float(str(args.bar).split(",")[0]) if args.bar else rng.max_delivery_bar
    except ValueError:
        raise InputError("--bar", args.bar, "a delivery pressure [bar gauge]") from None
    if not 0.0 <= bar <= rng.max_delivery_bar:
        raise InputError("--bar", args.bar, f"[0, {rng.max_delivery_bar:g}] bar gauge (the pump's range)")
    params = tuple(args.node_param or ())
    config = str(Path(args.config).resolve()) if args.config else None
    if config:
        params = (f"pump_config:={config}",) + params
    return {"rpms": rpms, "bar": bar, "params": params, "config": config}


def cmd_bench_node(args) -> int:
    """Handler of ``gerotor-twin bench node``."""
    from gerotor_twin.errors import InputError
    p = plan(args)
    if not 1.0 <= args.node_rate <= 20000.0:
        raise InputError("--node-rate", args.node_rate, "[1, 20000] Hz")
    if not 0 <= args.node_busy <= 64:
        raise InputError("--node-busy", args.node_busy, "0 to 64 processes")
    if not 1 <= args.node_repeats <= 100:
        raise InputError("--node-repeats", args.node_repeats, "1 to 100 runs per speed")
    res = run(model=args.node_model, rpms=p["rpms"], seconds=args.node_seconds, bar=p["bar"], rate=args.node_rate,
              busy=args.node_busy, params=p["params"], repeats=args.node_repeats)
    if args.json:
        Path(args.json).write_text(json.dumps({"node": res}, indent=2))
        print(f"wrote {args.json}")
    return 0
