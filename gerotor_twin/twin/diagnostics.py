"""``diagnostic_msgs/DiagnosticStatus`` dicts from a :meth:`TwinCore.snapshot` (no rclpy).

Key names carry their unit (``_s``, ``_rad_s``, ``_pa``, ``_m3s``); values
are strings as DiagnosticStatus requires (``n/a`` when undefined, never NaN).
"""
from __future__ import annotations

from typing import Any

from gerotor_twin.io import messages as m
from gerotor_twin.twin.inputs import INPUTS, REQUIRED

__all__ = ["model_status", "input_status", "MODEL_STATUS_NAME", "INPUT_STATUS_NAME"]

MODEL_STATUS_NAME = "gerotor_twin: model"
INPUT_STATUS_NAME = "gerotor_twin: inputs"
_EVENTS = ("cavitation_clamps", "housing_contact", "gear_contact_corrections", "contact_unloaded")


def _fmt(v: Any) -> Any:
    if v is None:
        return "n/a"
    if isinstance(v, float) and v != v:
        return "n/a"
    return v


def model_status(snap: dict, delta: dict[str, int]) -> dict:
    """Status of the model: state, real-time factor, lag, skips, resets, solver, events."""
    counts = snap["counts"]
    resets = snap["resets"]
    if snap["status"] == "running":
        level, msg = m.DIAG_OK, "running"
        if delta.get("solver_failures", 0) or delta.get("skips", 0):
            level, msg = m.DIAG_WARN, "running; skipped backlog or solver trouble in the last period"
        rtf = snap["real_time_factor"]
        if rtf is not None and rtf < 1.0:
            level, msg = m.DIAG_WARN, f"running slower than real time (RTF {rtf:.2f}); lag policy skips backlog"
        if snap.get("oil_temperature_warn"):
            level = m.DIAG_WARN
            msg += (f"; oil temperature stale: using the reference {snap['oil_temperature_c']:g} °C")
    elif snap["status"] == "held":
        level, msg = m.DIAG_STALE, f"held: {snap['reason']}"
    else:
        level, msg = m.DIAG_STALE, f"waiting: {snap['reason']}"
    values = {
        "status": snap["status"],
        "real_time_factor": _fmt(snap["real_time_factor"]),
        "lag_s": _fmt(snap["lag_s"]),
        "last_tick_compute_s": _fmt(snap["last_tick_compute_s"]),
        "simulated_s": snap["simulated_s"], "held_s": snap["held_s"],
        "skips": snap["skips"], "skipped_s": snap["skipped_s"],
        "resets": sum(resets.values()),
        "resets_clock_jump_back": resets.get("clock_jump_back", 0),
        "resets_solver_failure": resets.get("solver_failure", 0),
        "revolutions": snap["revolutions"], "waveforms": snap["waveforms"],
        "published": snap["published"], "nonfinite_suppressed": snap["nonfinite_suppressed"],
        "solver_steps": counts.get("steps", 0), "solver_substeps": counts.get("substeps", 0),
        "solver_rejected_substeps": counts.get("rejected_substeps", 0),
        "solver_failures": counts.get("solver_failures", 0) + resets.get("solver_failure", 0),
        "eccentricity_ratio": _fmt(snap["eccentricity_ratio"]),
        "oil_temperature_c": _fmt(snap.get("oil_temperature_c")),
        "oil_temperature_source": _fmt(snap.get("oil_temperature_source")),
        "oil_temperature_fallbacks": snap.get("oil_temperature_fallbacks", 0),
        "oil_temperature_lead_k": _fmt(snap.get("oil_temperature_lead_k")),
    }
    values.update(snap.get("flow_residual") or {})
    for k in _EVENTS:
        values[k] = counts.get(k, 0)
        values[k + "_last_period"] = delta.get(k, 0)
    if snap["last_summary"]:
        for k, v in snap["last_summary"].items():
            values["last_revolution_" + k] = v
    return m.diagnostic_status(level, MODEL_STATUS_NAME, msg, hardware_id="gerotor_twin", values=values)


def input_status(snap: dict, stale_timeout_s: float, delta: dict[str, int] | None = None) -> dict:
    """Status of the bench inputs: per input value, age, counters, last error.

    ``delta["rejected.<kind>"]``: rejections since the previous report (WARN if any);
    ``delta["zero_stamps.<kind>"]``: header stamps of 0 since then (WARN, named in the message).
    """
    delta = delta or {}
    level, problems = m.DIAG_OK, []
    values: dict[str, Any] = {}
    for kind, info in snap["inputs"].items():
        age = info["age_s"]
        values[f"{kind}.value_{INPUTS[kind].unit}"] = _fmt(info["value"])
        values[f"{kind}.age_s"] = _fmt(age)
        values[f"{kind}.accepted"] = info["accepted"]
        values[f"{kind}.clamped"] = info["clamped"]
        for reason, n in info["rejected"].items():
            values[f"{kind}.rejected.{reason}"] = n
        values[f"{kind}.lost"] = info.get("lost", 0)
        values[f"{kind}.missed_at_start"] = info.get("missed_at_start", 0)
        values[f"{kind}.stamp_restarts"] = info["stamp_restarts"]
        values[f"{kind}.stamp_rebases"] = info.get("stamp_rebases", 0)
        values[f"{kind}.zero_stamps"] = info.get("zero_stamps", 0)
        for key in ("sources_active", "sources_seen", "followed_source", "other_source_samples", "source_switches"):
            values[f"{kind}.{key}"] = _fmt(info.get(key))
        values[f"{kind}.last_error"] = info["last_error"]
        if kind in REQUIRED and (age is None or age > stale_timeout_s):
            level = max(level, m.DIAG_STALE if age is None else m.DIAG_WARN)
            problems.append(f"{kind} {'missing' if age is None else f'stale ({age:.3g} s)'}")
        if delta.get(f"rejected.{kind}", 0) or info.get("lost", 0):
            level = max(level, m.DIAG_WARN)
    bad = [f"{k}: {delta[f'rejected.{k}']} rejected ({i['last_error']})" for k, i in snap["inputs"].items()
           if delta.get(f"rejected.{k}", 0)]
    zero = [f"{k}: {delta[f'zero_stamps.{k}']} header stamps = 0 (unstamped: order not checked)"
            for k in snap["inputs"] if delta.get(f"zero_stamps.{k}", 0)]
    if zero:
        level = max(level, m.DIAG_WARN)
    bad += zero
    many = [f"{k}: {i['sources_active']} sources publishing (following source #{i['followed_source']}; "
            f"{i['other_source_samples']} samples of the others logged, not used)"
            for k, i in snap["inputs"].items() if (i.get("sources_active") or 0) > 1]
    if many:
        level = max(level, m.DIAG_WARN)
    bad += many
    lost = [f"{k}: {i['lost']} lost before reception ({delta.get(f'lost.{k}', 0)} in the last period)"
            for k, i in snap["inputs"].items() if i.get("lost", 0)]
    msg = "; ".join(problems + bad + lost) or "ok"
    return m.diagnostic_status(min(level, m.DIAG_STALE), INPUT_STATUS_NAME, msg, hardware_id="gerotor_twin",
                               values=values)
