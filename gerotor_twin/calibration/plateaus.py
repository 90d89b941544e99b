"""Steady plateaus of a bench recording as records a fit can use (the report's detector).

One :class:`PlateauRecord` per steady stretch found by
:func:`gerotor_twin.report.analysis.find_plateaus` on the bench series averaged on
a 0.1 s grid: the mean measured speed, delivery and suction pressure, oil
temperature and delivery flow over the plateau, and the standard error of the
mean flow (bin scatter, or batch means when larger).  SI units throughout.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

import numpy as np

from ..report.analysis import binned, find_plateaus, make_grid
from ..report.data import load_bench
from ..units import pa_abs_to_bar_gauge, rad_s_to_rpm

__all__ = ["PlateauRecord", "DetectorSettings", "bench_plateaus", "lag_undone_mean", "split_by_envelope",
           "thermometer_lag_note"]

#: Oil warming or cooling on a plateau beyond which an unset thermometer lag is worth a note [K/s].
OIL_DRIFT_NOTE_K_S = 0.05


@dataclass(frozen=True)
class DetectorSettings:
    """Plateau detector settings (see :func:`~gerotor_twin.report.analysis.find_plateaus`)."""
    grid_s: float = 0.1          #: bin width [s]
    min_s: float = 1.5           #: shortest plateau kept, after settling [s]
    settle_s: float = 1.0        #: dropped at the start of each plateau (drive, valve, flow meter) [s]
    oil_sensor_tau_s: float = 0.0  #: oil thermometer lag [s]: plateau mean + τ × slope of the readings
    flow_sensor_tau_s: float = 0.0  #: flow meter lag [s]: each plateau's mean flow with it undone (:func:`lag_undone_mean`)


@dataclass(frozen=True)
class PlateauRecord:
    """One steady operating point measured on the bench (means over the plateau, SI)."""
    bag: str                     #: recording path
    index: int                   #: plateau number in the recording (1-based)
    t0_s: float                  #: start, relative to the recording's first message [s]
    t1_s: float                  #: end [s]
    omega: float                 #: mean shaft speed [rad/s]
    p_delivery_pa: float         #: mean delivery pressure [Pa abs]
    p_suction_pa: float          #: mean suction pressure [Pa abs] (NaN: not recorded)
    oil_temperature_c: float     #: mean oil temperature [°C] (NaN: not recorded)
    flow_m3s: float              #: mean measured delivery flow [m³/s]
    flow_sem_m3s: float          #: standard error of that mean (see :func:`mean_standard_error`) [m³/s]
    bins: int                    #: grid bins averaged [-]
    oil_slope_k_s: float = math.nan  #: least-squares slope of the oil reading over the plateau [K/s] (NaN: none)

    @property
    def rpm(self) -> float:
        return rad_s_to_rpm(self.omega)

    def bar(self, p_atm: float) -> float:
        """Delivery gauge pressure [bar] against ``p_atm`` [Pa]."""
        return float(pa_abs_to_bar_gauge(self.p_delivery_pa, p_atm))

    def label(self) -> str:
        return f"{self.bag.rsplit('/', 1)[-1]}#{self.index}"

    def as_dict(self) -> dict:
        return asdict(self)


def mean_standard_error(v: np.ndarray, dt: float, batch_s: float = 0.5) -> float:
    """Standard error of the mean of a binned series [units of v], robust to correlated noise.

    The larger of the bin scatter / √bins and the batch-means estimate (batches of ``batch_s``
    [s], at least 3): slow components (aliased flow ripple, a meter's drift) correlate
    neighbouring bins, which the bin scatter alone would miss.
    """
    v = v[np.isfinite(v)]
    if v.size < 2:
        return math.nan
    sem = float(v.std(ddof=1) / math.sqrt(v.size))
    k = max(1, int(round(batch_s / dt)))
    nb = v.size // k
    if nb >= 3:
        means = v[:nb * k].reshape(nb, k).mean(axis=1)
        sem = max(sem, float(means.std(ddof=1) / math.sqrt(nb)))
    return sem


def lag_undone_mean(v: np.ndarray, dt: float, tau: float) -> tuple[float, float]:
    r"""Mean over a plateau of a quantity read through a first-order lag of time constant ``tau`` [s], from the
    readings' bin means ``v`` (consecutive bins of ``dt`` [s]); and that mean's standard error [units of v].

    A sensor with :math:`\tau \dot y = u - y` reads y for the quantity u.  For a weight w(t) on the plateau
    [a, b] that vanishes at both ends, integrating by parts,

    .. math::
        \int_a^b w\,u\,dt = \int_a^b \left(w - \tau \dot w\right) y\,dt

    exactly, whatever u did (a step the sensor has not followed yet, a ramp it lags by τ·u̇), and without the
    readings at the edges, which are single noisy samples.  w is a trapezoid: rising over the first quarter
    of the plateau, flat, falling over the last quarter (symmetric, so the weighted mean of a steady quantity
    or of a linear drift is its plain mean); the estimate is :math:`\sum_k c_k v_k` with
    :math:`c_k = (w_k - \tau \dot w_k)/\sum_k w_k` on the bin centres.  Its standard error is the plain
    mean's (:func:`mean_standard_error`) × :math:`\sqrt{n \sum_k c_k^2}`, the ratio of the two estimators'
    variances for uncorrelated bins.  ``tau`` = 0: the plain mean.

    Notes
    -----
    Exact for a first-order lag up to the bins' midpoint rule (O(dt²)); a sensor that is not one (a dead
    time, a second-order response) leaves a residual that the plateau's settling (``settle_s``) must still
    cover.  The derivative weight τ·ẇ grows as the plateau shortens: with τ comparable to the plateau, the
    estimate is unbiased but noisy, and its standard error says so.
    """
    v = np.asarray(v, dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return math.nan, math.nan
    mean, sem = float(v.mean()), mean_standard_error(v, dt)
    n = v.size
    if not tau > 0 or n < 3:
        return mean, sem
    m = max(1, n // 4)                                   # bins in each taper
    k = np.arange(n) + 0.5
    w = np.minimum(1.0, np.minimum(k, n - k) / m)
    dw = np.where(k < m, 1.0, np.where(k > n - m, -1.0, 0.0)) / (m * dt)
    c = (w - tau * dw) / w.sum()
    return float(c @ v), sem * math.sqrt(n * float(c @ c))


def _mean_on(series, edges: np.ndarray, a: int, b: int) -> float:
    if series is None or len(series[0]) == 0:
        return math.nan
    v = binned(series[0], series[1], edges)[a:b]
    v = v[np.isfinite(v)]
    return float(v.mean()) if v.size else math.nan


def _oil_on(series, t0: float, t1: float, tau: float) -> tuple[float, float]:
    """(Mean oil reading over [t0, t1] [°C] plus ``tau`` × its least-squares slope, that slope [K/s]): the
    thermometer's lag undone, as the node's ``oil_sensor_tau_s`` (:mod:`gerotor_twin.twin.oil_temperature`)."""
    from gerotor_twin.twin.oil_temperature import least_squares_slope
    if series is None or len(series[0]) == 0:
        return math.nan, math.nan
    t, v = np.asarray(series[0]), np.asarray(series[1])
    keep = (t >= t0) & (t <= t1) & np.isfinite(v)
    if not keep.any():
        return math.nan, math.nan
    slope = least_squares_slope(t[keep], v[keep])
    return float(v[keep].mean()) + (tau * slope if tau > 0 else 0.0), slope


def bench_plateaus(path, settings: DetectorSettings = DetectorSettings()) -> list[PlateauRecord]:
    """Detect the steady plateaus of one bench recording and average the bench series on each.

    Raises
    ------
    McapReadError
        As :func:`gerotor_twin.report.data.load_bench` (missing topics, corrupt file).
    """
    bench = load_bench(path)
    grid = make_grid(bench, bench.span, settings.grid_s)
    plateaus = find_plateaus(grid, min_s=settings.min_s, settle_s=settings.settle_s)
    dt = settings.grid_s
    edges = np.concatenate([grid.t - dt / 2, [grid.t[-1] + dt / 2]])
    out = []
    for p in plateaus:
        q = grid.q_meas[p.i0:p.i1]
        q = q[np.isfinite(q)]
        flow, sem = lag_undone_mean(q, dt, settings.flow_sensor_tau_s)
        oil, slope = _oil_on(bench.temperature, edges[p.i0], edges[p.i1], settings.oil_sensor_tau_s)
        out.append(PlateauRecord(
            bag=str(path), index=p.index, t0_s=p.t0, t1_s=p.t1,
            omega=float(np.mean(grid.omega[p.i0:p.i1])), p_delivery_pa=float(np.mean(grid.p_delivery[p.i0:p.i1])),
            p_suction_pa=_mean_on(bench.suction_pressure, edges, p.i0, p.i1),
            oil_temperature_c=oil, flow_m3s=flow, flow_sem_m3s=sem, bins=int(q.size),
            oil_slope_k_s=slope))
    return out


def split_by_envelope(records, config) -> tuple[list, list[tuple[object, str]]]:
    """The plateaus inside the input envelope of the pump ``config`` (:func:`gerotor_twin.model.records.check_inputs`,
    the twin's own check) and those outside it, each with the reason (field, value, allowed range): a plateau a
    biased sensor reads just beyond the pump's top pressure is left out with that line, not fitted.
    ``records``: :class:`PlateauRecord` (or anything with ``omega``, ``p_suction_pa``, ``p_delivery_pa`` and
    ``oil_temperature_c``, SI and °C; NaN: not measured)."""
    from ..errors import InputError
    from ..model.records import Inputs, check_inputs
    from ..units import celsius_to_kelvin
    kept, out = [], []
    for r in records:
        ps = r.p_suction_pa if math.isfinite(r.p_suction_pa) else config.boundary.suction_pressure_pa
        oil = celsius_to_kelvin(r.oil_temperature_c) if math.isfinite(r.oil_temperature_c) else None
        try:
            check_inputs(config, Inputs(r.omega, ps, r.p_delivery_pa, oil))
            kept.append(r)
        except InputError as exc:
            out.append((r, str(exc)))
    return kept, out


def thermometer_lag_note(records, tau_s: float) -> str | None:
    """One line for the user when the oil reading drifts on the plateaus and no thermometer lag is set.

    A thermometer with time constant τ reads τ × the warming rate behind the oil; the leakage
    follows the true temperature (μ falls ≈ 3 %/K for a VG46 near 50 °C), so an unset lag biases
    fitted clearances (measured: +0.6 % on the clearance factor of an emulated bench warming at
    0.1–0.37 K/s with a 3 s thermometer, docs/calibration_health.md).

    Parameters
    ----------
    records : sequence of dict
        Plateaus as stored in a calibration result (``PlateauRecord.as_dict``), with ``oil_slope_k_s`` [K/s].
    tau_s : float
        The thermometer lag already undone [s] (``--oil-sensor-tau``); > 0: no note.
    """
    if tau_s > 0:
        return None
    slopes = [abs(r["oil_slope_k_s"]) for r in records if math.isfinite(r["oil_slope_k_s"])]
    if not slopes or max(slopes) < OIL_DRIFT_NOTE_K_S:
        return None
    fast = max(slopes)
    return (f"note: the oil reading drifts by up to {fast:.2f} K/s on the plateaus; a thermometer lagging by τ "
            f"reads τ × that behind (3 s: {3 * fast:.1f} K). If yours lags, pass --oil-sensor-tau τ [s]")
