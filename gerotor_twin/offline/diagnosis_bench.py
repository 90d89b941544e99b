"""Confusion table of the fault classifier over emulated fault bags (a measurement, not a test).

``python -m gerotor_twin.offline.diagnosis_bench [-o DIR] [--seeds 1,2]`` makes one short bag per fault
kind, seed and severity with ``synth-bench`` (emulated pump at clearance factor 1.0 against the twin's
``config/pump.yaml``, the fault a step from the start), runs the twin over it (``run-bag``, health windows
of 0.5 s after 0.5 s of settling) and tabulates the fault the classifier names at the last health update
against the true kind (docs/calibration_health.md, "Fault diagnosis").
"""
from __future__ import annotations

import argparse
import collections
import json
import time
from pathlib import Path

from ..cli import main as cli_main
from ..twin.diagnosis import KINDS
from ..twin.health import fault_name
from .health_log import load_health

__all__ = ["PROFILE", "CASES", "run_case", "confusion", "main"]

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
    args = p.parse_args(argv)
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
