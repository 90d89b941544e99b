"""One recording of a fleet on a worker: ``run-bag`` + ``report`` (+ ``calibrate``) -> one summary row.

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
from ..twin.settings import TwinSettings
from .run_bag import run_bag

__all__ = ["process_bag", "summary_row", "health_summary", "calibration_summary"]


def _range(values, convert) -> list | None:
    v = np.asarray(values, dtype=float)
    v = v[np.isfinite(v)]
    return [convert(float(v.min())), convert(float(v.max()))] if v.size else None


def summary_row(bench, result: dict, p_atm: float) -> dict:
    """Fleet row of one recording from its bench data and its report metrics (SI; efficiency 0–1).

    ``p_atm`` [Pa] is the gauge zero of the pump config.  ``health`` is filled in by
    :func:`health_summary` (the twin log's last health update).
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


def health_summary(twin_log) -> dict | None:
    """The health monitor's final state in a twin log: level name, leakage factor ± sd, reference η_v,
    alarm intervals [s], the fault the classifier named and its probability [-]; ``None`` when the log has
    no health update (no measured flow, never steady)."""
    from ..twin.health import fault_name, tentative_rival
    from .health_log import LEVELS, alarm_intervals, load_health
    try:
        t, rows = load_health(twin_log)
    except McapReadError:
        return None
    last = rows[-1]
    return {"level": LEVELS.get(int(last["level"]), "?"), "updates": len(rows),
            "leakage_factor": last["leakage_factor"], "leakage_factor_sd": last["leakage_factor_sd"],
            "reference_efficiency": last["reference_efficiency"],
            "alarms": [list(a) for a in alarm_intervals(t, rows)], "fault": fault_name(last),
            "fault_confidence": last.get("fault_confidence"), "fault_rival": tentative_rival(last)}


def calibration_summary(bag, config, model: str, out_dir: Path, oil_sensor_tau_s: float = 0.0,
                        flow_meter: str = "delivery") -> dict:
    """Calibrate the pump on one recording (``gerotor-twin calibrate``, one process: a Dask worker is
    one core); write ``pump_fitted.yaml`` and ``calibration.json`` into ``out_dir``; return the fitted
    combinations with their 95 % intervals and residuals, or ``{"error": reason}`` (the row stays ok)."""
    import json

    import yaml

    from ..calibration.command import BENCH_CANDIDATES, calibrate_bags, fitted_config
    from ..calibration.plateaus import DetectorSettings, thermometer_lag_note
    try:                          # as `calibrate --bench` does it: its candidate sets, cross-validated
        res = calibrate_bags([bag], config_path=config, model=model, jobs=1, cv="auto", candidates=BENCH_CANDIDATES,
                             detector=DetectorSettings(oil_sensor_tau_s=oil_sensor_tau_s), flow_meter=flow_meter)
        (out_dir / "pump_fitted.yaml").write_text(yaml.safe_dump(fitted_config(res), sort_keys=False))
        (out_dir / "calibration.json").write_text(json.dumps(res, indent=1, default=float))
    except (InputError, McapReadError, ValueError, np.linalg.LinAlgError) as exc:
        return {"error": one_line(exc)}
    f = res["fit"]
    return {"config": str(out_dir / "pump_fitted.yaml"), "plateaus": len(res["plateau_records"]),
            "combinations": [{"label": c["label"], "factor": c["factor"], "factor_ci95": c["factor_ci95"]}
                             for c in f["combinations"]],
            "eta_max_abs": f["eta_error"]["max_abs"], "calibrated": res["verdict"]["calibrated"],
            "verdict": res["verdict"]["message"],
            "note": thermometer_lag_note(res["plateau_records"], oil_sensor_tau_s)}


def process_bag(settings: dict, item: dict) -> dict:
    """Run the twin over ``item["bag"]`` and report it into ``settings["out"]/bags/<name>/``; return the row.

    Parameters
    ----------
    settings : dict
        ``out`` (fleet directory), ``model`` (outer-gear model), ``config`` (pump YAML path or None),
        ``calibrate`` (also fit the pump to the recording; the twin still runs the given config, so
        the residuals show how far this pump is from it and the fit says by how much).
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
        meter = settings.get("flow_meter", "delivery")
        twin_settings = TwinSettings(max_span_s=math.inf, oil_sensor_tau_s=settings.get("oil_sensor_tau_s", 0.0),
                                     flow_meter=meter)
        stats = run_bag(item["bag"], d / "twin.mcap", model=settings["model"], config_path=settings["config"],
                        settings=twin_settings, overwrite=True, progress=None)
        result = build_report(item["bag"], [d / "twin.mcap"], d / "report.html", d / "report.json",
                              flow_meter=meter)
        p_atm = load_config(settings["config"]).fluid.atmospheric_pa
        row.update(summary_row(load_bench(item["bag"]), result, p_atm))
        row["real_time_factor"] = stats["real_time_factor"]
        row["health"] = health_summary(d / "twin.mcap")
        if settings.get("calibrate"):
            row["calibration"] = calibration_summary(item["bag"], settings["config"], settings["model"], d,
                                                     settings.get("oil_sensor_tau_s", 0.0), meter)
        if not math.isfinite(row["duration_s"]):
            raise McapReadError(item["bag"], "no finite time span")
    except (McapReadError, InputError, OSError, ValueError) as exc:
        row["status"], row["reason"] = "failed", one_line(exc)
    row["compute_s"] = time.perf_counter() - t0
    return row
