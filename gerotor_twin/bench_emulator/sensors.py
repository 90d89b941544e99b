"""Sensor and actuator models of the emulated bench (all SI, discrete time, deterministic).

Every element is updated once per internal tick ``dt`` [s]; noise comes from
a :class:`numpy.random.Generator` the caller seeds, so a run is repeatable
bit for bit.
"""
from __future__ import annotations

import math
from bisect import bisect_right
from collections import deque
from dataclasses import asdict, dataclass

import numpy as np

__all__ = ["FirstOrderLag", "Encoder", "BenchSpec", "OilBath", "noise_streams", "oil_warmup"]


@dataclass(frozen=True)
class BenchSpec:
    """Everything that makes the emulated bench differ from the twin (SI units).

    Attributes
    ----------
    seed : int
        Seed of every noise source (numpy ``SeedSequence``).
    bearing : str
        Outer-gear model of the emulated pump ("short" = Method 1; the twin defaults to "mobility").
    clearance_factor : float
        Tooth-tip and lateral clearances of the emulated pump relative to ``config/pump.yaml`` [-].
    internal_rate_hz : float
        Tick rate of the emulator: model slices, sensor filters [Hz].
    speed_rate_hz, pressure_rate_hz, flow_rate_hz, temperature_rate_hz : float
        Publish rates of the bench topics [Hz] (divisors of ``internal_rate_hz``).
    motor_tau_s, valve_tau_s : float
        First-order response of the drive speed and of the delivery pressure valve to set-points [s].
    encoder_counts : int
        Shaft encoder counts per revolution (quadrature edges) [-].
    speed_window_s : float
        Encoder differencing window of the speed measurement [s].
    speed_bias_rad_s, speed_tau_s, speed_noise_rad_s : float
        Shaft-speed reading after the encoder: bias [rad/s], first-order lag [s] (0: none) and noise
        (standard deviation) [rad/s].
    pressure_tau_s, suction_tau_s : float
        Delivery and suction pressure transducer time constants [s].
    pressure_bias_pa : float
        Bias of the delivery pressure transducer [Pa].
    pressure_noise_pa, suction_noise_pa : float
        Standard deviation of transducer noise [Pa].
    ripple_impedance : float
        Delivery-line impedance turning flow ripple into pressure ripple [Pa·s/m³].
    ripple_dc_tau_s : float
        Time constant separating the ripple from the mean flow [s].
    suction_drop_pa : float
        Suction-line pressure drop at the top of the pump's range, ``range.max_speed_rpm`` (∝ speed²) [Pa].
    flow_tau_s : float
        Flow-meter time constant [s].
    flow_noise_rel, flow_noise_m3s : float
        Flow-meter noise: relative to the reading [-] and absolute [m³/s] (standard deviations).
    flow_bias_m3s : float
        Flow-meter bias [m³/s].
    flow_meter : str
        Where the flow meter reads (:mod:`gerotor_twin.hydraulics.meter`): ``delivery`` (the delivered flow at the
        delivery pressure) or ``atmospheric`` (a return-line meter: the same mass's volume at atmospheric pressure,
        ρ(p_d)/ρ(p_atm) of the emulated pump's oil more).
    temperature_start_c, temperature_end_c, temperature_warmup_tau_s : float
        Oil warm-up of the emulated bench: the true oil temperature (which the
        emulated pump runs at) rises from the start value towards the end value
        as T(t) = T_end − (T_end − T_start)·exp(−t/τ_warm) [°C, °C, s]
        (:func:`oil_warmup`).  A profile that sets ``oil_temperature_c`` replaces the
        end value by its set-point from that segment on, and the start value by the
        first segment's set-point if it has one (:class:`OilBath`); τ_warm stays.
    temperature_tau_s, temperature_noise_c, temperature_bias_c : float
        Thermometer time constant [s], noise [K] and bias [K].
    latency_s, latency_jitter_s : float
        Receive latency of the recorder (log time − stamp): fixed part and mean of an exponential [s].
    wear_clearance_factor_end : float
        Wear scenario: the clearance factor grows linearly from ``clearance_factor`` at
        ``wear_start_s`` to this value at the end of the run [-] (0 = no wear).
    wear_start_s : float
        Start of the wear [s].
    warmup_s : float
        Simulated run-in at the first set-point before recording starts [s].
    start_time_ns : int
        Time stamp of the first sample [ns since the epoch] (fixed, so files are regenerable).
    """
    seed: int = 20240601
    bearing: str = "short"
    clearance_factor: float = 1.10
    internal_rate_hz: float = 1000.0
    speed_rate_hz: float = 100.0
    pressure_rate_hz: float = 100.0
    flow_rate_hz: float = 20.0
    temperature_rate_hz: float = 5.0
    motor_tau_s: float = 0.15
    valve_tau_s: float = 0.08
    encoder_counts: int = 16384
    speed_window_s: float = 0.01
    speed_bias_rad_s: float = 0.0
    speed_tau_s: float = 0.0
    speed_noise_rad_s: float = 0.0
    pressure_tau_s: float = 0.5e-3
    suction_tau_s: float = 0.5e-3
    pressure_bias_pa: float = 0.0
    pressure_noise_pa: float = 2000.0
    suction_noise_pa: float = 300.0
    ripple_impedance: float = 1.0e8
    ripple_dc_tau_s: float = 0.02
    suction_drop_pa: float = 5000.0
    flow_tau_s: float = 0.2
    flow_noise_rel: float = 0.003
    flow_noise_m3s: float = 1.0e-6
    flow_bias_m3s: float = 0.0
    flow_meter: str = "delivery"
    temperature_start_c: float = 30.0
    temperature_end_c: float = 70.0
    temperature_warmup_tau_s: float = 90.0
    temperature_tau_s: float = 3.0
    temperature_noise_c: float = 0.05
    temperature_bias_c: float = 0.0
    latency_s: float = 0.3e-3
    latency_jitter_s: float = 0.2e-3
    warmup_s: float = 0.3
    wear_clearance_factor_end: float = 0.0
    wear_start_s: float = 0.0
    start_time_ns: int = 1_735_689_600_000_000_000   # 2025-01-01T00:00:00Z

    def __post_init__(self):
        from gerotor_twin.errors import InputError
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or not 0 <= self.seed < 2**63:
            raise InputError("seed", self.seed, "an integer in [0, 2^63)")
        if not (self.wear_clearance_factor_end == 0 or 0.5 <= self.wear_clearance_factor_end <= 2.0):
            raise InputError("wear_clearance_factor_end", self.wear_clearance_factor_end, "0 (no wear) or [0.5, 2]")
        if not (math.isfinite(self.wear_start_s) and self.wear_start_s >= 0):
            raise InputError("wear_start_s", self.wear_start_s, "[0, inf) s")
        from gerotor_twin.hydraulics.meter import FLOW_METERS
        if self.flow_meter not in FLOW_METERS:
            raise InputError("flow_meter", self.flow_meter, " | ".join(FLOW_METERS))

    def decimation(self, rate_hz: float, field: str) -> int:
        """Ticks per published sample for a topic rate [Hz]; InputError if not a divisor."""
        from gerotor_twin.errors import InputError
        n = self.internal_rate_hz / rate_hz if rate_hz > 0 else math.nan      # 0, negative, NaN: refused
        if not math.isfinite(n) or abs(n - round(n)) >= 1e-9 or round(n) < 1:
            raise InputError(field, rate_hz, f"a divisor of the internal rate {self.internal_rate_hz:g} Hz")
        return int(round(n))

    def as_dict(self) -> dict:
        return asdict(self)


def oil_warmup(t_s: float, start_c: float, end_c: float, tau_s: float) -> float:
    """True oil temperature of the emulated bench at time t [°C]: first-order warm-up.

    T(t) = T_end − (T_end − T_start)·exp(−t/τ): the sump heats up from the pump's
    losses and approaches the temperature where the cooler carries them away
    (a constant temperature for τ ≤ 0).
    """
    if tau_s <= 0:
        return float(start_c)
    return float(end_c - (end_c - start_c) * math.exp(-max(t_s, 0.0) / tau_s))


class OilBath:
    """True oil temperature of the emulated bench [°C] following a set-point through the sump's warm-up.

    The sump approaches the oil temperature set-point u(t) (piecewise linear, given by its break
    points) with the warm-up time constant τ: T' = (u − T)/τ, T(0) = ``start_c``, solved exactly
    on each piece; after the last break point u stays at its last value.  On a constant piece of
    length h from T_a: ``oil_warmup(h, T_a, u, τ)``; on a ramp of slope s from u_a:
    T = T_a·e + u_a·(1 − e) + s·(h − τ(1 − e)), e = exp(−h/τ).  A constant set-point from
    t = 0 therefore gives exactly the warm-up of :func:`oil_warmup`; τ ≤ 0: T = ``start_c``
    throughout (no warm-up, as :func:`oil_warmup`).

    Parameters
    ----------
    knots_t : sequence of float
        Break points of the set-point, increasing, from 0 [s].
    knots_u : sequence of float
        Set-point at those times [°C].
    start_c : float
        Oil temperature at t = 0 [°C].
    tau_s : float
        Warm-up time constant [s].
    """

    def __init__(self, knots_t, knots_u, start_c: float, tau_s: float):
        t, u = [], []
        for tk, uk in zip(list(knots_t) + [math.inf], list(knots_u) + [knots_u[-1]]):
            t.append(float(tk))
            u.append(float(uk))
            if len(u) >= 3 and u[-3] == u[-2] == u[-1]:     # one constant piece, not several
                del t[-2], u[-2]
        self.t, self.u, self.tau, self.start_c = t, u, float(tau_s), float(start_c)
        self.t_knot = [self.start_c]
        for i in range(len(t) - 2 if self.tau > 0 else 0):
            self.t_knot.append(self._piece(i, t[i + 1]))

    def _piece(self, i: int, x: float) -> float:
        ta, tb, ua, ub, temp = self.t[i], self.t[i + 1], self.u[i], self.u[i + 1], self.t_knot[i]
        h = x - ta
        if ua == ub:
            return oil_warmup(h, temp, ua, self.tau)
        s = (ub - ua) / (tb - ta)
        g = -math.expm1(-h / self.tau)       # 1 − e
        return temp * (1.0 - g) + ua * g + s * (h - self.tau * g)

    def __call__(self, t_s: float) -> float:
        """T(t) [°C] at time ``t_s`` [s] (≥ 0)."""
        if self.tau <= 0:
            return self.start_c
        i = min(max(bisect_right(self.t, t_s) - 1, 0), len(self.t) - 2)
        return self._piece(i, t_s)


class FirstOrderLag:
    """y' = (u − y)/τ, exact for input held over each tick.

    Parameters
    ----------
    tau_s : float
        Time constant [s] (0: no lag).
    dt_s : float
        Tick [s].
    y0 : float
        Initial output (units of the signal).
    """

    def __init__(self, tau_s: float, dt_s: float, y0: float):
        self.a = 1.0 - math.exp(-dt_s / tau_s) if tau_s > 0 else 1.0
        self.y = float(y0)

    def __call__(self, u: float) -> float:
        if self.a == 1.0:              # no lag: the input itself, exactly
            self.y = float(u)
        else:
            self.y += self.a * (u - self.y)
        return self.y


class Encoder:
    """Shaft speed from a quadrature encoder: count difference over a window.

    Parameters
    ----------
    counts : int
        Counts per revolution [-].
    window_ticks : int
        Differencing window in ticks [-].
    dt_s : float
        Tick [s].
    theta0 : float
        Shaft angle at start [rad]; the history is filled assuming ``omega0`` [rad/s].
    """

    def __init__(self, counts: int, window_ticks: int, dt_s: float, theta0: float, omega0: float):
        self.q = 2 * math.pi / counts
        self.window = window_ticks
        self.dt = dt_s
        self.hist = deque((math.floor((theta0 - omega0 * dt_s * (window_ticks - i)) / self.q)
                           for i in range(window_ticks + 1)), maxlen=window_ticks + 1)

    def __call__(self, theta: float) -> tuple[float, float]:
        """Add the angle after a tick; return (measured speed [rad/s], quantized angle in [0, 2π) [rad])."""
        c = math.floor(theta / self.q)
        self.hist.append(c)
        speed = (self.hist[-1] - self.hist[0]) * self.q / (self.window * self.dt)
        return speed, (c * self.q) % (2 * math.pi)


def noise_streams(seed: int, names: tuple[str, ...]) -> dict[str, np.random.Generator]:
    """One independent generator per noise source, all derived from ``seed``."""
    children = np.random.SeedSequence(seed).spawn(len(names))
    return {n: np.random.default_rng(s) for n, s in zip(names, children)}
