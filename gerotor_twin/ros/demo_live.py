"""``make demo``: the nominal twin live beside a replayed bench, the twin calibrated on the map recording beside it.

Steps (separate processes; the node and the replay talk real DDS on loopback, private ``ROS_DOMAIN_ID``):

1. in the background, at low priority, while steps 2-4 run: ``gerotor-twin calibrate``
   on ``bags/bench_map.mcap`` (-> ``out/demo/pump_fitted.yaml``; ``--calibrated F``
   uses a pump file instead), then ``gerotor-twin run-bag --config`` that pump file
   over ``bags/bench_transient.mcap`` (offline, the node's core: the same predictions
   the node would make);
2. start ``twin_node`` (``python -m gerotor_twin.ros.node``) with
   ``config/twin.yaml`` (the packaged nominal pump), ``use_sim_time:=true`` and
   ``log_dir`` under the output directory, and wait for its "ready" line;
3. ``gerotor-twin replay bags/bench_transient.mcap`` in real time (rate 1,
   ``/clock`` at 50 Hz) into it;
4. stop the node with SIGINT (it finalises its MCAP log);
5. ``gerotor-twin report`` on the bench recording and both twin logs;
6. print where the report and the logs are, both twins' predictions per
   plateau and both verdict sets side by side.

The live node runs the nominal pump, what a node started without a pump file runs; the
calibrated twin, the one the demo's story ends on, runs offline, so its verdicts do not
depend on how busy the machine is, and in the replay's real-time window, so it adds no
wall time. Both undo the emulated bench thermometer's 3 s lag (``oil_sensor_tau_s``), as
the calibration does, so the pump file is their only difference.

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

from gerotor_twin.resources import share_dir
from gerotor_twin.yaml_safe import load_yaml_file
from gerotor_twin.units import m3s_to_lpm

#: The package's data (bags, config): the source tree in a checkout, share/gerotor_twin when installed.
ROOT = share_dir()

__all__ = ["main", "build_parser", "plateau_lines", "calibration_note", "labels"]


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


MAP = ROOT / "bags" / "bench_map.mcap"
#: The emulated bench thermometer's lag [s] (bags/README.md), undone by the calibration and by both twins here.
OIL_SENSOR_TAU_S = 3.0


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="python -m gerotor_twin.ros.demo_live", description=__doc__.splitlines()[0])
    ap.add_argument("--bag", default=str(ROOT / "bags" / "bench_transient.mcap"),
                    help="bench recording to replay (default: the packaged bags/bench_transient.mcap)")
    ap.add_argument("--out", default="out/demo", help="output directory (default: %(default)s)")
    ap.add_argument("--model", default="mobility")
    ap.add_argument("--rate", type=float, default=1.0)
    ap.add_argument("--map", default=str(MAP), metavar="BAG",
                    help="recording the calibration fits the clearances on (default bags/bench_map.mcap)")
    ap.add_argument("--calibrated", metavar="PUMP.yaml",
                    help="use this pump file for the calibrated twin instead of calibrating on --map (e.g. "
                         "bags/pump_fitted_bench_map.yaml, the shipped fit of bags/bench_map.mcap)")
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
    print(f"demo: nominal twin: node ({args.model}, config/pump.yaml, use_sim_time) + replay of {_shown(args.bag)} "
          f"in real time (ROS_DOMAIN_ID={args.domain_id})", flush=True)
    node = subprocess.Popen(
        [sys.executable, "-m", "gerotor_twin.ros.node", "--ros-args", "--params-file", str(ROOT / "config" / "twin.yaml"),
         "-p", "use_sim_time:=true", "-p", f"log_dir:={log_dir}", "-p", f"bearing_model:={args.model}",
         "-p", f"oil_sensor_tau_s:={float(args.oil_sensor_tau)}",
         # a short showcase: log every output (the defaults decimate them for hours-long runs)
         "-p", "log_outputs_every:=1", "-p", "log_waveform_every:=1", "-p", "log_diagnostics_every:=1"],
        env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
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
                             env=env)
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
    """What a pump file's ``calibration`` block says, in one line: bags, plateaus, the fitted clearance
    factor(s) with their parameter intervals, the volumetric-efficiency RMSE before and after the fit, the
    prediction interval of η_v and a refused calibration; or that it has no such block."""
    cal = (load_yaml_file(pump_yaml) or {}).get("calibration")
    if not isinstance(cal, dict):
        return f"{pump_yaml}: no calibration block"
    parts = [f"{c['combination']} x {c['factor']:.4f} (parameter 95 % CI {c['factor_ci95'][0]:.4f}-"
             f"{c['factor_ci95'][1]:.4f})" for c in cal.get("fitted_combinations", [])]
    res = cal.get("residuals", {})
    if "eta_rmse" in res and "eta_rmse_prior" in res:
        parts.append(f"eta_v RMSE {100 * res['eta_rmse_prior']:.2f} -> {100 * res['eta_rmse']:.2f} %-pt")
    pi = cal.get("prediction_interval")
    if isinstance(pi, dict) and "eta_half_width_twin" in pi:
        parts.append(f"eta_v predicted +- {100 * pi['eta_half_width_twin']:.2f} %-pt (95 %, model form included)")
    if isinstance(cal.get("verdict"), dict) and cal["verdict"].get("calibrated") is False:
        parts.append("calibration refused: the nominal values kept")
    return (f"{', '.join(cal.get('bags', []))}, {cal.get('plateaus', '?')} plateaus"
            + (": " + "; ".join(parts) if parts else ""))


def _shown(path) -> str:
    """``path`` relative to the package root when inside it (the background commands run there), else absolute."""
    p = Path(path).resolve()
    return str(p.relative_to(ROOT)) if p.is_relative_to(ROOT) else str(p)


def _lower_priority(pid: int, niceness: int = 10) -> None:
    """Nice a started process to ``niceness`` (or leave it at this process's, if higher). Set after the start:
    ``preexec_fn`` is unsafe in a process with threads."""
    try:
        os.setpriority(os.PRIO_PROCESS, pid, max(niceness, os.getpriority(os.PRIO_PROCESS, 0)))
    except ProcessLookupError:          # already finished
        pass


class Background(threading.Thread):
    """Commands run one after the other in a thread, each a process at low priority (``nice 10``), while the
    replay runs; stops at the first that fails (``failed``: its name) or at :meth:`cancel`."""

    def __init__(self, steps: list[tuple[str, list[str], Path]]):
        super().__init__(daemon=True)
        self.steps = steps                  #: (name, argv, log file)
        self.failed: str | None = None
        self._proc: subprocess.Popen | None = None
        self._cancelled = threading.Event()

    def run(self) -> None:
        for name, argv, log in self.steps:
            if self._cancelled.is_set():
                self.failed = name
                return
            with open(log, "w") as f:
                self._proc = subprocess.Popen(argv, cwd=ROOT, stdout=f, stderr=subprocess.STDOUT)
            _lower_priority(self._proc.pid)
            if self._cancelled.is_set():
                self._proc.terminate()
            if self._proc.wait() != 0:
                self.failed = name
                return

    def cancel(self) -> None:
        self._cancelled.set()
        if self._proc is not None and self._proc.poll() is None:
            self._proc.terminate()
        self.join()


def _calibrated_steps(args, out: Path) -> tuple[list[tuple[str, list[str], Path]], Path, Path]:
    """The calibrated twin's commands: ``calibrate`` on the map recording (unless ``--calibrated`` names a pump
    file), then ``run-bag --config`` over the demo's recording; and the pump file and twin log they write."""
    config = Path(args.calibrated) if args.calibrated else out / "pump_fitted.yaml"
    twin_log = out / "calibrated_twin.mcap"
    tau, bag, config_arg = str(args.oil_sensor_tau), _shown(args.bag), _shown(config)
    steps = [] if args.calibrated else [("calibrate", ["calibrate", "--bench", _shown(args.map), "-o", config_arg,
                                                       "--oil-sensor-tau", tau, "--overwrite"])]
    steps.append(("run-bag", ["run-bag", bag, "-o", _shown(twin_log), "--config", config_arg, "--model",
                              args.model, "--oil-sensor-tau", tau, "--overwrite", "--quiet"]))
    for name, cmd in steps:
        print(f"demo: calibrated twin: gerotor-twin {' '.join(cmd)}   (in the background)", flush=True)
    return ([(name, [sys.executable, "-m", "gerotor_twin", *cmd], out / f"{name}.log") for name, cmd in steps],
            config, twin_log)


def _calibrated_result(bg: Background, config: Path, out: Path) -> bool:
    """Wait for the background commands; print what the calibration found and the run-bag line (or the failure)."""
    bg.join()
    if bg.failed:
        text = (out / f"{bg.failed}.log").read_text().strip().splitlines()
        print(f"demo: {bg.failed} failed:\n" + "\n".join(text[-10:]), file=sys.stderr)
        return False
    print(f"demo: calibrated twin: {config}: {calibration_note(config)}")
    print(f"demo: calibrated twin: {(out / 'run-bag.log').read_text().strip().splitlines()[-1]}", flush=True)
    return True


def labels(args) -> list[str]:
    """Report labels of the two twins: ``nominal`` and ``calibrated from <recording or pump file>``."""
    return ["nominal", f"calibrated from {Path(args.calibrated or args.map).stem}"]


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


def _report(args, logs: list[Path], out: Path) -> dict | None:
    from gerotor_twin.io import McapReadError
    from gerotor_twin.report.build import build_report
    try:
        return build_report(args.bag, logs, out / "report.html", out / "metrics.json", labels=labels(args))
    except McapReadError as exc:
        print(f"demo: report failed: {exc}", file=sys.stderr)
        return None


def main(argv=None) -> int:
    args = build_parser().parse_args(argv)
    out = Path(args.out).resolve()
    log_dir = out / "log"
    try:
        log_dir.mkdir(parents=True, exist_ok=True)
    except OSError as exc:                 # --out under a file, not writable: one line, as the CLI says it
        from gerotor_twin.errors import path_error_line
        print(path_error_line(exc), file=sys.stderr)
        return 2
    if args.domain_id is None:
        from gerotor_twin.ros.domain import claim_domain
        env_id = os.environ.get("GEROTOR_TWIN_DEMO_DOMAIN")
        args.domain_id = int(env_id) if env_id else claim_domain()
    print("demo: model kernels (compiled by make setup; on a cold cache once now, under a minute) ...", flush=True)
    print(f"demo: model kernels ready in {_compile_kernels(args.model):.1f} s", flush=True)
    t0 = time.monotonic()
    steps, config, cal_log = _calibrated_steps(args, out)
    bg = Background(steps)
    bg.start()
    try:
        twin_log = _live_twin(args, log_dir)
    except BaseException:           # Ctrl-C included: no calibration left running
        bg.cancel()
        raise
    if twin_log is None:
        bg.cancel()
        return 1
    if not _calibrated_result(bg, config, out):
        return 1
    res = _report(args, [twin_log, cal_log], out)
    if res is None:
        return 1
    print(f"demo: node log     {twin_log} ({twin_log.stat().st_size / 1e6:.2f} MB)")
    print(f"demo: run-bag log  {cal_log} ({cal_log.stat().st_size / 1e6:.2f} MB)")
    print(f"demo: report       {out / 'report.html'}")
    print(f"demo: metrics      {out / 'metrics.json'}")
    for line in plateau_lines(res) + [f"demo: {h}" for h in res["headline"]]:
        print(line)
    print(f"demo: done in {time.monotonic() - t0:.0f} s", flush=True)
    return 0


if __name__ == "__main__":
    from gerotor_twin.errors import one_line_warnings
    with one_line_warnings():              # a truncated log is one `warning:` line, as in the CLI
        code = main()
    sys.exit(code)
