"""Confusion table of the fault classifier over emulated fault bags (a measurement, not a test).

``python -m gerotor_twin.offline.diagnosis_bench [-o DIR] [--seeds 1,2]`` makes one short bag per fault
kind, seed and severity with ``synth-bench`` (emulated pump at clearance factor 1.0 against the twin's
``config/pump.yaml``, the fault a step from the start), runs the twin over it (``run-bag``, health windows
of 0.5 s after 0.5 s of settling) and tabulates the fault the classifier names at the last health update
against the true kind (docs/calibration_health.md, "Fault diagnosis").

``--model-windows`` instead classifies windows made by the twin's own steady model with each fault in
full (:func:`model_records`, the behaviour tests' windows) on sets of operating points: what one speed or
one operating point can tell apart.
"""
from __future__ import annotations

import argparse
import collections
import json
import math
import time
from pathlib import Path

import numpy as np

from ..cli import main as cli_main
from ..twin.diagnosis import KINDS, WindowRecord
from ..twin.health import fault_name
from .health_log import load_health

__all__ = ["PROFILE", "CASES", "run_case", "confusion", "main", "model_records", "MODEL_CASES", "POINTS"]

P_ATM = 101325.0                   #: [Pa]
OIL_K = 323.15                     #: [K]
#: operating points of the bags and of :func:`model_records` [rpm, bar]
POINTS = ((1000, 5), (1000, 25), (2500, 25), (2500, 5))
#: kind → (scaled_config keywords or ``offset_pa`` [Pa], flow-meter gain [-]) for :func:`model_records`
MODEL_CASES = {"healthy": ({}, 0.0), "tip_wear": ({"tip": 2.0}, 0.0), "lateral_wear": ({"lateral": 1.15}, 0.0),
               "air_ingress": ({"air_fraction": 0.03}, 0.0), "pressure_offset": ({"offset_pa": 1e5}, 0.0),
               "flowmeter_drift": ({}, 0.05)}

#: four plateaus of 2.5 s at 50 °C: two speeds × two delivery pressures [rpm, bar]
PROFILE = """name: diagnosis
segments:
  - {duration_s: 2.5, rpm: 1000, bar: 5, oil_temperature_c: 50}
  - {duration_s: 2.5, rpm: 1000, bar: 25}
  - {duration_s: 2.5, rpm: 2500, bar: 25}
  - {duration_s: 2.5, rpm: 2500, bar: 5}
"""

#: true kind → two severities (``--fault-to``; healthy: none)
CASES = {"healthy": (None, None), "tip_wear": (1.5, 2.0), "lateral_wear": (1.1, 1.3),
         "air_ingress": (0.01, 0.03), "pressure_offset": (5e4, 1e5), "flowmeter_drift": (0.02, 0.05),
         "speed_dropout": (0.1, 0.3), "suction_restriction": (3e4, 6e4)}


def _flow(cfg, rpm, bar, p_suction=P_ATM, **fault):
    from ..model.clearance_scale import scaled_config
    from ..model.pump import PumpModel
    from ..model.steady import run_steady
    off = fault.pop("offset_pa", 0.0)
    model = PumpModel(scaled_config(cfg, **fault) if fault else cfg)
    return run_steady(model, rpm, bar - off / 1e5, p_suction=p_suction, oil_temperature=OIL_K)


def model_records(cfg, fault: dict, gain: float = 0.0, rel_sd: float = 0.003, seed: int = 0, windows: int = 3,
                  restriction_pa: float | None = None, points=POINTS) -> list[WindowRecord]:
    """Settled windows of the pump ``cfg`` with ``fault`` applied in full (:func:`scaled_config` keywords, or
    ``offset_pa`` [Pa]: the transducer reads that much high) and a flow-meter gain ``gain`` [-], ``windows``
    per operating point of ``points`` [rpm, bar] at 50 °C, flow noise ``rel_sd`` × flow; the predictions are
    the configured twin's steady state.  With ``restriction_pa`` [Pa] a suction sensor reads a line drop of
    5 kPa at 3000 rpm ∝ speed² plus the restriction at 68.3 L/min ∝ flow² (100 Pa noise)."""
    rng = np.random.default_rng(seed)
    out, t = [], 0.0
    for rpm, bar in points:
        p_s = P_ATM
        if restriction_pa is not None:
            q0 = _flow(cfg, rpm, bar).mean_delivery_flow_m3s
            p_s = P_ATM - 5e3 * (rpm / 3000) ** 2 - restriction_pa * (q0 / 68.3 * 6e4) ** 2
        pred = _flow(cfg, rpm, bar, p_s)
        true = _flow(cfg, rpm, bar, p_s, **dict(fault)).mean_delivery_flow_m3s
        for _ in range(windows):
            t += 0.5
            q_meas = true * (1 + gain) + rng.normal(0.0, rel_sd * true)
            p_read = p_s + (0.0 if restriction_pa is None else rng.normal(0.0, 100.0))
            out.append(WindowRecord(t, rpm * math.pi / 30, P_ATM + bar * 1e5, p_read, OIL_K, q_meas,
                                    pred.mean_delivery_flow_m3s, pred.theoretical_flow_m3s, rel_sd * q_meas))
    return out


def model_windows_table() -> str:
    """Markdown table: per set of operating points and true kind, the named kind and the probabilities > 0.05."""
    from ..config import load_config
    from ..twin.diagnosis import SteadySignatures, classify
    cfg = load_config()
    sig = SteadySignatures(cfg)
    lines = ["| operating points [rpm / bar] | true | named (probability) | other kinds > 0.05 |", "|---|---|---|---|"]
    for pts in (POINTS, POINTS[:2], POINTS[2:], POINTS[1:2]):
        for kind, (fault, gain) in MODEL_CASES.items():
            recs = model_records(cfg, fault, gain, points=pts)
            d = classify(recs, [sig(r) for r in recs])
            other = ", ".join(f"{k} {p:.2f}" for k, p in d.probability.items() if p > 0.05 and k != d.kind)
            lines.append(f"| {', '.join(f'{r}/{b}' for r, b in pts)} | {kind} | {d.kind} ({d.confidence:.2f}) | {other} |")
    return "\n".join(lines)


def run_case(kind: str, to, seed: int, out: Path) -> tuple[str, float]:
    """One bag of ``kind`` at severity ``to`` [the kind's unit] and ``seed``; the named fault and its
    probability [-] at the last health update."""
    bag, twin = out / f"{kind}_{to}_{seed}.mcap", out / f"{kind}_{to}_{seed}_twin.mcap"
    fault = [] if to is None else ["--fault", kind, "--fault-to", f"{to:g}", "--fault-ramp", "0"]
    argv = ["synth-bench", "--profile-file", str(out / "profile.yaml"), "--clearance-factor", "1.0", "--seed",
            str(seed), "-o", str(bag), "--overwrite", "--quiet", *fault]
    if cli_main(argv) or cli_main(["run-bag", str(bag), "-o", str(twin), "--overwrite", "--quiet",
                                   "--health", "window_s=0.5", "--health", "settle_s=0.5"]):
        raise RuntimeError(f"{kind} {to} seed {seed}: a command failed")
    _, rows = load_health(twin)
    return fault_name(rows[-1]), float(rows[-1]["fault_confidence"])


def confusion(results) -> str:
    """Markdown table: true kind per row, named kind per column (counts)."""
    named = [k for k in KINDS if any(r[2] == k for r in results)]
    cells = collections.Counter((r[0], r[2]) for r in results)
    lines = ["| true \\ named | " + " | ".join(named) + " |", "|---" * (len(named) + 1) + "|"]
    for kind in CASES:
        lines.append(f"| {kind} | " + " | ".join(str(cells.get((kind, n), "")) for n in named) + " |")
    return "\n".join(lines)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="python -m gerotor_twin.offline.diagnosis_bench", description=__doc__)
    p.add_argument("-o", "--out", default="diagnosis_bench", help="directory for the bags and results.json")
    p.add_argument("--seeds", default="1,2", help="noise seeds, comma-separated (default 1,2)")
    p.add_argument("--model-windows", action="store_true",
                   help="classify windows of the twin's own model on sets of operating points instead (seconds)")
    args = p.parse_args(argv)
    if args.model_windows:
        print(model_windows_table())
        return 0
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "profile.yaml").write_text(PROFILE)
    results, t0 = [], time.time()
    for kind, tos in CASES.items():
        for to in sorted(set(tos), key=lambda v: -1 if v is None else v):
            for seed in (int(s) for s in args.seeds.split(",")):
                name, p_named = run_case(kind, to, seed, out)
                results.append((kind, to, name, p_named, seed))
                print(f"{kind:20s} {to!s:8s} seed {seed}: {name} ({p_named:.2f})", flush=True)
    (out / "results.json").write_text(json.dumps(results, indent=1))
    print(confusion(results))
    print(f"{len(results)} bags in {time.time() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
