"""``gerotor-twin batch BAG_DIR_OR_GLOB -o OUTDIR``: run-bag + report for a fleet of recordings on Dask.

OUTDIR receives:

=====================  ======================================================
``manifest.json``      model and pump config of the fleet (a rerun must match)
``bags.jsonl``         one row per finished recording, appended as it finishes
``bags/<name>/``       ``twin.mcap`` (run-bag), ``report.html`` + ``report.json``
``fleet.json``         the rows of the recordings selected by this run
``fleet.csv``          the same as a table (SI units, efficiency 0–1)
``fleet.html``         one row per recording (date, duration, operating range,
                       flow bias/RMSE, η error, health), linked to its report
=====================  ======================================================

Resumable: a rerun on the same OUTDIR skips the recordings already done (same
path, size and modification time) and runs the new ones, so a nightly
``batch /data/bags -o /data/fleet`` processes what arrived since.
"""
from __future__ import annotations

import csv
import glob
import hashlib
import json
import sys
import time
from pathlib import Path
from typing import IO

from ..errors import InputError
from ..hydraulics.meter import FLOW_METERS
from ..model.pump import BEARING_MODELS
from .engine import Progress, add_engine_arguments, check_engine_args, dask_client, discarded_if_unused, run_tasks
from .results_store import ResultStore

__all__ = ["find_bags", "run_batch", "add_parser", "CSV_COLUMNS"]

CSV_COLUMNS = ("name", "status", "reason", "date_utc", "duration_s", "speed_min_rpm", "speed_max_rpm",
               "delivery_min_bar", "delivery_max_bar", "plateaus", "flow_bias_m3s", "flow_rmse_m3s",
               "flow_max_abs_m3s", "eta_bias", "eta_rmse", "health", "health_leakage_factor",
               "health_leakage_factor_sd", "health_reference_efficiency", "fit_combination", "fit_factor",
               "fit_factor_lo", "fit_factor_hi", "fit_eta_max_abs", "fit_error", "bag", "report")


def find_bags(pattern: str) -> list[Path]:
    """The ``.mcap`` recordings named by a directory, a glob or one file (sorted, resolved)."""
    p = Path(pattern)
    if p.is_dir():
        found = sorted(p.glob("*.mcap"))
    elif p.is_file():
        found = [p]
    else:
        found = sorted(Path(f) for f in glob.glob(pattern, recursive=True) if Path(f).is_file())
    if not found:
        raise InputError("BAG_DIR_OR_GLOB", pattern, "a directory holding .mcap files, a glob matching some, "
                                                     "or one .mcap file")
    return [f.resolve() for f in found]


def _item(bag: Path) -> dict:
    st = bag.stat()
    digest = hashlib.sha1(f"{bag}|{st.st_size}|{st.st_mtime_ns}".encode()).hexdigest()[:12]
    return {"id": digest, "bag": str(bag), "name": f"{bag.stem}-{digest[:8]}"}


def _prepare(out: Path, model: str, config: str | None, calibrate: bool = False, oil_sensor_tau_s: float = 0.0,
             flow_meter: str = "delivery") -> None:
    manifest = out / "manifest.json"
    want = {"model": model, "config": str(Path(config).resolve()) if config else None, "calibrate": calibrate,
            "oil_sensor_tau_s": oil_sensor_tau_s, "flow_meter": flow_meter}
    if manifest.exists():
        have = {"calibrate": False, "oil_sensor_tau_s": 0.0, "flow_meter": "delivery",
                **json.loads(manifest.read_text())}
        for key, opt in (("model", "--model"), ("config", "--config"), ("calibrate", "--calibrate"),
                         ("oil_sensor_tau_s", "--oil-sensor-tau"), ("flow_meter", "--flow-meter")):
            if have.get(key) != want[key]:
                raise InputError(opt, want[key], f"{have.get(key)!r} (the fleet in {out} was run with it)",
                                 "use another -o for another model, pump config or calibration choice")
        return
    if out.exists() and not out.is_dir():
        raise InputError("-o", str(out), "a directory (it is a file)")
    out.mkdir(parents=True, exist_ok=True)
    manifest.write_text(json.dumps({**want, "created_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())},
                                   indent=2))


def _failure(item: dict, reason: str) -> dict:
    return {"id": item["id"], "bag": item["bag"], "name": item["name"], "status": "failed", "reason": reason}


def _csv_row(r: dict) -> list:
    sr, dr = r.get("speed_range_rpm") or [None, None], r.get("delivery_range_bar") or [None, None]
    h, cal = r.get("health") or {}, r.get("calibration") or {}
    fit = (cal.get("combinations") or [{}])[0]
    ci = fit.get("factor_ci95") or [None, None]
    flat = {**r, "speed_min_rpm": sr[0], "speed_max_rpm": sr[1], "delivery_min_bar": dr[0],
            "delivery_max_bar": dr[1], "health": h.get("level"), "health_leakage_factor": h.get("leakage_factor"),
            "health_leakage_factor_sd": h.get("leakage_factor_sd"),
            "health_reference_efficiency": h.get("reference_efficiency"), "fit_combination": fit.get("label"),
            "fit_factor": fit.get("factor"), "fit_factor_lo": ci[0], "fit_factor_hi": ci[1],
            "fit_eta_max_abs": cal.get("eta_max_abs"), "fit_error": cal.get("error")}
    return [flat.get(c) for c in CSV_COLUMNS]


def write_fleet(out: Path, rows: list[dict], info: list[str]) -> None:
    """``fleet.json``, ``fleet.csv`` and ``fleet.html`` from the rows (sorted by name)."""
    from .batch_html import fleet_page
    (out / "fleet.json").write_text(json.dumps({"info": info, "recordings": rows}, indent=2))
    with open(out / "fleet.csv", "w", newline="", encoding="utf-8") as fh:
        w = csv.writer(fh)
        w.writerow(CSV_COLUMNS)
        w.writerows(_csv_row(r) for r in rows)
    (out / "fleet.html").write_text(fleet_page(out, rows, info), encoding="utf-8")


def run_batch(pattern: str, out, *, model: str = "mobility", config: str | None = None, scheduler: str | None = None,
              workers: int | None = None, calibrate: bool = False, oil_sensor_tau_s: float = 0.0,
              flow_meter: str = "delivery", progress: IO[str] | None = sys.stderr) -> dict:
    """Process every recording matched by ``pattern`` into ``out``; return counts and timing.

    ``oil_sensor_tau_s`` [s]: the bench thermometer's lag, undone in the twin runs and the calibration
    (as ``run-bag --oil-sensor-tau``); ``flow_meter``: where the bench's flow meter reads, in the twin runs, the
    reports and the calibration (as ``run-bag --flow-meter``)."""
    from ..twin.settings import TwinSettings, oil_sensor_tau_arg
    oil_sensor_tau_arg(oil_sensor_tau_s)
    TwinSettings(flow_meter=flow_meter)                 # checked once here, not once per bag
    if model not in BEARING_MODELS:
        raise InputError("--model", model, " | ".join(BEARING_MODELS))
    check_engine_args(scheduler, workers)
    if config is not None:
        from ..config import load_config
        load_config(config)                       # a bad config is one error here, not one per bag
    items = [_item(b) for b in find_bags(pattern)]
    out = Path(out)
    with discarded_if_unused(out, ("manifest.json", "bags.jsonl"), "bags.jsonl"):
        _prepare(out, model, config, calibrate, oil_sensor_tau_s, flow_meter)
        settings = {"out": str(out.resolve()), "model": model, "calibrate": calibrate,
                    "oil_sensor_tau_s": oil_sensor_tau_s, "flow_meter": flow_meter,
                    "config": str(Path(config).resolve()) if config else None}
        t0 = time.monotonic()
        with ResultStore(out / "bags.jsonl") as store:
            kept = sum(it["id"] in store for it in items)
            bar = Progress("batch", len(items), done=kept, unit="recordings", stream=progress)
            n_workers = 0
            if kept < len(items):
                from .batch_bag import process_bag
                with dask_client(scheduler, workers) as client:
                    n_workers = len(client.scheduler_info()["workers"])
                    run_tasks(client, process_bag, settings, items, store, key_prefix="batch", progress=bar,
                              failure=_failure)
            bar.close()
            rows = sorted((store.records[it["id"]] for it in items if it["id"] in store), key=lambda r: r["name"])
    ok = sum(r["status"] == "ok" for r in rows)
    wall = time.monotonic() - t0
    info = [f"{len(rows)} recordings ({pattern}): {ok} reported, {len(rows) - ok} failed; model {model}, "
            f"config {config or 'default pump'}",
            f"{len(items) - kept} processed this run in {wall:.1f} s on {n_workers} worker(s), {kept} kept from before"]
    write_fleet(out, rows, info)
    return {"recordings": len(rows), "ok": ok, "failed": len(rows) - ok, "kept": kept,
            "processed": len(items) - kept, "wall_s": wall, "workers": n_workers}


def cmd_batch(args) -> int:
    res = run_batch(args.bags, args.output, model=args.model, config=args.config, scheduler=args.scheduler,
                    workers=args.workers, calibrate=args.calibrate, oil_sensor_tau_s=args.oil_sensor_tau,
                    flow_meter=args.flow_meter, progress=None if args.quiet else sys.stderr)
    out = Path(args.output)
    print(f"batch: {res['recordings']} recordings, {res['ok']} reported, {res['failed']} failed "
          f"({res['processed']} processed in {res['wall_s']:.1f} s on {res['workers']} worker(s), "
          f"{res['kept']} kept)")
    print(f"wrote {out / 'fleet.html'}, {out / 'fleet.json'}, {out / 'fleet.csv'}")
    return 0


def add_parser(sub) -> None:
    p = sub.add_parser("batch", help="run-bag + report for every recording of a fleet, on Dask",
                       description="Run the twin over every bench recording (a directory, a glob or one file) "
                                   "and report each, on a Dask cluster (embedded by default); resumable; "
                                   "fleet summary as HTML, JSON and CSV. See docs/sweep.md.")
    p.add_argument("bags", metavar="BAG_DIR_OR_GLOB", help="directory of .mcap files, a quoted glob, or one file")
    p.add_argument("-o", "--output", required=True, help="fleet output directory (rerun to add new recordings)")
    p.add_argument("--model", default="mobility", help="outer-gear model: " + " | ".join(BEARING_MODELS))
    p.add_argument("--config", help="pump YAML (default config/pump.yaml)")
    add_engine_arguments(p)
    p.add_argument("--oil-sensor-tau", type=float, default=0.0, metavar="S",
                   help="time constant of the bench's oil thermometer [s], undone in the twin and the fit "
                        "(as run-bag --oil-sensor-tau; default 0)")
    p.add_argument("--flow-meter", choices=FLOW_METERS, default="delivery",
                   help="where the bench's flow meter reads, in the twin, the reports and the fit (as run-bag "
                        "--flow-meter; default delivery)")
    p.add_argument("--calibrate", action="store_true",
                   help="also fit the pump (tooth-tip + lateral clearances) to each recording: "
                        "bags/<name>/pump_fitted.yaml and the fitted factor in the summary (minutes per bag)")
    p.set_defaults(func=cmd_batch)
