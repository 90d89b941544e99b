"""``make demo``: the twin node, fed by a replayed bench recording, then the report.

Steps (each a separate process, real DDS on loopback, private ``ROS_DOMAIN_ID``):

1. start ``twin_node`` (``python -m gerotor_twin.ros.node``) with
   ``config/twin.yaml``, ``use_sim_time:=true`` and ``log_dir`` under the
   output directory, and wait for its "ready" line;
2. ``gerotor-twin replay bags/bench_transient.mcap`` in real time (rate 1,
   ``/clock`` at 50 Hz) into it;
3. stop the node with SIGINT (it finalises its MCAP log);
4. ``gerotor-twin report`` on the bench recording and the node's log;
5. print where the report and the log are, and the headline metrics.

This module starts processes only; it does not import rclpy itself.
"""
from __future__ import annotations

import argparse
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

from gerotor_twin.resources import resource_path
from gerotor_twin.units import m3s_to_lpm

__all__ = ["main"]


def _pump(stream, sink: list, ready: threading.Event, echo: bool) -> None:
    for line in iter(stream.readline, ""):
        sink.append(line)
        if "ready in" in line:
            ready.set()
        if echo:
            sys.stderr.write("  [node] " + line)


def _compile_kernels(model: str) -> float:
    """Compile the model kernels here (or load them from numba's disk cache) so the node starts in seconds;
    returns the time it took [s]. The first run after an install or a source change compiles for
    about 1–2 min on the dev machine; later runs load the cache in a second."""
    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import Inputs, PumpModel
    from gerotor_twin.units import bar_gauge_to_pa_abs, rpm_to_rad_s
    t0 = time.monotonic()
    cfg = load_config()
    m = PumpModel(cfg, model)
    inp = Inputs(rpm_to_rad_s(1500.0), cfg.boundary.suction_pressure_pa,
                 bar_gauge_to_pa_abs(20.0, cfg.fluid.atmospheric_pa))
    m.advance(m.initial_state(inp), 0.002, inp)
    return time.monotonic() - t0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m gerotor_twin.ros.demo_live", description=__doc__.splitlines()[0])
    ap.add_argument("--bag", default=str(resource_path("bags", "bench_transient.mcap")),
                    help="bench recording to replay (default: the packaged bags/bench_transient.mcap)")
    ap.add_argument("--out", default="out/demo", help="output directory (default: %(default)s)")
    ap.add_argument("--model", default="mobility")
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--domain-id", type=int, default=None,
                    help="ROS_DOMAIN_ID (default: a free one in 0-101, or $GEROTOR_TWIN_DEMO_DOMAIN)")
    ap.add_argument("--verbose", action="store_true", help="echo the node's log lines")
    args = ap.parse_args(argv)
    if args.domain_id is None:
        from gerotor_twin.ros.domain import claim_domain
        env_id = os.environ.get("GEROTOR_TWIN_DEMO_DOMAIN")
        args.domain_id = int(env_id) if env_id else claim_domain()
    out = Path(args.out).resolve()
    log_dir = out / "log"
    log_dir.mkdir(parents=True, exist_ok=True)
    before = set(log_dir.glob("*.mcap"))
    env = dict(os.environ, ROS_DOMAIN_ID=str(args.domain_id))
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    print("demo: model kernels (compiled once after an install, about 1-2 min; cached after) ...", flush=True)
    print(f"demo: model kernels ready in {_compile_kernels(args.model):.1f} s", flush=True)
    t0 = time.monotonic()
    print(f"demo: twin node ({args.model}, use_sim_time) + replay of {args.bag} in real time "
          f"(ROS_DOMAIN_ID={args.domain_id})", flush=True)
    node = subprocess.Popen(
        [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file", str(resource_path("config", "twin.yaml")),
         "-p", "use_sim_time:=true", "-p", f"log_dir:={log_dir}", "-p", f"bearing_model:={args.model}",
         # a short showcase: log every output (the defaults decimate them for hours-long runs)
         "-p", "log_outputs_every:=1", "-p", "log_waveform_every:=1", "-p", "log_diagnostics_every:=1"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    ready = threading.Event()
    threading.Thread(target=_pump, args=(node.stdout, lines, ready, args.verbose), daemon=True).start()
    try:
        if not ready.wait(300) or node.poll() is not None:
            print("demo: the node did not become ready:\n" + "".join(lines[-20:]), file=sys.stderr)
            return 1
        startup = next((ln.strip() for ln in lines if "ready in" in ln), "")
        print(f"demo: node {startup[startup.find('ready in'):]}", flush=True)
        rep = subprocess.run([sys.executable, "-m", "gerotor_twin", "replay", args.bag, "--rate", str(args.rate),
                              "--clock-rate", "50", "--delay", "0.5", "--wait-subscribers", "1"],
                             env=env)
        if rep.returncode != 0:
            print("demo: replay failed", file=sys.stderr)
            return 1
        time.sleep(1.0)
    finally:
        if node.poll() is None:
            node.send_signal(signal.SIGINT)
            try:
                node.wait(timeout=60)
            except subprocess.TimeoutExpired:
                node.kill()
                node.wait()
    logs = sorted(set(log_dir.glob("*.mcap")) - before, key=lambda p: p.stat().st_mtime)
    if not logs:
        print("demo: the node wrote no MCAP log:\n" + "".join(lines[-20:]), file=sys.stderr)
        return 1
    twin_log = logs[-1]
    from gerotor_twin.io import McapReadError
    from gerotor_twin.report.build import build_report
    html, js = out / "report.html", out / "metrics.json"
    try:
        res = build_report(args.bag, [twin_log], html, js)
    except McapReadError as exc:
        print(f"demo: report failed: {exc}", file=sys.stderr)
        return 1
    print(f"demo: node log     {twin_log} ({twin_log.stat().st_size / 1e6:.2f} MB)")
    print(f"demo: report       {html}")
    print(f"demo: metrics      {js}")
    for p, row in zip(res["plateaus"], res["twins"][0]["plateaus"]):
        fm, fp = row["flow_measured_m3s"], row["flow_predicted_m3s"]
        em, ep = row["eta_measured"], row["eta_predicted"]
        print(f"  plateau {p['index']}: {row['rpm']:6.0f} rpm {row['bar']:5.1f} bar  flow meas {m3s_to_lpm(fm):6.2f} "
              f"pred {'–' if fp is None else f'{m3s_to_lpm(fp):6.2f}'} L/min  eta_v meas {100 * em:5.2f} % "
              f"pred {'–' if ep is None else f'{100 * ep:5.2f}'} %")
    for h in res["headline"]:
        print(f"demo: {h}")
    print(f"demo: done in {time.monotonic() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    from gerotor_twin.errors import one_line_warnings
    with one_line_warnings():              # a truncated log is one `warning:` line, as in the CLI
        code = main()
    sys.exit(code)
