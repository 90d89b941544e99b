"""Fault classifier over emulated fault bags: per bag, per alarm and the detection delays (a measurement, not a test).

``python -m gerotor_twin.offline.diagnosis_bench [-o DIR] [--config PUMP] [--seeds 1,2] [--severity high|low|both]
[--ramp S]`` makes one short bag per fault kind, seed and severity with ``synth-bench`` (the built-in
``diagnosis`` profile scaled to the pump's range; each kind alone; emulated pump at clearance factor 1.0
against the twin of the same config, by default the packaged ``config/pump.yaml``; the fault ramps linearly
from none at the start to its severity at ``--ramp`` s, default the bag's length, 0: a step), runs the twin
over it (``run-bag``, health windows of 0.5 s after 0.5 s of settling, ``--settle``) and reports, with a line per
bag as it goes:

* the severities, solved on the pump for the flow kinds: the value at which the fault's apparent loss at the
  health monitor's reference point is :data:`TARGET_LOSS` (4 pt low, 8 pt high; :func:`severity_for`), or the
  end of the kind's allowed range with the loss it reaches there;
* per bag, the fault named at the last health update against the true kind (a confusion table);
* per alarm (``alarm_records``: each WARN / ERROR interval, named at its last update), the fraction naming
  the true kind, per kind and over all fault bags, how many of those named it already at their first update,
  and the alarms on healthy bags;
* per kind, the detection delay: from the time the fault's apparent loss of volumetric efficiency at the
  health monitor's reference point reaches 2 pt (:func:`truth_crossing`, from the bag's ``fault_series``
  truth) to the first health update at WARN / ERROR naming the true kind.

It writes ``results.json`` (every bag and the summary) in the output directory (docs/calibration_health.md,
"Fault diagnosis").

``--model-windows`` instead classifies windows made by the twin's own steady model with each fault in
full (:func:`model_records`, the behaviour tests' windows) on sets of operating points: what one speed or
one operating point can tell apart.
"""
from __future__ import annotations

import argparse
import collections
import json
import sys
import time
from pathlib import Path

import numpy as np

from ..cli import main as cli_main
from ..errors import InputError, check_range
from ..twin.diagnosis import KINDS
from ..twin.health import LEVELS, alarm_records, fault_name, fault_text
from .health_log import load_health
from .model_windows import MODEL_CASES, POINTS, model_records, model_windows_table

__all__ = ["profile_s", "LOSS_PT", "CASES", "TARGET_LOSS", "FIXED_SEVERITY", "severity_for", "severities",
           "reference_loss", "crossing_time", "truth_crossing", "health_args", "WINDOW_S", "SETTLE_S",
           "first_named_alarm", "run_case", "confusion", "alarm_summary", "alarm_table", "main", "model_records",
           "MODEL_CASES", "POINTS"]

#: loss of volumetric efficiency at the monitor's reference point from which the detection delay counts [-]
LOSS_PT = 0.02

#: apparent loss of volumetric efficiency at the monitor's reference point that a flow kind's (low, high)
#: severity reaches at the end of its ramp [-]: each pump gets the severities that make it (:func:`severity_for`)
TARGET_LOSS = (0.04, 0.08)
#: the kinds that leave the measured flow as predicted → (low, high) severity (``--fault-to``)
FIXED_SEVERITY = {"speed_dropout": (0.1, 0.3), "suction_restriction": (3e4, 6e4)}
#: the kinds of the bags, healthy first
CASES = ("healthy", "tip_wear", "lateral_wear", "air_ingress", "pressure_offset", "flowmeter_drift",
         "speed_dropout", "suction_restriction")


def profile_s(profile_file: str | None = None) -> float:
    """Length [s] of the ``diagnosis`` profile or of ``profile_file`` (the default ramp: a fault reaches its
    severity at the bag's end)."""
    from ..bench_emulator.profile_file import load_profile_file
    from ..bench_emulator.profiles import get_profile
    return (get_profile("diagnosis") if profile_file is None else load_profile_file(profile_file)).duration_s


def severity_for(cfg, kind: str, target: float = TARGET_LOSS[1], settings=None) -> tuple[float, float]:
    """The severity of ``kind`` whose apparent loss at the monitor's reference point is ``target`` [-] on the
    pump ``cfg``, and that loss [-] (:func:`reference_loss`).

    Solved by Brent's method between no fault and the end of the kind's allowed range in the direction that
    loses flow (:data:`~gerotor_twin.bench_emulator.faults.FAULT_KINDS`: a wear × 3, 10 % of free air, an
    offset of −5 bar but no lower than the reference pressure read as 0 bar gauge, a gain of −0.5); the meter
    gain g in closed form, −g·η_v = target.  Where even the end of the range loses less (a low-pressure pump's
    tip wear), that end, with the loss it reaches.  Rounded to three significant digits of its distance from no
    fault, so a table can quote it.
    """
    from scipy.optimize import brentq
    from ..bench_emulator.faults import FAULT_KINDS
    from ..twin.health import HealthSettings
    fk = FAULT_KINDS[kind]
    none = cfg.air.air_fraction if fk.none is None else fk.none
    far = {"pressure_offset": max(fk.lo, -(settings or HealthSettings()).within(cfg.range).reference_bar * 1e5),
           "flowmeter_drift": fk.lo}.get(kind, fk.hi)

    def loss(v):
        return float(reference_loss(cfg, kind, [v], settings)[0])

    if kind == "flowmeter_drift":
        v = -target / loss(-1.0)                   # loss(g) = −g·η_v
    elif loss(far) <= target:
        v = far
    else:
        v = brentq(lambda x: loss(x) - target, none, far, xtol=1e-4 * abs(far - none))
    step = v - none
    v = none + float(f"{step:.3g}")
    return v, loss(v)


def reference_loss(cfg, kind: str, values, settings=None) -> np.ndarray:
    """Apparent loss of volumetric efficiency [-] at the health monitor's reference point for each fault value.

    Δη = η_v the twin predicts − η_v the bench's flow meter shows, both at the reference speed, delivery
    pressure and oil temperature of ``settings`` (:class:`~gerotor_twin.twin.health.HealthSettings`) for
    the pump ``cfg`` (the emulated pump of the bags, at clearance factor 1.0): wear and air ingress by the
    pump's steady state with the clearance factor or free-air fraction ``v``; a flow-meter gain g: −g·η_v; a
    pressure offset δp: η_v(p + δp) − η_v(p) (the twin runs at the pressure read); a suction restriction v
    [Pa at rated flow]: η_v(p_s) − η_v(p_s − v·(Q/Q_rated)²) (a true loss the twin predicts from the
    measured suction pressure); a speed dropout: 0.  Positive: the pump looks worse than the twin predicts.

    Parameters
    ----------
    cfg : PumpConfig
    kind : str
        A kind of :data:`CASES` other than ``healthy``.
    values : sequence of float
        Fault values (the kind's unit, :data:`~gerotor_twin.bench_emulator.faults.FAULT_KINDS`).
    """
    from ..model.clearance_scale import scaled_config
    from ..model.pump import PumpModel
    from ..model.steady import run_steady
    from ..twin.health import HealthSettings
    s = (settings or HealthSettings()).within(cfg.range)
    rpm, oil = s.reference_rpm, s.reference_oil_c + 273.15
    p_s = cfg.boundary.suction_pressure_pa

    def eta(c=cfg, bar=s.reference_bar, ps=p_s):
        r = run_steady(PumpModel(c), rpm, bar, p_suction=ps, oil_temperature=oil)
        return r.mean_delivery_flow_m3s / r.theoretical_flow_m3s

    e0, q_share = eta(), rpm / cfg.range.max_speed_rpm
    per_value = {"tip_wear": lambda v: e0 - eta(scaled_config(cfg, tip=v)),
                 "lateral_wear": lambda v: e0 - eta(scaled_config(cfg, lateral=v)),
                 "air_ingress": lambda v: e0 - eta(scaled_config(cfg, air_fraction=v)),
                 "pressure_offset": lambda v: eta(bar=s.reference_bar + v / 1e5) - e0,
                 "flowmeter_drift": lambda v: -v * e0,
                 "suction_restriction": lambda v: e0 - eta(ps=p_s - v * (q_share * e0) ** 2),
                 "speed_dropout": lambda v: 0.0}
    if kind not in per_value:
        raise InputError("kind", kind, " | ".join(per_value))
    return np.array([per_value[kind](float(v)) for v in values])


def crossing_time(t_s, loss, threshold: float = LOSS_PT) -> float | None:
    """First time [s] the apparent loss ``loss`` [-] (samples at ``t_s`` [s]) reaches ``threshold`` [-] in
    magnitude, linearly interpolated between the samples; None when it never does."""
    t, a = np.asarray(t_s, float), np.abs(np.asarray(loss, float))
    i = int(np.argmax(a >= threshold))
    if a[i] < threshold:
        return None
    if i == 0:
        return float(t[0])
    return float(t[i - 1] + (threshold - a[i - 1]) / (a[i] - a[i - 1]) * (t[i] - t[i - 1]))


def truth_crossing(cfg, bag: Path, kind: str, grid: int = 11) -> tuple[float | None, float]:
    """When the bag's fault (its ``fault_series`` metadata, every 0.1 s) makes the apparent loss at the
    reference point reach :data:`LOSS_PT` [s] (None: never), and that loss at the end of the run [-].
    The loss is computed on ``grid`` values from the first to the last of the series and interpolated
    linearly in the fault's value (:func:`reference_loss`)."""
    from ..bench_emulator.emulator import EMULATOR_METADATA
    from ..io.reader import metadata
    series = json.loads(metadata(bag)[EMULATOR_METADATA]["fault_series"])
    v = np.asarray(series[kind], float)
    lo, hi = float(v.min()), float(v.max())
    grid_v = np.linspace(lo, hi, grid) if hi > lo else np.array([lo])
    grid_loss = reference_loss(cfg, kind, grid_v)
    loss = np.interp(v, grid_v, grid_loss) if hi > lo else np.full_like(v, grid_loss[0])
    return crossing_time(series["t_s"], loss), float(loss[-1])


def first_named_alarm(t, rows, kind: str) -> float | None:
    """Time [s] of the first health update at WARN or ERROR whose named fault is ``kind`` (None: none)."""
    return next((float(ti) for ti, r in zip(t, rows) if LEVELS.get(int(r["level"])) in ("WARN", "ERROR")
                 and fault_name(r) == kind), None)


#: the health monitor's windows in the bags [s]: ``window_s`` and ``settle_s`` (the speed and pressure steady this
#: long first: 2.5 time constants of the default bench's 0.2-s flow meter, where the monitor's settings ask for
#: five; kept so the figures stay comparable, docs/calibration_health.md, "The windows' settling")
WINDOW_S, SETTLE_S = 0.5, 0.5


def health_args(settle_s: float = SETTLE_S, flow_sensor_tau_s: float = 0.0) -> tuple[str, ...]:
    """``run-bag --health`` settings of the bags' monitor: windows of :data:`WINDOW_S`, ``settle_s`` [s] and the
    flow meter's time constant ``flow_sensor_tau_s`` [s] (0: off, left at the monitor's default)."""
    items = [f"window_s={WINDOW_S:g}", f"settle_s={settle_s:g}"]
    items += [f"flow_sensor_tau_s={flow_sensor_tau_s:g}"] if flow_sensor_tau_s > 0 else []
    return tuple(a for item in items for a in ("--health", item))


def run_case(cfg, kind: str, to, seed: int, out: Path, ramp_s: float, config_path: str | None = None,
             profile_file: str | None = None, health: tuple = health_args()) -> dict:
    """One bag of ``kind`` reaching severity ``to`` [the kind's unit] over ``ramp_s`` [s] from the start, noise
    ``seed``, on the pump ``cfg`` (read from ``config_path``; None: the packaged default pump) along the
    ``diagnosis`` profile or ``profile_file``, and the twin over it (``health``: its ``run-bag`` monitor
    settings, :func:`health_args`).

    Returns
    -------
    dict
        ``kind``, ``to``, ``seed``, ``ramp_s``; ``named`` and ``confidence`` [-] at the last health update;
        ``alarms`` (``alarm_records``); ``loss_end`` [-] and ``crossing_s`` [s] (:func:`truth_crossing`;
        None without a fault); ``first_right_s`` [s] (:func:`first_named_alarm`) and ``delay_s`` [s] from the
        crossing (None when either is).
    """
    tag = f"{kind}_{to:.4g}_{seed}" if to is not None else f"{kind}_{seed}"
    bag, twin = out / f"{tag}.mcap", out / f"{tag}_twin.mcap"
    fault = [] if to is None else ["--fault", kind, "--fault-to", f"{to:g}", "--fault-ramp", f"{ramp_s:g}"]
    pump = [] if config_path is None else ["--config", str(config_path)]
    profile = ["--profile", "diagnosis"] if profile_file is None else ["--profile-file", str(profile_file)]
    argv = ["synth-bench", *profile, *pump, "--clearance-factor", "1.0", "--seed",
            str(seed), "-o", str(bag), "--overwrite", "--quiet", *fault]
    if cli_main(argv) or cli_main(["run-bag", str(bag), *pump, "-o", str(twin), "--overwrite", "--quiet",
                                   *health]):
        raise RuntimeError(f"{kind} {to} seed {seed}: a command failed")
    t, rows = load_health(twin)
    crossing, loss_end = (None, 0.0) if to is None else truth_crossing(cfg, bag, kind)
    first = first_named_alarm(t, rows, kind)
    return {"kind": kind, "to": to, "seed": seed, "ramp_s": ramp_s, "named": fault_name(rows[-1]),
            "confidence": float(rows[-1]["fault_confidence"]), "alarms": alarm_records(t, rows),
            "loss_end": loss_end, "crossing_s": crossing, "first_right_s": first,
            "delay_s": None if crossing is None or first is None else first - crossing}


def confusion(results) -> str:
    """Markdown table over the bags: true kind per row, the kind named at the last health update per column."""
    named = [k for k in KINDS if any(r["named"] == k for r in results)]
    cells = collections.Counter((r["kind"], r["named"]) for r in results)
    lines = ["| true \\ named | " + " | ".join(named) + " |", "|---" * (len(named) + 1) + "|"]
    for kind in CASES:
        lines.append(f"| {kind} | " + " | ".join(str(cells.get((kind, n), "")) for n in named) + " |")
    return "\n".join(lines)


def _span(values, fmt: str = "{:.1f}") -> str:
    v = sorted(x for x in values if x is not None)
    if not v:
        return "–"
    lo, hi = fmt.format(v[0]), fmt.format(v[-1])
    return lo if lo == hi else f"{lo} … {hi}"


def alarm_summary(results) -> dict:
    """Per true kind and ``all`` (the fault bags): bags, alarms, alarms naming the true kind at their last update
    (``alarm_records``' ``fault``), their fraction (None without alarms), alarms naming it already at their first
    update (``first_right``), the kinds the other alarms named, the right and the wrong alarms whose last naming was
    tentative (``tentative``: [right, wrong]; its ``rival`` not yet excluded), 2-pt crossings [s] and delays [s]
    (:func:`run_case`), bags whose fault crossed 2 pt but no alarm named it."""
    out = {}
    groups = {k: [r for r in results if r["kind"] == k] for k in CASES}
    groups["all"] = [r for r in results if r["kind"] != "healthy"]
    for kind, rs in groups.items():
        alarms = [(r["kind"], a) for r in rs for a in r["alarms"]]
        right = sum(a["fault"] == k for k, a in alarms)
        out[kind] = {"bags": len(rs), "alarms": len(alarms), "right": right,
                     "first_right": sum(a.get("first_fault") == k for k, a in alarms),
                     "fraction": right / len(alarms) if alarms else None,
                     "wrong_named": dict(collections.Counter(str(a["fault"]) for k, a in alarms if a["fault"] != k)),
                     "tentative": [sum(bool(a.get("rival")) and (a["fault"] == k) == right_one for k, a in alarms)
                                   for right_one in (True, False)],
                     "crossing_s": [r["crossing_s"] for r in rs], "delay_s": [r["delay_s"] for r in rs],
                     "missed": sum(r["crossing_s"] is not None and r["first_right_s"] is None for r in rs)}
    return out


def alarm_table(summary: dict) -> str:
    """Markdown table of :func:`alarm_summary`: per kind the alarms naming it, the 2-pt crossings and delays."""
    lines = ["| true kind | bags | alarms | naming the true kind at the alarm's end | at its first update "
             "| other alarms named | tentative namings (right / wrong) | loss crosses 2 pt at [s] "
             "| delay to the first alarm update naming it [s] | crossed, never named in an alarm |", "|---" * 10 + "|"]
    for kind, s in summary.items():
        frac = "–" if s["fraction"] is None else f"{s['right']} ({100 * s['fraction']:.0f} %)"
        first = "–" if s["fraction"] is None else str(s.get("first_right", "–"))
        other = ", ".join(f"{k} {n}" for k, n in sorted(s["wrong_named"].items())) or "–"
        crossed = [c for c in s["crossing_s"] if c is not None]
        cross = "never" if kind != "all" and not crossed and kind != "healthy" else _span(crossed)
        delay = _span(s["delay_s"], "{:+.1f}")
        if "…" in delay and len([d for d in s["delay_s"] if d is not None]) > 2:
            delay += f" (median {float(np.median([d for d in s['delay_s'] if d is not None])):+.1f})"
        tent = "–" if s["fraction"] is None else "{} / {}".format(*s["tentative"])
        lines.append(f"| {kind} | {s['bags']} | {s['alarms']} | {frac} | {first} | {other} | {tent} | {cross} | {delay} "
                     f"| {s['missed']} |")
    return "\n".join(lines)


def severities(cfg, severity: str, progress=None) -> dict[str, list]:
    """kind → the severities of its bags on the pump ``cfg`` (``severity``: high | low | both): the flow kinds'
    solved for :data:`TARGET_LOSS` (:func:`severity_for`), the others :data:`FIXED_SEVERITY`; healthy: [None].
    ``progress``: a stream for one line per kind."""
    pick = {"high": (1,), "low": (0,), "both": (0, 1)}
    if severity not in pick:
        raise InputError("--severity", severity, " | ".join(pick))
    out = {"healthy": [None]}
    for kind in CASES[1:]:
        if kind in FIXED_SEVERITY:
            out[kind] = [FIXED_SEVERITY[kind][i] for i in pick[severity]]
            continue
        solved = [severity_for(cfg, kind, TARGET_LOSS[i]) for i in pick[severity]]
        out[kind] = [v for v, _ in solved]
        if progress is not None:
            print(f"  {kind}: " + ", ".join(f"{v:.4g} (loss {100 * l:.2f} pt)" for v, l in solved),
                  file=progress, flush=True)
    return out


def _seeds(seeds: str) -> list[int]:
    """``--seeds``: comma-separated integers."""
    try:
        return [int(s) for s in seeds.split(",")]
    except ValueError:
        raise InputError("--seeds", seeds, "comma-separated integers") from None


def _cases(seeds: str, sev: dict[str, list]) -> list[tuple[str, float | None, int]]:
    """(kind, severity, seed) of every bag: ``seeds`` comma-separated integers, ``sev`` from :func:`severities`."""
    return [(kind, to, seed) for kind in CASES for to in sev[kind] for seed in _seeds(seeds)]


def run_bags(out: Path, cases, ramp_s: float, cfg, config_path: str | None = None,
             profile_file: str | None = None, health: tuple = health_args()) -> list[dict]:
    """:func:`run_case` over ``cases`` ((kind, severity, seed)) into ``out``, one progress line per bag."""
    out.mkdir(parents=True, exist_ok=True)
    results, t0 = [], time.time()
    for i, (kind, to, seed) in enumerate(cases, 1):
        r = run_case(cfg, kind, to, seed, out, ramp_s, config_path, profile_file, health)
        results.append(r)
        alarms = ", ".join(f"{a['level']} {a['start_s']:.1f}-{a['end_s']:.1f} s "
                           f"{fault_text(a['fault'], None, a.get('rival'))}" for a in r["alarms"])
        cross = "-" if r["crossing_s"] is None else f"{r['crossing_s']:.1f} s"
        sev = "-" if to is None else f"{to:.4g}"
        print(f"[{i}/{len(cases)} {time.time() - t0:4.0f} s] {kind:20s} {sev:8s} seed {seed}: last {r['named']} "
              f"({r['confidence']:.2f}); 2 pt at {cross}; alarms: {alarms or 'none'}", flush=True)
    return results


def _separability(cfg, loss: float) -> int:
    """``--separability``: the table of :mod:`.separability` on the pump's diagnosis profile."""
    from ..twin.diagnosis import DiagnosisSettings
    from .separability import profile_points, separability, separability_table
    points = profile_points(cfg)
    print(f"separation of the flow kinds at a {100 * loss:g} pt loss, 3 windows at each of "
          + ", ".join(f"{r:g} rpm / {b:g} bar" for r, b in points) + ":")
    print(separability_table(separability(cfg, points, loss), 2.0 * DiagnosisSettings().separable_z ** 2))
    return 0


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m gerotor_twin.offline.diagnosis_bench", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("-o", "--out", default="diagnosis_bench", help="directory for the bags and results.json")
    p.add_argument("--seeds", default="1", help="noise seeds, comma-separated (default 1)")
    p.add_argument("--severity", default="high", help="high | low | both severities of each kind (default high)")
    p.add_argument("--ramp", type=float, default=None,
                   help="seconds from the start until a fault reaches its severity (default: the bag's length, 20 s; "
                        "0: a step)")
    p.add_argument("--config", default=None,
                   help="the pump (twin and emulated pump, a pump YAML; default the packaged config/pump.yaml): the "
                        "profile is scaled to its range and each flow kind's severity solved for its loss")
    p.add_argument("--profile-file", default=None, metavar="F",
                   help="a profile YAML file instead of the built-in diagnosis profile (taken as written)")
    p.add_argument("--settle", type=float, default=SETTLE_S, metavar="S",
                   help="the health monitor's settle_s in the bags [s] (default %(default)g; the monitor asks for at "
                        "least five time constants of the bench's flow meter)")
    p.add_argument("--flow-sensor-tau", type=float, default=0.0, metavar="S",
                   help="the bench flow meter's time constant [s] given to the monitor (health flow_sensor_tau_s; "
                        "default 0: off)")
    p.add_argument("--model-windows", action="store_true",
                   help="classify windows of the twin's own model on sets of operating points instead (seconds)")
    p.add_argument("--separability", type=float, default=None, metavar="LOSS",
                   help="instead, how well the classifier could tell each flow kind from every other on the "
                        "profile's points of the pump (--config), each fault at this loss at the reference point, "
                        "e.g. 0.04 [-] (seconds; gerotor_twin.offline.separability)")
    args = p.parse_args(argv)
    if args.model_windows:
        print(model_windows_table())
        return 0
    from ..bench_emulator.profile_file import load_profile_file
    from ..config import load_config
    try:
        cfg = load_config(args.config)
        if args.separability is not None:
            return _separability(cfg, check_range("--separability", args.separability, 1e-4, 0.5))
        length = profile_s(args.profile_file)
        if args.profile_file is not None:
            load_profile_file(args.profile_file, cfg.range)          # inside the pump's range, or refused here
        ramp_s = length if args.ramp is None else check_range("--ramp", args.ramp, 0.0, 1e4, unit="s")
        check_range("--settle", args.settle, 0.0, 600.0, unit="s")
        check_range("--flow-sensor-tau", args.flow_sensor_tau, 0.0, 60.0, unit="s")
        _seeds(args.seeds)
        print(f"severities on {args.config or 'the default pump'} (the apparent loss at the health monitor's "
              f"reference point when reached):", flush=True)
        sev = severities(cfg, args.severity, progress=sys.stdout)
    except InputError as e:
        p.error(str(e))
    t0, out = time.time(), Path(args.out)
    results = run_bags(out, _cases(args.seeds, sev), ramp_s, cfg, args.config, args.profile_file,
                       health_args(args.settle, args.flow_sensor_tau))
    summary = alarm_summary(results)
    (out / "results.json").write_text(json.dumps({"argv": sys.argv[1:] if argv is None else list(argv),
                                                  "severities": sev, "results": results, "summary": summary},
                                                 indent=1))
    print(confusion(results), "", alarm_table(summary), sep="\n")
    print(f"{len(results)} bags in {time.time() - t0:.0f} s; wrote {out / 'results.json'}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
