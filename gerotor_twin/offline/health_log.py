"""``gerotor-twin health TWIN.mcap``: the health estimate of a twin log over time, and its alarm intervals.

Reads ``twin/health`` (see :mod:`gerotor_twin.twin.health`) from a node log or a
``run-bag`` output and prints one line per update (or every ``--every``-th) and the
intervals spent in WARN and ERROR, each with the fault the classifier named at its last update
(:mod:`gerotor_twin.twin.diagnosis`) and that fault's probability.
"""
from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from ..io import McapReadError, open_mcap, read_topics
from ..io.reader import multiarray_series
from ..twin.health import (HEALTH_FIELDS, LEVELS, alarm_intervals, alarm_records, fault_name, fault_text,
                           tentative_rival)

__all__ = ["load_health", "alarm_intervals", "LEVELS", "cmd_health", "add_parser"]


def load_health(path) -> tuple[np.ndarray, list[dict]]:
    """Times [s, from the log's first measured-flow input (the bench recording's start), else its first
    ``/diagnostics``, else the first update] and field dicts of every ``twin/health`` message."""
    f = open_mcap(path)
    types = f.topic_types()
    topic = next((t for t in types if t.endswith("twin/health")), None)
    if topic is None:
        raise McapReadError(str(path), "no twin/health topic (a log of a version without the health monitor?)")
    s = read_topics(path, [topic])[topic]
    if len(s) == 0:
        raise McapReadError(str(path), "twin/health has no messages (no measured delivery flow, or never steady)")
    t0_ns = int(s.log_time_ns[0])
    for suffix in ("bench/delivery_flow", "/diagnostics"):
        other = next((t for t in types if t.endswith(suffix)), None)
        d = read_topics(path, [other])[other] if other else ()
        if len(d):
            t0_ns = min(t0_ns, int(d.log_time_ns[0]))
            break
    t, v, _ = multiarray_series(s, t0_ns=t0_ns)
    return t, [dict(zip(HEALTH_FIELDS, row)) for row in v]


def cmd_health(args) -> int:
    t, rows = load_health(args.log)
    every = max(1, args.every)
    print(f"{args.log}: {len(rows)} health updates over {t[-1]:.1f} s")
    print("   t [s]  leakage factor      eta_ref [%]      residual [L/min]  level  fault (probability)")
    for i, (ti, r) in enumerate(zip(t, rows)):
        if i % every and i != len(rows) - 1:
            continue
        print(f"  {ti:6.1f}  {r['leakage_factor']:.4f} ± {r['leakage_factor_sd']:.4f}  "
              f"{100 * r['reference_efficiency']:6.2f} ± {100 * r['reference_efficiency_sd']:.2f}  "
              f"{6e4 * r['residual_m3s']:+8.3f}          {LEVELS.get(int(r['level']), '?'):5s}  "
              f"{fault_text(fault_name(r), r.get('fault_confidence'), tentative_rival(r))}")
    alarms = alarm_records(t, rows)
    for a in alarms:
        first = "" if a["first_fault"] == a["fault"] else (f" (first named {fault_text(a['first_fault'], a['first_confidence'])}"
                                                            f"; {a['fault']} from {a['named_at_s']:.1f} s)")
        print(f"  {a['level']} from {a['start_s']:.1f} s to {a['end_s']:.1f} s: "
              f"{fault_text(a['fault'], a['confidence'], a['rival'])}{first}")
    if not alarms:
        print("  no WARN or ERROR")
    if args.json:
        Path(args.json).write_text(json.dumps({"t_s": t.tolist(), "updates": rows,
                                               "alarms": [[a["level"], a["start_s"], a["end_s"]] for a in alarms],
                                               "alarm_records": alarms}, indent=1))
        print(f"wrote {args.json}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("health", help="print the health estimate (twin/health) of a twin log and its alarms")
    p.add_argument("log", help="node log or run-bag output (MCAP)")
    p.add_argument("--every", type=int, default=1, help="print every N-th update (default 1)")
    p.add_argument("--json", metavar="F", help="write every update and the alarm intervals as JSON (alarm_records: "
                                               "start_s, end_s, level, fault, confidence named at the alarm's last "
                                               "update; first_fault, first_confidence at its first; named_at_s)")
    p.set_defaults(func=cmd_health)
