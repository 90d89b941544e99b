"""The interactive time plots of the report, one function per plot: ``ReportContext -> TimeSeries | None``.

To add a plot, write such a function and list it in :data:`layout.PAGE`; a trace with
``csv="name [unit]"`` on the report grid also becomes a column of the aligned-series CSV.
:func:`bench_panel` makes the usual "raw bench samples under their 0.1 s means" plot in one call.
"""
from __future__ import annotations

import numpy as np

from ..units import pa_abs_to_bar_gauge, rad_s_to_rpm
from .analysis import on_grid
from .context import BENCH_RAW, MEASURED, ReportContext
from .panels import Band, TimeSeries, Trace, plateau_steps

__all__ = ["bench_panel", "ts_speed", "ts_pressure", "ts_flow", "ts_residual", "ts_efficiency"]

LPM = 6e4
OPERATING = "Operating point over time"
FLOW = "Delivery flow: measured vs predicted"


def bench_panel(ctx: ReportContext, panel_id: str, heading: str, y_label: str, series, convert,
                name: str, caption: str = "", decimals: int = 2) -> TimeSeries | None:
    """Raw bench samples (light) under their means on the report grid (dark, in the CSV).

    Parameters
    ----------
    series : tuple of arrays or None
        ``(t [s], v [SI])`` as in :class:`data.BenchData`; ``None``: no plot.
    convert : callable
        SI -> display units (e.g. :func:`units.rad_s_to_rpm`).
    name : str
        Quantity name for the legend and CSV column; the unit comes from ``y_label``'s brackets.
    """
    if series is None or len(series[0]) == 0:
        return None
    t, v = ctx.in_span(*series)
    unit = y_label[y_label.rfind("["):] if "[" in y_label else ""
    mean = convert(on_grid(ctx.grid, *series))
    return TimeSeries(panel_id, heading, y_label, (
        Trace("bench raw", t, convert(v), BENCH_RAW, 1.0, raw=True, decimals=decimals),
        Trace(f"{ctx.grid_dt:g} s mean", ctx.grid.t, mean, "#111111", 1.6, csv=f"{name} {unit}".strip(),
              decimals=decimals)), caption)


def ts_speed(ctx: ReportContext) -> TimeSeries | None:
    return bench_panel(ctx, "ts-speed", OPERATING, "shaft speed [rpm]", ctx.bench.speed, rad_s_to_rpm,
                       "speed", "Bench shaft speed: raw samples and 0.1 s means; grey: detected plateaus.", 1)


def ts_pressure(ctx: ReportContext) -> TimeSeries | None:
    p_atm = ctx.config.fluid.atmospheric_pa
    return bench_panel(ctx, "ts-pressure", OPERATING, "delivery pressure [bar g]", ctx.bench.delivery_pressure,
                       lambda p: pa_abs_to_bar_gauge(p, p_atm), "delivery pressure",
                       "Bench delivery pressure (gauge): raw samples and 0.1 s means.", 3)


def ts_oil_temperature(ctx: ReportContext) -> TimeSeries | None:
    return bench_panel(ctx, "ts-oil-temperature", OPERATING, "oil temperature [°C]", ctx.bench.temperature,
                       lambda c: c, "oil temperature",                       # sensor_msgs/Temperature: °C
                       "Bench oil temperature: raw samples and 0.1 s means (the twin's oil properties follow "
                       "it, docs/fluid.md); none when the bag has no /bench/oil_temperature.", 1)


def _flow_tolerance(ctx: ReportContext) -> Band | None:
    rows = ctx.comps[0]["plateaus"] if ctx.comps else []
    tols = [v["flow_tol_m3s"] for v in ctx.verdicts[0]] if ctx.verdicts else []
    if not rows or all(t is None for t in tols):
        return None
    t, lo = plateau_steps(ctx.plateaus, [None if tol is None else (r["flow_measured_m3s"] - tol) * LPM
                                         for r, tol in zip(rows, tols)])
    _, hi = plateau_steps(ctx.plateaus, [None if tol is None else (r["flow_measured_m3s"] + tol) * LPM
                                         for r, tol in zip(rows, tols)])
    return Band("tolerance", t, lo, hi)


def ts_flow(ctx: ReportContext) -> TimeSeries:
    t, q = ctx.in_span(*ctx.bench.flow)
    traces = [Trace("flow meter raw", t, q * LPM, BENCH_RAW, 1.0, raw=True),
              Trace("measured, 0.1 s mean", ctx.grid.t, ctx.grid.q_meas * LPM, MEASURED, 1.6,
                    csv="flow measured [L/min]")]
    for i, c in enumerate(ctx.comps):
        traces.append(Trace(f"predicted: {c['label']}", ctx.grid.t, c["q_pred"] * LPM, width=1.4,
                            csv=f"flow predicted {c['label']} [L/min]", **ctx.twin_style(i)))
    band = _flow_tolerance(ctx)
    return TimeSeries("ts-flow", FLOW, "mean delivery flow [L/min]", tuple(traces),
                      "Flow meter samples (light), their 0.1 s means and the twin's revolution means on the same "
                      "grid; green band: the acceptance tolerance about the measured plateau mean.",
                      (band,) if band else (), height=300)


def ts_residual(ctx: ReportContext) -> TimeSeries:
    traces = tuple(Trace(c["label"], ctx.grid.t, (c["q_pred"] - ctx.grid.q_meas) * LPM, width=1.2,
                         csv=f"flow error {c['label']} [L/min]", **ctx.twin_style(i))
                   for i, c in enumerate(ctx.comps))
    tols = [v["flow_tol_m3s"] for v in ctx.verdicts[0]] if ctx.verdicts else []
    bands = ()
    if tols and any(x is not None for x in tols):
        t, hi = plateau_steps(ctx.plateaus, [None if x is None else x * LPM for x in tols])
        bands = (Band("tolerance", t, -hi, hi),)
    return TimeSeries("ts-residual", FLOW, "pred − meas [L/min]", traces,
                      "Flow error on the 0.1 s grid (transients show the flow meter's lag); green: tolerance.",
                      bands, height=240, zero_line=True)


def ts_efficiency(ctx: ReportContext) -> TimeSeries:
    traces = [Trace("measured", ctx.grid.t, ctx.comps[0]["eta_meas"] * 100, MEASURED, 1.4,
                    csv="volumetric efficiency measured [%]", decimals=2)] if ctx.comps else []
    for i, c in enumerate(ctx.comps):
        traces.append(Trace(f"predicted: {c['label']}", ctx.grid.t, c["eta_pred"] * 100, width=1.3,
                            csv=f"volumetric efficiency predicted {c['label']} [%]", decimals=2,
                            **ctx.twin_style(i)))
    bands = ()
    etol = ctx.criterion.eta_tolerance()
    if etol is not None and ctx.comps:
        rows = ctx.comps[0]["plateaus"]
        mid = [None if r["eta_measured"] is None else r["eta_measured"] * 100 for r in rows]
        t, lo = plateau_steps(ctx.plateaus, [None if m is None else m - etol * 100 for m in mid])
        _, hi = plateau_steps(ctx.plateaus, [None if m is None else m + etol * 100 for m in mid])
        bands = (Band("tolerance", t, lo, hi),)
    return TimeSeries("ts-efficiency", FLOW, "volumetric efficiency [%]", tuple(traces),
                      "Measured η_v = measured flow / (displacement × measured speed / 2π) and the twin's, on the "
                      "0.1 s grid (meaningless in transients: the flow meter lags); green: tolerance.",
                      bands, height=240)


def plateau_index(ctx: ReportContext) -> np.ndarray:
    """Plateau number of every grid bin (0: not in a plateau), for the aligned CSV."""
    out = np.zeros(ctx.grid.t.size, dtype=int)
    for p in ctx.plateaus:
        out[p.i0:p.i1] = p.index
    return out
