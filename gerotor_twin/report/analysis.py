"""Align bench and twin series on one time grid, find steady plateaus, compute error metrics.

Definitions (SI inside; the HTML shows L/min, bar and %):

* **Grid**: uniform, ``dt`` [s] (default 0.1 s) over the common span; each
  series is averaged in the grid bins (bins without samples are
  interpolated), so sensor noise and the twin's per-revolution summaries are
  compared on the same footing.
* **Plateau**: a stretch where the bench's speed and delivery pressure
  (``smooth_s`` moving mean, 0.5 s) move less than ``speed_tol_rpm_s``
  (15 rpm/s) and ``pressure_tol_bar_s`` (0.3 bar/s); its first ``settle_s``
  (1 s: drive, valve and flow-meter settling) and last bin are dropped, and
  what is left must last ``min_s`` (1.5 s) or more.
* **Errors** are predicted − measured: mean delivery flow [m³/s] on the grid,
  and volumetric efficiency η_v [-] (measured: measured flow / (displacement ×
  measured speed / 2π)).  Per plateau and overall (all plateau samples):
  bias (mean error), RMSE, maximum absolute error; ``whole_run`` uses every
  grid sample (transients included, so flow-meter lag shows).
* **Flow meter lag** (``flow_sensor_tau_s`` > 0, ``report --flow-sensor-tau``): the twin's flow is compared
  as the bench's meter would read it, through a first-order lag of that time constant
  (:func:`read_through_lag`), so a plateau that starts before a slow meter has settled is not judged on
  the meter's lag.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..units import P_ATM, pa_abs_to_bar_gauge, rad_s_to_rpm
from .data import BenchData, TwinData

__all__ = ["Grid", "Plateau", "make_grid", "find_plateaus", "error_stats", "compare", "read_through_lag"]


@dataclass
class Grid:
    """Bench series averaged on a uniform grid."""
    t: np.ndarray          #: bin centres [s]
    omega: np.ndarray      #: [rad/s]
    p_delivery: np.ndarray  #: [Pa abs]
    q_meas: np.ndarray     #: measured delivery flow [m³/s]


@dataclass
class Plateau:
    """A steady operating point: grid index range [i0, i1) and its means."""
    index: int
    i0: int
    i1: int
    t0: float
    t1: float
    rpm: float
    bar: float


def binned(t: np.ndarray, v: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Mean of ``v`` in each bin of ``edges``; empty bins interpolated (ends held) [units of v]."""
    idx = np.searchsorted(edges, t, side="right") - 1
    n = edges.size - 1
    ok = (idx >= 0) & (idx < n) & np.isfinite(v)
    s = np.bincount(idx[ok], weights=v[ok], minlength=n)
    c = np.bincount(idx[ok], minlength=n)
    centres = 0.5 * (edges[:-1] + edges[1:])
    out = np.full(n, np.nan)
    out[c > 0] = s[c > 0] / c[c > 0]
    good = c > 0
    if good.any() and not good.all():
        out[~good] = np.interp(centres[~good], centres[good], out[good])
    return out


def make_grid(bench: BenchData, span: tuple[float, float], dt: float = 0.1) -> Grid:
    """Bench series on a grid of ``dt`` [s] over ``span`` [s]."""
    n = max(1, int(math.floor((span[1] - span[0]) / dt)))
    edges = span[0] + dt * np.arange(n + 1)
    return Grid(t=0.5 * (edges[:-1] + edges[1:]), omega=binned(*bench.speed, edges),
                p_delivery=binned(*bench.delivery_pressure, edges), q_meas=binned(*bench.flow, edges))


def plateau_temperatures(bench: BenchData, grid: Grid, plateaus: list[Plateau]) -> list[float | None]:
    """Mean bench oil temperature [°C] over each plateau (None without ``/bench/oil_temperature``)."""
    if bench.temperature is None or grid.t.size == 0:
        return [None] * len(plateaus)
    dt = grid.t[1] - grid.t[0] if grid.t.size > 1 else 0.1
    edges = np.concatenate([grid.t - dt / 2, [grid.t[-1] + dt / 2]])
    temp = binned(*bench.temperature, edges)
    out = []
    for p in plateaus:
        v = temp[p.i0:p.i1]
        v = v[np.isfinite(v)]
        out.append(float(v.mean()) if v.size else None)
    return out


def meter_expansion(grid: Grid, plateaus: list[Plateau], temps: list[float | None], config) -> np.ndarray:
    """Per grid bin, ρ(p_d)/ρ(p_atm) of the twin's oil (:mod:`gerotor_twin.hydraulics.meter`): the factor on the
    twin's delivery flow that a flow meter at atmospheric pressure reads, at the bin's delivery pressure and its
    plateau's oil temperature (the config's reference temperature outside the plateaus)."""
    from gerotor_twin.hydraulics.meter import expansion, oil_state_equation
    t_bin = np.full(grid.t.shape, np.nan)
    for p, tc in zip(plateaus, temps):
        if tc is not None:
            t_bin[p.i0:p.i1] = tc + 273.15
    out = np.ones(grid.t.shape)
    p_atm = config.fluid.atmospheric_pa
    for t_k in {None if not np.isfinite(t) else float(t) for t in t_bin}:
        eos = oil_state_equation(config, t_k)
        at = ~np.isfinite(t_bin) if t_k is None else t_bin == t_k
        for i in np.flatnonzero(at & np.isfinite(grid.p_delivery)):
            out[i] = expansion(float(grid.p_delivery[i]), p_atm, eos)
    return out


def add_temperatures(comp: dict, temps: list[float | None]) -> dict:
    """Put each plateau's oil temperature [°C] (``oil_temperature_c``) into the rows of a :func:`compare` result."""
    for row, tc in zip(comp["plateaus"], temps):
        row["oil_temperature_c"] = tc
    return comp


def on_grid(grid: Grid, t: np.ndarray, v: np.ndarray) -> np.ndarray:
    """A twin series averaged on ``grid``'s bins."""
    dt = grid.t[1] - grid.t[0] if grid.t.size > 1 else 0.1
    edges = np.concatenate([grid.t - dt / 2, [grid.t[-1] + dt / 2]])
    return binned(t, v, edges)


def _smooth(v: np.ndarray, n: int) -> np.ndarray:
    if n <= 1:
        return v.copy()
    k = np.ones(n) / n
    pad = np.concatenate([np.full(n // 2, v[0]), v, np.full(n - 1 - n // 2, v[-1])])
    return np.convolve(pad, k, mode="valid")


def find_plateaus(grid: Grid, *, min_s: float = 1.5, settle_s: float = 1.0, speed_tol_rpm_s: float = 15.0,
                  pressure_tol_bar_s: float = 0.3, smooth_s: float = 0.5, p_atm: float = P_ATM) -> list[Plateau]:
    """Steady stretches of the bench's speed and delivery pressure (see module doc); gauge zero ``p_atm`` [Pa]."""
    t = grid.t
    if t.size < 3:
        return []
    dt = t[1] - t[0]
    n = max(1, int(round(smooth_s / dt)))
    rpm = _smooth(rad_s_to_rpm(grid.omega), n)
    bar = _smooth(pa_abs_to_bar_gauge(grid.p_delivery, p_atm), n)
    drpm = np.abs(np.gradient(rpm, dt))
    dbar = np.abs(np.gradient(bar, dt))
    steady = (drpm < speed_tol_rpm_s) & (dbar < pressure_tol_bar_s)
    bad = ~steady
    out, i = [], 0
    while i < t.size:
        if bad[i]:
            i += 1
            continue
        j = i
        while j < t.size and not bad[j]:
            j += 1
        a = i + int(round(settle_s / dt))
        b = j - 1
        if (b - a) * dt >= min_s:
            w = rad_s_to_rpm(grid.omega[a:b])
            p = pa_abs_to_bar_gauge(grid.p_delivery[a:b], p_atm)
            out.append(Plateau(len(out) + 1, a, b, float(t[a] - dt / 2), float(t[b - 1] + dt / 2),
                               float(np.mean(w)), float(np.mean(p))))
        i = j
    return out


def error_stats(err: np.ndarray) -> dict:
    """Bias, RMSE and maximum absolute value of an error array (NaNs ignored)."""
    e = err[np.isfinite(err)]
    if e.size == 0:
        return {"bias": None, "rmse": None, "max_abs": None, "n": 0}
    return {"bias": float(e.mean()), "rmse": float(np.sqrt(np.mean(e ** 2))), "max_abs": float(np.abs(e).max()),
            "n": int(e.size)}


def read_through_lag(t: np.ndarray, v: np.ndarray, tau: float) -> np.ndarray:
    r"""The series ``v`` (samples at ``t`` [s], each the mean over the interval that ends at its time, as the
    twin's revolution summaries are) as a first-order-lag sensor of time constant ``tau`` [s] reads it:

    .. math:: y_k = v_k + (y_{k-1} - v_k)\, e^{-(t_k - t_{k-1})/\tau},\qquad y_0 = v_0

    exact for v held over each interval (:math:`\tau \dot y = v - y`); ``tau`` ≤ 0 returns ``v``.
    """
    from gerotor_twin.hydraulics.meter import lag_step
    v = np.asarray(v, dtype=float)
    if not tau > 0 or v.size == 0:
        return v
    dt = np.diff(np.asarray(t, dtype=float))
    y = np.empty_like(v)
    y[0] = v[0]
    for k in range(1, v.size):
        y[k] = lag_step(y[k - 1], v[k], dt[k - 1], tau)
    return y


def compare(grid: Grid, plateaus: list[Plateau], twin: TwinData, displacement_m3: float,
            flow_sensor_tau_s: float = 0.0, meter_expansion: np.ndarray | None = None) -> dict:
    """Metrics of one twin against the bench; with ``flow_sensor_tau_s`` > 0 [s] the twin's flow as the bench's
    meter reads it (:func:`read_through_lag`), its η_v from that flow; with ``meter_expansion`` (per grid bin,
    :func:`meter_expansion`) the twin's flow and η_v as a meter at another pressure reads them.

    Returns
    -------
    dict
        ``q_pred`` and ``eta_pred`` on the grid, ``plateaus`` (per plateau: rpm, bar, measured and
        predicted mean flow [m³/s] and η_v [-], flow and η_v error stats), ``overall`` (all
        plateau samples) and ``whole_run`` (every grid sample) error stats.
    """
    ts, v = twin.summary
    if flow_sensor_tau_s > 0:
        q_read = read_through_lag(ts, v[:, 0], flow_sensor_tau_s)
        q_pred = on_grid(grid, ts, q_read)
        with np.errstate(divide="ignore", invalid="ignore"):
            eta_pred = on_grid(grid, ts, np.where(v[:, 1] > 0, q_read / v[:, 1], np.nan))
    else:
        q_pred = on_grid(grid, ts, v[:, 0])
        eta_pred = on_grid(grid, ts, v[:, 3])
    qth_meas = displacement_m3 * grid.omega / (2 * math.pi)
    with np.errstate(divide="ignore", invalid="ignore"):
        eta_meas = np.where(qth_meas > 0, grid.q_meas / qth_meas, np.nan)
    if meter_expansion is not None:
        q_pred = q_pred * meter_expansion
        eta_pred = eta_pred * meter_expansion
    # the twin has no prediction outside its own span: blank those bins
    outside = (grid.t < ts.min()) | (grid.t > ts.max())
    q_pred[outside] = np.nan
    eta_pred[outside] = np.nan
    err_q = q_pred - grid.q_meas
    err_eta = eta_pred - eta_meas
    rows, sel = [], []
    for p in plateaus:
        s = slice(p.i0, p.i1)
        sel.append(np.arange(p.i0, p.i1))
        rows.append({"plateau": p.index, "t0_s": p.t0, "t1_s": p.t1, "rpm": p.rpm, "bar": p.bar, "bins": p.i1 - p.i0,
                     "flow_measured_m3s": float(np.nanmean(grid.q_meas[s])),
                     "flow_predicted_m3s": _nanmean(q_pred[s]),
                     "eta_measured": _nanmean(eta_meas[s]), "eta_predicted": _nanmean(eta_pred[s]),
                     "flow_error_m3s": error_stats(err_q[s]), "eta_error": error_stats(err_eta[s])})
    idx = np.concatenate(sel) if sel else np.array([], dtype=int)
    return {"label": twin.label, "path": twin.path, "q_pred": q_pred, "eta_pred": eta_pred, "eta_meas": eta_meas,
            "plateaus": rows,
            "overall": {"flow_error_m3s": error_stats(err_q[idx]), "eta_error": error_stats(err_eta[idx])},
            "whole_run": {"flow_error_m3s": error_stats(err_q)}}


def _nanmean(v: np.ndarray) -> float | None:
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else None


def revolution_phase(twin: TwinData, displacement_m3: float, t: np.ndarray) -> np.ndarray:
    """Shaft angle within the revolution [rad] at times ``t`` [s], from the revolution-end stamps.

    The twin stamps each ``flow_summary`` at the end of a whole revolution, so between two
    consecutive stamps one revolution apart (checked against the revolution time
    displacement / theoretical flow, within 2 %) the angle runs from 0 to 2π (constant
    speed within a revolution); other times get NaN.
    """
    ts, v = twin.summary
    k = np.searchsorted(ts, t, side="right")
    ok = (k > 0) & (k < ts.size)
    out = np.full(t.shape, np.nan)
    kk = k[ok]
    a, b = ts[kk - 1], ts[kk]
    with np.errstate(divide="ignore", invalid="ignore"):
        period = displacement_m3 / v[kk, 1]
        one_rev = np.abs((b - a) - period) < 0.02 * period
    ph = 2 * math.pi * (t[ok] - a) / (b - a)
    out[ok] = np.where(one_rev, ph, np.nan)
    return out
