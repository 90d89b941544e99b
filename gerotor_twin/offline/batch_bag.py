"""One recording of a fleet on a worker: ``run-bag`` + ``report`` -> one summary row.

Runs where the engine puts it; the bag and the pump config are read by path,
so on a multi-machine cluster both must be on storage every worker sees (the
same path).  Any problem with one recording (unreadable bag, missing topics,
no steady plateau ...) makes its row ``failed`` with the one-line reason; the
other recordings go on.
"""
from __future__ import annotations

import math
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

from ..config import load_config
from ..errors import InputError, one_line
from ..io import McapReadError
from ..units import pa_abs_to_bar_gauge, rad_s_to_rpm
from .run_bag import run_bag

__all__ = ["process_bag", "summary_row"]


def _range(values, convert) -> list | None:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return [convert(float(v.min())), convert(float(v.max()))] if v.size else None


def summary_row(bench, result: dict, p_atm: float) -> dict:
    """Fleet row of one recording from its bench data and its report metrics (SI; efficiency 0–1).

    ``p_atm`` [Pa] is the gauge zero of the pump config.  ``health`` is None: this build has no
    health estimator (issue 14 adds one).
    """
    twin = result["twins"][0]
    o = twin["overall"]
    fe, ee = o["flow_error_m3s"], o["eta_error"]
    t_speed, speed = bench.speed
    duration = max(float(t_speed[-1]), float(bench.delivery_pressure[0][-1])) if len(t_speed) else 0.0
    return {
        "date_utc": datetime.fromtimestamp(bench.t0_ns / 1e9, tz=timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ"),
        "duration_s": duration,
        "speed_range_rpm": _range(speed, rad_s_to_rpm),
        "delivery_range_bar": _range(bench.delivery_pressure[1], lambda p: pa_abs_to_bar_gauge(p, p_atm)),
        "plateaus": len(result["plateaus"]),
        "flow_bias_m3s": fe["bias"], "flow_rmse_m3s": fe["rmse"], "flow_max_abs_m3s": fe["max_abs"],
        "eta_bias": ee["bias"], "eta_rmse": ee["rmse"],
        "health": None,
        "notes": result["notes"],
    }


def process_bag(settings: dict, item: dict) -> dict:
    """Run the twin over ``item["bag"]`` and report it into ``settings["out"]/bags/<name>/``; return the row.

    Parameters
    ----------
    settings : dict
        ``out`` (fleet directory), ``model`` (outer-gear model), ``config`` (pump YAML path or None).
    item : dict
        ``id``, ``bag`` (absolute path), ``name`` (directory name of its outputs).
    """
    from ..report.build import build_report
    from ..report.data import load_bench
    t0 = time.perf_counter()
    d = Path(settings["out"]) / "bags" / item["name"]
    row = {"id": item["id"], "bag": item["bag"], "name": item["name"], "status": "ok", "reason": "",
           "twin": str(d / "twin.mcap"), "report": str(d / "report.html")}
    try:
        d.mkdir(parents=True, exist_ok=True)
        stats = run_bag(item["bag"], d / "twin.mcap", model=settings["model"], config_path=settings["config"],
                        overwrite=True, progress=None)
        result = build_report(item["bag"], [d / "twin.mcap"], d / "report.html", d / "report.json")
        p_atm = load_config(settings["config"]).fluid.atmospheric_pa
        row.update(summary_row(load_bench(item["bag"]), result, p_atm))
        row["real_time_factor"] = stats["real_time_factor"]
        if not math.isfinite(row["duration_s"]):
            raise McapReadError(item["bag"], "no finite time span")
    except (McapReadError, InputError, OSError, ValueError) as exc:
        row["status"], row["reason"] = "failed", one_line(exc)
    row["compute_s"] = time.perf_counter() - t0
    return row
