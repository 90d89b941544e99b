"""``make demo``: the nominal twin live beside a replayed bench, the calibrated twin beside it, one report.

Steps (the node and the replay are separate processes, real DDS on loopback, private ``ROS_DOMAIN_ID``):

1. start ``twin_node`` (``python -m gerotor_twin.ros.node``) with
   ``config/twin.yaml`` (the packaged nominal pump), ``use_sim_time:=true`` and
   ``log_dir`` under the output directory, and wait for its "ready" line;
2. ``gerotor-twin replay bags/bench_transient.mcap`` in real time (rate 1,
   ``/clock`` at 50 Hz) into it;
3. stop the node with SIGINT (it finalises its MCAP log);
4. the twin with the pump calibrated on the map recording
   (``bags/pump_fitted_bench_map.yaml``) over the same recording, offline
   (:func:`gerotor_twin.offline.run_bag.run_bag`, what ``gerotor-twin run-bag
   --config`` does: the same core, the same predictions as the node);
5. ``gerotor-twin report`` on the bench recording and both twin logs;
6. print where the report and the logs are, both twins' predictions per
   plateau and both verdict sets side by side.

The live node runs the nominal pump, what a node started without a pump file runs; the
calibrated twin, the one the demo's story ends on, runs offline, so its verdicts do not
depend on how busy the machine is. Both undo the emulated bench thermometer's 3 s lag
(``oil_sensor_tau_s``), as the calibration did, so the pump file is their only difference.

This module starts processes only; it does not import rclpy itself.
"""
from __future__ import annotations

import argparse
import math
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import yaml

from gerotor_twin.units import m3s_to_lpm

ROOT = Path(__file__).resolve().parent.parent.parent

__all__ = ["main", "plateau_lines", "calibration_note"]


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


FITTED = ROOT / "bags" / "pump_fitted_bench_map.yaml"
#: The emulated bench thermometer's lag [s] (bags/README.md), undone by the calibration and by both twins here.
OIL_SENSOR_TAU_S = 3.0
LABELS = ("nominal", "calibrated from bench_map")


def _parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gerotor_twin.ros.demo_live", description=__doc__.splitlines()[0])
    ap.add_argument("--bag", default=str(ROOT / "bags" / "bench_transient.mcap"))
    ap.add_argument("--out", default=str(ROOT / "out" / "demo"))
    ap.add_argument("--model", default="mobility")
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--calibrated", default=str(FITTED), metavar="PUMP.yaml",
                    help="pump file of the calibrated twin (default: the one fitted on bags/bench_map.mcap)")
    ap.add_argument("--oil-sensor-tau", type=float, default=OIL_SENSOR_TAU_S, metavar="S",
                    help=f"oil thermometer lag undone by both twins [s] (default {OIL_SENSOR_TAU_S:g})")
    ap.add_argument("--domain-id", type=int, default=None,
                    help="ROS_DOMAIN_ID (default: a free one in 0-101, or $GEROTOR_TWIN_DEMO_DOMAIN)")
    ap.add_argument("--verbose", action="store_true", help="echo the node's log lines")
    return ap


def _stop(node: subprocess.Popen) -> None:
    if node.poll() is None:
        node.send_signal(signal.SIGINT)
        try:
            node.wait(timeout=60)
        except subprocess.TimeoutExpired:
            node.kill()
            node.wait()


def _live_twin(args, log_dir: Path) -> Path | None:
    """The node (nominal pump) fed by the real-time replay; its new MCAP log, or None (the reason printed)."""
    before = set(log_dir.glob("*.mcap"))
    env = dict(os.environ, ROS_DOMAIN_ID=str(args.domain_id))
    env.setdefault("AMENT_PREFIX_PATH", sys.prefix)
    print(f"demo: nominal twin: node ({args.model}, config/pump.yaml, use_sim_time) + replay of {args.bag} "
          f"in real time (ROS_DOMAIN_ID={args.domain_id})", flush=True)
    node = subprocess.Popen(
        [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file", str(ROOT / "config" / "twin.yaml"),
         "-p", "use_sim_time:=true", "-p", f"log_dir:={log_dir}", "-p", f"bearing_model:={args.model}",
         "-p", f"oil_sensor_tau_s:={float(args.oil_sensor_tau)}",
         # a short showcase: log every output (the defaults decimate them for hours-long runs)
         "-p", "log_outputs_every:=1", "-p", "log_waveform_every:=1", "-p", "log_diagnostics_every:=1"],
        cwd=ROOT, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    lines: list[str] = []
    ready = threading.Event()
    threading.Thread(target=_pump, args=(node.stdout, lines, ready, args.verbose), daemon=True).start()
    try:
        if not ready.wait(300) or node.poll() is not None:
            print("demo: the node did not become ready:\n" + "".join(lines[-20:]), file=sys.stderr)
            return None
        startup = next((ln.strip() for ln in lines if "ready in" in ln), "")
        print(f"demo: node {startup[startup.find('ready in'):]}", flush=True)
        rep = subprocess.run([sys.executable, "-m", "gerotor_twin", "replay", args.bag, "--rate", str(args.rate),
                              "--clock-rate", "50", "--delay", "0.5", "--wait-subscribers", "1"],
                             cwd=ROOT, env=env)
        if rep.returncode != 0:
            print("demo: replay failed", file=sys.stderr)
            return None
        time.sleep(1.0)
    finally:
        _stop(node)
    logs = sorted(set(log_dir.glob("*.mcap")) - before, key=lambda p: p.stat().st_mtime)
    if not logs:
        print("demo: the node wrote no MCAP log:\n" + "".join(lines[-20:]), file=sys.stderr)
        return None
    return logs[-1]


def calibration_note(pump_yaml) -> str:
    """Where a pump file's values come from, in one line: its ``calibration`` block (tool, bags, date, fitted
    factor), or that it has none."""
    cal = (yaml.safe_load(Path(pump_yaml).read_text()) or {}).get("calibration")
    if not isinstance(cal, dict):
        return f"{pump_yaml}: no calibration block"
    factors = ", ".join(f"{c['combination']} x {c['factor']:.4f}" for c in cal.get("fitted_combinations", []))
    return (f"{pump_yaml}: fitted by `{cal.get('tool', '?')}` on {', '.join(cal.get('bags', []))} "
            f"({cal.get('date', '?')[:10]}, {cal.get('plateaus', '?')} plateaus" + (f"; {factors}" if factors else "")
            + ")")


def _calibrated_twin(args, out: Path) -> Path:
    """The calibrated pump over the same recording, offline (``run-bag --config``); its MCAP log."""
    from gerotor_twin.offline.run_bag import run_bag
    from gerotor_twin.twin.settings import TwinSettings, oil_sensor_tau_arg
    log = out / "calibrated_twin.mcap"
    print(f"demo: calibrated twin: run-bag --config {args.calibrated} over the same recording (offline, no ROS)",
          flush=True)
    print(f"demo:   {calibration_note(args.calibrated)}", flush=True)
    print("demo:   regenerate it: gerotor-twin calibrate --bench bags/bench_map.mcap "
          "-o bags/pump_fitted_bench_map.yaml --oil-sensor-tau 3 --overwrite   (minutes; make demo-calibrate)",
          flush=True)
    settings = TwinSettings(max_span_s=math.inf, oil_sensor_tau_s=oil_sensor_tau_arg(args.oil_sensor_tau))
    res = run_bag(args.bag, log, model=args.model, config_path=args.calibrated, settings=settings,
                  overwrite=True, progress=None)
    print(f"demo:   {res['simulated_s']:.1f} s simulated in {res['wall_s']:.1f} s", flush=True)
    return log


def _fmt(v, scale: float, fmt: str) -> str:
    return "–" if v is None else format(v * scale, fmt)


def plateau_lines(res: dict) -> list[str]:
    """Per plateau of a :func:`~gerotor_twin.report.build.build_report` result: the measured and each twin's
    predicted flow and volumetric efficiency, and each twin's verdict, in one line (a header line first)."""
    twins = res["twins"]
    names = ", ".join(t["label"] for t in twins)
    out = [f"  plateau: speed, pressure | flow [L/min] measured, {names} | eta_v [%] measured, {names} | verdicts"]
    for k, p in enumerate(res["plateaus"]):
        rows = [t["plateaus"][k] for t in twins]
        flows = ", ".join(_fmt(r["flow_predicted_m3s"], m3s_to_lpm(1.0), "6.2f") for r in rows)
        etas = ", ".join(_fmt(r["eta_predicted"], 100.0, "5.2f") for r in rows)
        verdicts = ", ".join(vs[k]["verdict"] for vs in res["verdicts"])
        out.append(f"  plateau {p['index']}: {rows[0]['rpm']:6.0f} rpm {rows[0]['bar']:5.1f} bar | flow "
                   f"{_fmt(rows[0]['flow_measured_m3s'], m3s_to_lpm(1.0), '6.2f')}, {flows} | eta_v "
                   f"{_fmt(rows[0]['eta_measured'], 100.0, '5.2f')}, {etas} | {verdicts}")
    return out


def main(argv=None) -> int:
    args = _parser().parse_args(argv)
    if args.domain_id is None:
        from gerotor_twin.ros.domain import claim_domain
        env_id = os.environ.get("GEROTOR_TWIN_DEMO_DOMAIN")
        args.domain_id = int(env_id) if env_id else claim_domain()
    out = Path(args.out)
    log_dir = out / "log"
    log_dir.mkdir(parents=True, exist_ok=True)
    print("demo: model kernels (compiled once after an install, about 1-2 min; cached after) ...", flush=True)
    print(f"demo: model kernels ready in {_compile_kernels(args.model):.1f} s", flush=True)
    t0 = time.monotonic()
    twin_log = _live_twin(args, log_dir)
    if twin_log is None:
        return 1
    from gerotor_twin.io import McapReadError
    from gerotor_twin.report.build import build_report
    html, js = out / "report.html", out / "metrics.json"
    try:
        cal_log = _calibrated_twin(args, out)
        res = build_report(args.bag, [twin_log, cal_log], html, js, labels=list(LABELS))
    except McapReadError as exc:
        print(f"demo: report failed: {exc}", file=sys.stderr)
        return 1
    print(f"demo: node log     {twin_log} ({twin_log.stat().st_size / 1e6:.2f} MB)")
    print(f"demo: run-bag log  {cal_log} ({cal_log.stat().st_size / 1e6:.2f} MB)")
    print(f"demo: report       {html}")
    print(f"demo: metrics      {js}")
    for line in plateau_lines(res) + [f"demo: {h}" for h in res["headline"]]:
        print(line)
    print(f"demo: done in {time.monotonic() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    from gerotor_twin.errors import one_line_warnings
    with one_line_warnings():              # a truncated log is one `warning:` line, as in the CLI
        code = main()
    sys.exit(code)
