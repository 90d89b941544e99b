"""``gerotor-twin bench sweep``: design-study points per second on 1, 2, ... Dask workers (printed, never a test).

Two studies (``--sweep-kind``), both on the twin's mobility model with the default numerics:

``geometry`` (default)
    Latin hypercube over eccentricity and lobe radius at one operating point: every point
    builds its own geometry tables (the expensive part of a real design study); the table
    cache is a fresh directory per run, so each run pays that cost.
``operating``
    Latin hypercube over speed and delivery pressure on the default pump, tables built once
    before the clock starts: the cost of the steady state itself plus Dask's per-task overhead.

Wall time includes starting the embedded cluster; the speed-up is the ratio of points per
second to the single worker's.
"""
from __future__ import annotations

import json
import os
import sys
import tempfile
import time
from pathlib import Path

from ..errors import InputError
from .engine import warm_up_kernels

__all__ = ["bench_sweep", "add_parser"]

BENCH_SPECS = {
    "geometry": {
        "title": "eccentricity x lobe radius (LHS) at 2000 rpm / 15 bar, mobility model, cold table cache",
        "model": "mobility",
        "operating": {"speed_rpm": 2000, "delivery_bar": 15},
        "parameters": {"gears.eccentricity_m": {"min": 3.3e-3, "max": 3.7e-3},
                       "gears.lobe_radius_m": {"min": 8.5e-3, "max": 9.5e-3}},
        "design": "lhs", "seed": 7},
    "operating": {
        "title": "speed x delivery pressure (LHS) on the default pump, mobility model, tables built beforehand",
        "model": "mobility",
        "parameters": {"operating.speed_rpm": {"min": 500.0, "max": 3000.0},
                       "operating.delivery_bar": {"min": 2.0, "max": 27.5}},
        "design": "lhs", "seed": 7},
}


def _workers(text: str) -> list[int]:
    try:
        vals = [int(v) for v in str(text).split(",")]
    except ValueError:
        raise InputError("--sweep-workers", text, "comma-separated integers in [1, 512]") from None
    if not vals or any(not 1 <= v <= 512 for v in vals):
        raise InputError("--sweep-workers", text, "comma-separated integers in [1, 512]")
    return vals


def bench_sweep(points: int = 8, workers=(1, 2), scheduler: str | None = None, kind: str = "geometry",
                stream=sys.stdout) -> list[dict]:
    """Run the bench study once per worker count; return one row per run (points/s, speed-up)."""
    from .sweep import run_sweep
    from .sweep_spec import parse_spec
    if not 2 <= points <= 100_000:
        raise InputError("--sweep-points", points, "an integer in [2, 100000]")
    if kind not in BENCH_SPECS:
        raise InputError("--sweep-kind", kind, " | ".join(BENCH_SPECS))
    spec = parse_spec({**BENCH_SPECS[kind], "samples": points})
    warm_up_kernels()
    rows = []
    old = os.environ.get("GEROTOR_TWIN_CACHE")
    try:
        for n in ([None] if scheduler else workers):
            with tempfile.TemporaryDirectory(prefix="gerotor_bench_sweep_") as tmp:
                os.environ["GEROTOR_TWIN_CACHE"] = str(Path(tmp) / "cache")    # a fresh table cache per run
                if kind == "operating":
                    from ..config import load_config
                    from ..geometry.tables import cached_tables
                    c = load_config()
                    cached_tables(c.gears, c.suction_port, c.delivery_port, c.numerics.table_points)
                t0 = time.perf_counter()
                res = run_sweep(spec, Path(tmp) / "results", scheduler=scheduler, workers=n, progress=None)
                wall = time.perf_counter() - t0
                recs = [json.loads(x) for x in (Path(tmp) / "results" / "points.jsonl").read_text().splitlines()]
            cpu = sum(r["compute_s"] or 0.0 for r in recs) / max(1, len(recs))
            row = {"workers": res["workers"], "points": res["points"], "failed": res["failed"], "wall_s": wall,
                   "run_s": res["run_s"], "points_per_s": res["points"] / wall,
                   "points_per_s_running": res["points"] / res["run_s"], "mean_point_s": cpu}
            row["speedup"] = row["points_per_s"] / rows[0]["points_per_s"] if rows else 1.0
            row["speedup_running"] = row["points_per_s_running"] / rows[0]["points_per_s_running"] if rows else 1.0
            rows.append(row)
            print(f"  {row['workers']:3d} worker(s): {row['points']} points in {wall:6.1f} s = "
                  f"{row['points_per_s']:6.2f} points/s, speed-up {row['speedup']:.2f} (cluster start included); "
                  f"{row['points_per_s_running']:6.2f} points/s, speed-up {row['speedup_running']:.2f} once running; "
                  f"{cpu:.3f} s per point inside a task; {row['failed']} failed", file=stream, flush=True)
    finally:
        if old is None:
            os.environ.pop("GEROTOR_TWIN_CACHE", None)
        else:
            os.environ["GEROTOR_TWIN_CACHE"] = old
    return rows


def add_parser(subparsers) -> None:
    """Teach the existing ``bench`` sub-command the choice ``sweep`` (registered in ``cli._COMMAND_MODULES``)."""
    from ..cli import extend_bench
    bench = extend_bench(subparsers, "sweep")
    if bench is None:
        return
    bench.add_argument("--sweep-points", type=int, default=8, help="bench sweep: points per run (default 8)")
    bench.add_argument("--sweep-workers", default="1,2", help="bench sweep: worker counts to time (default 1,2)")
    bench.add_argument("--sweep-kind", default="geometry", help="bench sweep: geometry | operating (default geometry)")
    bench.add_argument("--sweep-scheduler", help="bench sweep: time a running Dask cluster instead (tcp://host:8786)")
    previous = bench.get_default("func")

    def dispatch(args):
        if args.what != "sweep":
            return previous(args)
        spec = BENCH_SPECS.get(args.sweep_kind, {"title": "?"})
        print(f"bench sweep ({args.sweep_kind}): {spec['title']}; {args.sweep_points} points per run; "
              f"{os.cpu_count()} cores here, load average {os.getloadavg()[0]:.2f}")
        rows = bench_sweep(args.sweep_points, _workers(args.sweep_workers), args.sweep_scheduler, args.sweep_kind)
        if args.json:
            Path(args.json).write_text(json.dumps({"sweep": rows}, indent=2))
            print(f"wrote {args.json}")
        return 0

    bench.set_defaults(func=dispatch)
