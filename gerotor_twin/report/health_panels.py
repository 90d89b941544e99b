"""The health monitor's plots of the report (``twin/health``, :mod:`gerotor_twin.twin.health`).

Two plots, for the first twin log that carries health updates: the estimated efficiency at the
monitor's reference point with its ±2σ band, its calibrated (healthy) value and the WARN / ERROR
thresholds; and the estimated leakage factor with its ±2σ band. The intervals the monitor spent
in WARN or ERROR are shaded in both, labelled with the fault the classifier named at their last update
(:func:`gerotor_twin.twin.health.alarm_records`); beside them, the fault timeline: a table of the alarms
with level, start, end, named fault and its probability (none when the monitor never left OK).
"""
from __future__ import annotations

import numpy as np

from ..twin.health import HEALTH_FIELDS, HealthSettings, alarm_records, fault_text
from .context import ReportContext
from .panels import Band, Column, Interval, Table, TimeSeries, Trace

__all__ = ["ts_health_efficiency", "ts_health_leakage", "fault_timeline"]

HEALTH = "Pump health (online estimate)"
ALARM_COLORS = {"WARN": "rgba(240,170,0,0.18)", "ERROR": "rgba(220,50,40,0.18)"}
F = {name: i for i, name in enumerate(HEALTH_FIELDS)}


def _health(ctx: ReportContext):
    """(twin, t [s], values (n, fields)) of the first twin with health updates inside the span, else None."""
    for twin in ctx.twins:
        if twin.health is None or len(twin.health[0]) == 0:
            continue
        t, v = twin.health
        keep = (t >= ctx.span[0]) & (t <= ctx.span[1])
        if keep.any():
            return twin, t[keep], v[keep]
    return None


def _setting(twin, name: str) -> float:
    """A health setting as logged in the twin's parameters (``health_<name>``), else the default."""
    raw = twin.parameters.get(f"health_{name}")
    try:
        return float(str(raw).strip("'\""))
    except (TypeError, ValueError):
        return float(getattr(HealthSettings(), name))


def _alarms(t: np.ndarray, v: np.ndarray) -> list[dict]:
    """The alarm records (:func:`~gerotor_twin.twin.health.alarm_records`) of the health updates ``v`` at ``t`` [s]."""
    return alarm_records(t, [dict(zip(HEALTH_FIELDS, row)) for row in v])


def _intervals(t: np.ndarray, v: np.ndarray) -> tuple[Interval, ...]:
    out = []
    for a in _alarms(t, v):
        named = fault_text(a["fault"], a["confidence"], a["rival"])
        out.append(Interval(a["start_s"], a["end_s"], a["level"] if named == "-" else f"{a['level']}: {named}",
                            ALARM_COLORS[a["level"]]))
    return tuple(out)


def ts_health_efficiency(ctx: ReportContext) -> TimeSeries | None:
    found = _health(ctx)
    if found is None:
        return None
    twin, t, v = found
    eta, sd = v[:, F["reference_efficiency"]] * 100, v[:, F["reference_efficiency_sd"]] * 100
    cal = v[:, F["calibrated_reference_efficiency"]] * 100
    traces = [Trace("estimated", t, eta, "#1f5fa8", 1.6, decimals=2),
              Trace("calibrated (healthy)", t, cal, "#2a8a3a", 1.2, (6, 3), decimals=2)]
    for name, color in (("warn_pt", "#c98a00"), ("error_pt", "#c0392b")):
        pt = _setting(twin, name)
        traces.append(Trace(f"{name.split('_')[0].upper()} threshold (−{pt:g} pt)", t, cal - pt, color, 1.0,
                            (2, 3), decimals=2))
    rpm, bar, oil = (_setting(twin, k) for k in ("reference_rpm", "reference_bar", "reference_oil_c"))
    return TimeSeries("ts-health-efficiency", HEALTH, "reference η_v [%]", tuple(traces),
                      f"Volumetric efficiency the twin infers for the pump in front of it at the reference point "
                      f"({rpm:g} rpm, {bar:g} bar g, {oil:g} °C oil), from the flow residual; blue band ±2σ. "
                      "Shaded: intervals the monitor spent in WARN (amber) or ERROR (red).",
                      (Band("±2σ", t, eta - 2 * sd, eta + 2 * sd, "rgba(31,95,168,0.15)", "rgba(31,95,168,0.5)"),),
                      intervals=_intervals(t, v))


def ts_health_leakage(ctx: ReportContext) -> TimeSeries | None:
    found = _health(ctx)
    if found is None:
        return None
    _, t, v = found
    k, sd = v[:, F["leakage_factor"]], v[:, F["leakage_factor_sd"]]
    return TimeSeries("ts-health-leakage", HEALTH, "leakage factor [-]", (
        Trace("estimated", t, k, "#1f5fa8", 1.6, decimals=3),
        Trace("clearance factor", t, v[:, F["clearance_factor"]], "#7a4fa0", 1.2, (6, 3), decimals=3)),
        "Leakage of the pump over the twin's (1 = as calibrated), blue band ±2σ; the clearance factor is the "
        "common tooth-tip and lateral clearance scaling that explains it, k^(1/n) with n ≈ 3 the loss exponent.",
        (Band("±2σ", t, k - 2 * sd, k + 2 * sd, "rgba(31,95,168,0.15)", "rgba(31,95,168,0.5)"),),
        intervals=_intervals(t, v))


def fault_timeline(ctx: ReportContext) -> Table | None:
    """The health monitor's alarms with the fault named at each one's last update and its probability (None
    without health updates or without an alarm)."""
    found = _health(ctx)
    if found is None:
        return None
    twin, t, v = found
    alarms = _alarms(t, v)
    if not alarms:
        return None
    cols = (Column("level", "{}", True), Column("from [s]", "{:.1f}"), Column("to [s]", "{:.1f}"),
            Column("fault named", "{}", True), Column("probability [-]", "{:.2f}"))
    rows = tuple((a["level"], a["start_s"], a["end_s"], fault_text(a["fault"], None, a["rival"]), a["confidence"])
                 for a in alarms)
    return Table("tab-fault-timeline", HEALTH, cols, rows, f"{ctx.stem}_fault_timeline.csv",
                 "Each interval the monitor spent in WARN or ERROR (times as in the plots) with the fault the "
                 "classifier named at its last update (healthy, a fault kind, or unknown: no kind explains the "
                 "residuals, or one operating point only; 'a or b': a tentative naming, a not yet told apart "
                 "from b at the operating points seen) and its probability (for unknown: that of a fault); '-': the "
                 "log carries no diagnosis.", f"Fault timeline ({twin.label})")
