r"""Steady plateaus of a bench pump without a time-resolved recording (fast known truth for calibration tests).

A plateau of a ``synth-bench --bench-pump F`` recording is, once the drive, the valve and the sensors have
settled, the emulated pump's periodic steady state at the plateau's speed, pressures and oil temperature,
read through biased and noisy sensors.  This module computes exactly that, without the 1 kHz emulation
between plateaus (a 20 s recording takes ≈ 45 s to synthesize on the dev machine, a steady plateau
≈ 0.1 s):

* **truth**: the emulated pump (:func:`gerotor_twin.bench_emulator.emulator.emulated_config`: the bench
  pump's form deviations, the emulator's finer numerics and its outer-gear model ``spec.bearing``) at the
  true speed ω, delivery pressure p_d, suction pressure p_s = p_atm − Δp_s (ω/ω_max)² (the bench's
  suction line, ``spec.suction_drop_pa``) and oil temperature T;
* **readings** (what a plateau record of the recording holds): ω + b_ω, p_d + b_p, T + b_T and the mean
  flow Q + b_Q + ε, each ``b`` the bench pump's sensor bias; ε is drawn from N(0, s²), s the standard error
  of the mean of ``samples`` flow-meter readings of standard deviation √(σ_abs² + (σ_rel Q)²) (the
  sensor's noise settings; the emulator's meter noise is white at its publish rate).

Sensor lags do not enter a settled plateau.  What this leaves out of a real recording: the flow ripple
aliased into the meter's samples, an oil temperature drifting during the plateau, the regulator's
residual motion (the calibration tests on recordings cover those, ``test/test_calibrate.py``).
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ..bench_emulator.bench_pump import BenchPump
from ..bench_emulator.emulator import emulated_config
from ..bench_emulator.sensors import BenchSpec
from ..config import load_config
from .fit_model import PlateauTask, plateau_flow
from .plateaus import PlateauRecord

__all__ = ["SteadyBench", "steady_plateaus"]


@dataclass(frozen=True)
class SteadyBench:
    """A bench pump on a steady bench: its emulated config and sensor settings."""
    bench_pump: BenchPump
    spec: BenchSpec              #: sensor settings (the bench pump's on top of the emulator's defaults)
    raw_truth: dict              #: the emulated pump's config mapping
    max_speed_rad_s: float       #: top of the config's speed range [rad/s]
    p_atm_pa: float              #: atmospheric pressure [Pa]

    @classmethod
    def of(cls, bench_pump: BenchPump, config_path=None, base: BenchSpec = BenchSpec()) -> "SteadyBench":
        nominal = load_config(config_path)
        spec = bench_pump.bench_spec(base)
        cfg = emulated_config(nominal, spec.clearance_factor, bench_pump)
        return cls(bench_pump, spec, cfg.to_dict(), nominal.range.max_speed_rpm * math.pi / 30,
                   nominal.fluid.atmospheric_pa)

    def suction_pa(self, omega: float) -> float:
        """True suction pressure at speed ``omega`` [rad/s] → [Pa abs] (the emulator's suction line)."""
        return self.p_atm_pa - self.spec.suction_drop_pa * (omega / self.max_speed_rad_s) ** 2

    def true_flow(self, omega: float, p_delivery_pa: float, oil_c: float) -> float:
        """The emulated pump's revolution-mean delivery flow in periodic steady state [m³/s]."""
        task = PlateauTask(self.raw_truth, float(self.raw_truth["clearances"]["tooth_tip_m"]), self.spec.bearing,
                           omega, self.suction_pa(omega), p_delivery_pa, oil_c)
        return float(plateau_flow(task)["flow_m3s"])


def steady_plateaus(bench: SteadyBench, points, *, seed: int, samples: int = 40, source: str = "steady") -> list[PlateauRecord]:
    """Plateau records of ``bench`` at the operating points ``points`` (module doc).

    Parameters
    ----------
    bench : SteadyBench
        The bench pump and its sensors.
    points : iterable of (float, float, float)
        True (speed [rad/s], delivery pressure [Pa abs], oil temperature [°C]) of each plateau.
    seed : int
        Seed of the flow noise draws.
    samples : int
        Flow-meter readings averaged per plateau [-] (the emulator's 20 Hz meter over 2 s: 40).
    source : str
        Name recorded as each plateau's origin.
    """
    s = bench.spec
    rng = np.random.default_rng(seed)
    out = []
    for k, (omega, p_d, t_c) in enumerate(points, start=1):
        q = bench.true_flow(omega, p_d, t_c)
        sem = math.hypot(s.flow_noise_m3s, s.flow_noise_rel * q) / math.sqrt(samples)
        out.append(PlateauRecord(
            bag=source, index=k, t0_s=math.nan, t1_s=math.nan, omega=omega + s.speed_bias_rad_s,
            p_delivery_pa=p_d + s.pressure_bias_pa, p_suction_pa=bench.suction_pa(omega),
            oil_temperature_c=t_c + s.temperature_bias_c, flow_m3s=q + s.flow_bias_m3s + sem * rng.standard_normal(),
            flow_sem_m3s=sem, bins=samples))
    return out
