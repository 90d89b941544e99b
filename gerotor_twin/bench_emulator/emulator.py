"""The bench emulator: a pump that differs from the twin on purpose, seen through bench sensors.

The emulated pump is :class:`~gerotor_twin.model.pump.PumpModel` with

* another outer-gear model (``BenchSpec.bearing``, default the short-bearing
  "Method 1"; the twin defaults to the mobility method),
* tooth-tip and lateral clearances ``BenchSpec.clearance_factor`` × nominal
  (default +10 %, so about +33 % leakage),

driven by a motor and a pressure valve that follow the profile's set-points
with first-order lags, at an oil temperature that warms up (or follows the
profile's oil temperature set-points) with the sump's time constant
(:func:`oil_bath`).  Every internal tick (1 kHz) advances the model with
the inputs held, then the sensors see the result: an encoder (quantized,
differenced over 10 ms), fast pressure transducers that see the flow ripple
through the delivery-line impedance, a flow meter with its own time
constant, a slow thermometer, Gaussian noise on each, and a recorder
latency.  Fault scenarios (:mod:`.faults`) wear the pump, add air, restrict the suction or
corrupt the sensors during the run.  Output: an MCAP file with the bench topics of DESIGN.md, rosbag2
conventions (via :mod:`gerotor_twin.io`), identical bytes for the same seed,
profile and software versions.
"""
from __future__ import annotations

import json
import math
import sys
import time
from dataclasses import replace
from pathlib import Path
from typing import IO, Callable

import numpy as np
import yaml

from gerotor_twin.config import PumpConfig, load_config, parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.io import McapLog
from gerotor_twin.io import messages as m
from gerotor_twin.hydraulics.state_equation import convert_log_density
from gerotor_twin.model.clearance_scale import scale_clearances, take_config
from gerotor_twin.model.pump import BEARING_MODELS, Inputs, PumpModel
from gerotor_twin.units import celsius_to_kelvin, kelvin_to_celsius, rpm_to_rad_s

from .profiles import Profile
from .bench_pump import BenchPump
from .faults import Fault, FaultScenario, SuctionRestriction
from .sensors import BenchSpec, Encoder, FirstOrderLag, OilBath, noise_streams

__all__ = ["BENCH_TOPICS", "EMULATOR_METADATA", "BenchDrive", "BenchSensors", "emulated_config", "oil_bath",
           "synthesize"]

#: Topics and types written (DESIGN.md, bench inputs of the twin).
BENCH_TOPICS = {
    "/bench/shaft_speed": m.JOINT_STATE,
    "/bench/delivery_pressure": m.FLUID_PRESSURE,
    "/bench/suction_pressure": m.FLUID_PRESSURE,
    "/bench/delivery_flow": m.FLOAT64,
    "/bench/oil_temperature": m.TEMPERATURE,
}
#: Metadata record describing how a file was synthesized.
EMULATOR_METADATA = "gerotor_twin.bench_emulator"
SHAFT_JOINT = "pump_shaft"
#: Numerics of the emulated pump, fixed (not the twin's defaults): 0.5° output steps and
#: 5e-5 on ln(ρ/ρ₀), so the "bench" is the better-resolved of the two and a
#: change of the twin's numerics settings does not change what the emulator writes (a change of
#: the integrator itself does: ∂f/∂t in the stages, say).
EMULATOR_NUMERICS = {"max_step_deg": 0.5, "tolerance": 5e-5, "error_measure": "log_density",
                     "max_substep_attempts": 1_000_000}


def emulated_config(config: PumpConfig, factor: float, bench_pump: BenchPump | None = None) -> PumpConfig:
    """The emulated pump: ``config`` with the deviations of ``bench_pump`` (if any), then tooth-tip and
    lateral clearances multiplied by ``factor`` [-], integrated with :data:`EMULATOR_NUMERICS`.

    Raises
    ------
    InputError
        ``factor`` outside [0.5, 2], or a deviation that makes the config invalid (its field named,
        with the bench pump's name).
    """
    if not (math.isfinite(factor) and 0.5 <= factor <= 2.0):
        raise InputError("clearance_factor", factor, "[0.5, 2]")
    raw = config.to_dict()
    label = f"clearances x{factor:g}"
    if bench_pump is not None:
        raw = bench_pump.emulated_raw(raw)
        label = f"bench pump {bench_pump.name}, " + label
    raw["clearances"]["tooth_tip_m"] *= factor
    raw["clearances"]["lateral_m"] *= factor
    raw["numerics"].update(EMULATOR_NUMERICS)
    try:
        return parse_config(raw, source=f"{config.source} ({label})")
    except InputError as e:
        raise InputError(f"emulated pump ({label}) {e.field}", e.value, e.allowed, e.reason) from None


def oil_bath(profile: Profile, spec: BenchSpec) -> OilBath:
    """The true oil temperature of the emulated bench along ``profile`` [°C] (:class:`OilBath`).

    Set-point: each segment's ``oil_temperature_c`` (held by the segments after it), and
    ``spec.temperature_end_c`` before the first segment that sets one; start: the first
    segment's ``oil_temperature_c`` (the bench conditioned to it, as the drive and valve
    start at the first speed and pressure) or ``spec.temperature_start_c``.  A profile without
    oil temperatures gives the warm-up of :func:`~.sensors.oil_warmup`.
    """
    kt, ku = profile.oil_knots(spec.temperature_end_c)
    first = profile.segments[0].oil_temperature_c
    return OilBath(kt, ku, spec.temperature_start_c if first is None else first, spec.temperature_warmup_tau_s)


def profile_metadata(profile: Profile) -> dict[str, str]:
    """What the file's metadata says about the profile: name, description, segments (JSON) and,
    for a profile file, its text."""
    meta = {"profile": profile.name, "profile_description": profile.description,
            "segments": json.dumps([s.as_dict() for s in profile.segments])}
    return meta if not profile.source else {**meta, "profile_file_text": profile.source}


def file_metadata(profile: Profile, spec: BenchSpec, cfg: PumpConfig, command: str,
                  bench_pump: BenchPump | None, faults: FaultScenario = FaultScenario()) -> dict[str, dict[str, str]]:
    """The file's metadata record :data:`EMULATOR_METADATA`: the profile, the emulator settings, the
    command, the emulated pump's config, with a bench pump its resolved description (YAML: every
    value used) and the file's text, and with faults their truth (:func:`fault_metadata`)."""
    meta = {"synthetic": "true", **profile_metadata(profile),
            "spec": json.dumps(spec.as_dict(), sort_keys=True), "seed": str(spec.seed),
            "command": command, "emulated_pump_config": yaml.safe_dump(cfg.to_dict(), sort_keys=False)}
    if bench_pump is not None:
        meta["bench_pump"] = yaml.safe_dump(bench_pump.as_dict(), sort_keys=False, allow_unicode=True)
        if bench_pump.source:
            meta["bench_pump_file_text"] = bench_pump.source
    return {EMULATOR_METADATA: {**meta, **fault_metadata(faults, spec, cfg)}}


def fault_metadata(faults: FaultScenario, spec: BenchSpec, cfg: PumpConfig) -> dict[str, str]:
    """The faults' truth (none without faults): ``faults``, each fault resolved (YAML: kind, ``to``, unit,
    meaning, start, ramp, end [s]); ``fault_series``, every fault's value every :data:`WEAR_UPDATE_TICKS`
    ticks (JSON: ``t_s``, ``tick`` and one list per kind, unit per kind); ``speed_samples_dropped``, how many
    shaft-speed samples are missing."""
    if not faults:
        return {}
    dt = 1.0 / spec.internal_rate_hz
    dropped = faults.speed_dropped(spec.decimation(spec.speed_rate_hz, "speed_rate_hz"), dt)
    return {"faults": yaml.safe_dump(faults.as_dict(), sort_keys=False),
            "fault_series": json.dumps(faults.series(WEAR_UPDATE_TICKS, dt, cfg.air.air_fraction)),
            "speed_samples_dropped": str(int(dropped.sum()))}


def _progress_printer(stream: IO[str] | None, label: str, total_s: float) -> Callable[[float], None]:
    wall0 = time.monotonic()
    last = [-1.0]

    def show(t: float, done: bool = False) -> None:
        if stream is None:
            return
        now = time.monotonic()
        if not done and (now - last[0] < 1.0 or t <= 0):
            return
        last[0] = now
        el = now - wall0
        eta = el * (total_s - t) / t if t > 0 else float("nan")
        print(f"\r{label}: {t:7.1f}/{total_s:.1f} s simulated, {el:6.0f} s elapsed, ETA {eta:5.0f} s ",
              end="\n" if done else "", file=stream, flush=True)
    return show


class BenchSensors:
    """The bench's sensors, updated once per tick and published at their rates (all SI).

    An encoder (quantized, differenced over ``spec.speed_window_s``) and a speed filter; pressure
    transducers that see the flow ripple through the delivery-line impedance; a flow meter and a
    thermometer, each a first-order lag; every published sample adds the sensor's bias and Gaussian
    noise (:class:`~.sensors.BenchSpec`).

    Parameters
    ----------
    spec : BenchSpec
        Sensor settings, rates and time constants.
    dt : float
        Tick [s].
    rng : dict of numpy.random.Generator
        Noise streams by sensor (:func:`~.sensors.noise_streams`).
    emit : callable
        ``emit(topic, message, stamp_ns)`` records one sample.
    inp : Inputs
        Speed [rad/s] and pressures [Pa] at the start of the recording.
    q0 : float
        Delivery flow at the start [m³/s].
    temp0_c : float
        Oil temperature at the start [°C].
    theta0 : float
        Shaft angle at the start [rad].
    faults : FaultScenario
        The run's faults; the sensor kinds (pressure offset, speed dropout, flow-meter drift) act here.
    meter0 : float
        What the flow meter reads per unit of delivered flow at the start (:func:`meter_factor`) [-].
    """

    def __init__(self, spec: BenchSpec, dt: float, rng: dict, emit: Callable, inp: Inputs, q0: float,
                 temp0_c: float, theta0: float, faults: FaultScenario = FaultScenario(), meter0: float = 1.0):
        self.spec, self.rng, self.emit, self.dt = spec, rng, emit, dt
        self.offset = faults.by_kind.get("pressure_offset")
        self.drift = faults.by_kind.get("flowmeter_drift")
        self.dec = {"speed": spec.decimation(spec.speed_rate_hz, "speed_rate_hz"),
                    "pressure": spec.decimation(spec.pressure_rate_hz, "pressure_rate_hz"),
                    "flow": spec.decimation(spec.flow_rate_hz, "flow_rate_hz"),
                    "temperature": spec.decimation(spec.temperature_rate_hz, "temperature_rate_hz")}
        self.ripple_dc = FirstOrderLag(spec.ripple_dc_tau_s, dt, q0)
        self.delivery = FirstOrderLag(spec.pressure_tau_s, dt, inp.p_delivery)
        self.suction = FirstOrderLag(spec.suction_tau_s, dt, inp.p_suction)
        self.speed = FirstOrderLag(spec.speed_tau_s, dt, inp.omega)
        self.flow = FirstOrderLag(spec.flow_tau_s, dt, q0 * meter0)     # meter0: the meter's factor at the start
        self.thermo = FirstOrderLag(spec.temperature_tau_s, dt, temp0_c)
        self.encoder = Encoder(spec.encoder_counts, max(1, int(round(spec.speed_window_s * spec.internal_rate_hz))),
                               dt, theta0, inp.omega)
        self.speed_dropped = faults.speed_dropped(self.dec["speed"], dt) if "speed_dropout" in faults.by_kind else None

    def _noise(self, stream: str, sigma: float) -> float:
        return self.rng[stream].normal(0.0, sigma)

    def tick(self, i: int, t_ns: int, pd: float, ps: float, q_inst: float, q_mean: float, oil_c: float,
             theta: float, meter_factor: float = 1.0) -> None:
        """Tick ``i`` (from 1), stamped ``t_ns`` [ns]: the true delivery and suction pressures [Pa],
        instantaneous and tick-mean delivery flow [m³/s], oil temperature [°C] and shaft angle [rad]; the flow
        meter reads ``meter_factor`` × the tick-mean flow (its pressure's volume of that mass, ``spec.flow_meter``)."""
        s, dec, t = self.spec, self.dec, i * self.dt
        p_meas = self.delivery(pd + s.ripple_impedance * (q_inst - self.ripple_dc(q_mean)))
        s_meas = self.suction(ps - 0.1 * s.ripple_impedance * (q_inst - self.ripple_dc.y))
        q_meas = self.flow(q_mean * meter_factor)
        temp = self.thermo(oil_c)
        w_enc, angle = self.encoder(theta)
        w_meas = self.speed(w_enc)
        if i % dec["speed"] == 0:
            w_meas += s.speed_bias_rad_s + (self._noise("speed", s.speed_noise_rad_s) if s.speed_noise_rad_s > 0
                                            else 0.0)
            dropped = self.speed_dropped is not None and self.speed_dropped[i // dec["speed"] - 1]
            self.emit("/bench/shaft_speed", m.joint_state(t_ns, name=[SHAFT_JOINT], position=[angle],
                                                          velocity=[w_meas]), t_ns, not dropped)
        if i % dec["pressure"] == 0:
            if self.offset is not None:
                p_meas += self.offset.value(t)
            self.emit("/bench/delivery_pressure", m.fluid_pressure(
                t_ns, p_meas + s.pressure_bias_pa + self._noise("pressure", s.pressure_noise_pa),
                variance=s.pressure_noise_pa ** 2), t_ns)
            self.emit("/bench/suction_pressure", m.fluid_pressure(
                t_ns, s_meas + self._noise("suction", s.suction_noise_pa), variance=s.suction_noise_pa ** 2), t_ns)
        if i % dec["flow"] == 0:
            sigma = math.hypot(s.flow_noise_rel * q_meas, s.flow_noise_m3s)
            reading = q_meas + s.flow_bias_m3s + self._noise("flow", sigma)
            if self.drift is not None:
                reading *= 1.0 + self.drift.value(t)
            self.emit("/bench/delivery_flow", m.float64(reading), t_ns)
        if i % dec["temperature"] == 0:
            self.emit("/bench/oil_temperature", m.temperature(
                t_ns, temp + s.temperature_bias_c + self._noise("temperature", s.temperature_noise_c),
                variance=s.temperature_noise_c ** 2), t_ns)


def meter_factor(spec: BenchSpec, model, p_atm: float) -> Callable[[float], float]:
    """p_d [Pa abs] → what the bench's flow meter reads per unit of delivered flow at p_d: 1 at the delivery
    pressure, ρ(p_d)/ρ(p_atm) of the emulated pump's oil (at its current temperature) in the return line
    (``spec.flow_meter``, :mod:`gerotor_twin.hydraulics.meter`)."""
    if spec.flow_meter == "delivery":
        return lambda p_d: 1.0
    from gerotor_twin.hydraulics.meter import expansion
    return lambda p_d: expansion(p_d, p_atm, model.kernel.eos)


def synthesize(profile: Profile, output, spec: BenchSpec = BenchSpec(), *, config: PumpConfig | None = None,
               overwrite: bool = False, command: str = "", progress: IO[str] | None = sys.stderr,
               bench_pump: BenchPump | None = None, faults: tuple[Fault, ...] = ()) -> dict:
    """Run the emulated bench along ``profile`` and record it to MCAP.

    Parameters
    ----------
    profile : Profile
        Set-points of speed, delivery pressure and (optionally) oil temperature; they must lie in
        the pump's range (``config.range``).
    output : path or binary stream
        MCAP file to create (or a stream such as ``io.BytesIO``).
    spec : BenchSpec
        Emulator and sensor parameters, including the seed (for a bench pump:
        ``bench_pump.bench_spec(...)``, its sensors and no common clearance factor).
    config : PumpConfig, optional
        Nominal pump (default ``config/pump.yaml``); the emulated pump derives from it.
    overwrite : bool
        Replace an existing file.
    command : str
        The command line, stored in the file's metadata.
    progress : text stream or None
        Where to print progress (default stderr).
    bench_pump : BenchPump, optional
        How the emulated pump differs from ``config`` in form (:mod:`.bench_pump`); its deviations
        come before ``spec.clearance_factor``, and its resolved description goes into the metadata.
    faults : sequence of Fault
        Fault scenarios (:mod:`.faults`), at most one per kind; their truth goes into the metadata.

    Returns
    -------
    dict
        Message counts, duration [s], the ground truth per plateau (true mean delivery
        flow [m³/s], theoretical flow [m³/s], volumetric efficiency [-]) and, with faults,
        ``fault_truth`` (:func:`fault_truth`).
    """
    nominal, cfg, scenario = checked_inputs(profile, spec, config, bench_pump, faults)
    model = PumpModel(cfg, spec.bearing)
    dt = 1.0 / spec.internal_rate_hz
    n_ticks = int(round(profile.duration_s * spec.internal_rate_hz))
    rng = noise_streams(spec.seed, ("speed", "pressure", "suction", "flow", "temperature", "latency"))
    drive = BenchDrive(profile, spec, cfg, dt, n_ticks)
    inp = drive.start()                     # run-in at the first set-point (not recorded)
    state = model.initial_state(inp, t=-spec.warmup_s)
    state, out = model.advance(state, spec.warmup_s, inp)
    q_dc0 = float(np.mean(out.delivery_flow[-max(1, len(out) // 4):]))
    drive.restriction = SuctionRestriction(scenario, model.theoretical_flow(drive.w_max), dt, q_dc0)

    resolved = None if bench_pump is None else bench_pump.resolved(nominal, spec)
    log = McapLog(output, metadata=file_metadata(profile, spec, cfg, command, resolved, scenario), overwrite=overwrite)
    for topic, msgtype in BENCH_TOPICS.items():
        log.add_topic(topic, msgtype, qos="sensor")
    show = _progress_printer(progress, f"synth-bench {profile.name}", profile.duration_s)
    true = np.empty((5, n_ticks))           # delivered flow, speed, oil [°C], suction pressure, eccentricity
    true_c = np.full(n_ticks, spec.clearance_factor)
    t0_ns = spec.start_time_ns

    def emit(topic: str, msg: dict, t_ns: int, write: bool = True) -> None:
        lat = spec.latency_s + rng["latency"].exponential(spec.latency_jitter_s)
        if write:
            log.write(topic, msg, t_ns + int(round(lat * 1e9)), t_ns)

    meter = meter_factor(spec, model, cfg.fluid.atmospheric_pa)
    sensors = BenchSensors(spec, dt, rng, emit, inp, q_dc0, drive.bath.start_c, state.theta, scenario,
                           meter(inp.p_delivery))
    try:
        for k in range(n_ticks):
            true_c[k], state = update_pump(model, cfg, spec, scenario, dt, profile.duration_s, k, state)
            inp = drive(k)
            state, out = model.advance(state, dt, inp)
            drive.restriction.feed(out.port_mass_in / dt)
            q_mean = tick_mean_flow(out)
            true[:, k] = (q_mean, inp.omega, kelvin_to_celsius(inp.oil_temperature), inp.p_suction,
                          math.hypot(*state.eccentricity))
            t = (k + 1) * dt
            sensors.tick(k + 1, t0_ns + int(round(t * 1e9)), inp.p_delivery, inp.p_suction,
                         float(out.delivery_flow[-1]), q_mean, true[2, k], state.theta,
                         meter(inp.p_delivery))
            show(t)
    finally:
        counts = log.message_counts
        log.close()
    show(profile.duration_s, done=True)
    res = {"profile": profile.name, "duration_s": profile.duration_s, "seed": spec.seed, "message_counts": counts,
           "truth": wear_truth(_truth(profile, cfg, model, true[0], true[1], true[2], dt), true_c, dt, spec)}
    return res if not scenario else {**res, "fault_truth": fault_truth(scenario, cfg, dt, true[0], true[3], true[4])}


class BenchDrive:
    """What the bench feeds the emulated pump each tick: the drive's speed and the delivery valve's pressure
    following the profile's set-points through first-order lags (``spec.motor_tau_s``, ``spec.valve_tau_s``),
    the suction pressure (the suction line's drop ∝ speed², ``spec.suction_drop_pa`` at ``range.max_speed_rpm``,
    less a suction restriction fault's, :attr:`restriction`) and the oil bath's temperature (:func:`oil_bath`).

    Parameters
    ----------
    profile : Profile
        Set-points.
    spec : BenchSpec
        Emulator settings.
    cfg : PumpConfig
        The emulated pump (atmospheric pressure [Pa], range).
    dt : float
        Tick [s].
    n_ticks : int
        Ticks of the run.
    """

    def __init__(self, profile: Profile, spec: BenchSpec, cfg: PumpConfig, dt: float, n_ticks: int):
        self.sp_w, self.sp_p = profile.setpoints(np.arange(n_ticks + 1) * dt)
        self.spec, self.dt, self.p_atm = spec, dt, cfg.fluid.atmospheric_pa
        self.w_max = rpm_to_rad_s(cfg.range.max_speed_rpm)
        self.bath = oil_bath(profile, spec)
        self.motor = FirstOrderLag(spec.motor_tau_s, dt, self.sp_w[0])
        self.valve = FirstOrderLag(spec.valve_tau_s, dt, self.sp_p[0])
        self.restriction: SuctionRestriction | None = None

    def suction(self, w: float) -> float:
        """Suction pressure at shaft speed ``w`` [rad/s] without a restriction fault [Pa absolute]."""
        return self.p_atm - self.spec.suction_drop_pa * (w / self.w_max) ** 2

    def oil_k(self, t: float) -> float:
        """True oil temperature of the emulated pump at ``t`` [s] [K]."""
        return celsius_to_kelvin(self.bath(t))

    def start(self) -> Inputs:
        """The inputs at the first set-point (the run-in's) [rad/s, Pa, Pa, K]."""
        w0, p0 = self.sp_w[0], self.sp_p[0]
        return Inputs(float(w0), self.suction(w0), self.p_atm + float(p0), self.oil_k(0.0))

    def __call__(self, k: int) -> Inputs:
        """The inputs over tick ``k`` (from 0) [rad/s, Pa, Pa, K]; the lags advance by one tick."""
        w = max(0.0, self.motor(self.sp_w[k]))
        pd = self.p_atm + self.valve(self.sp_p[k])
        ps = self.suction(w) - self.restriction.drop(k * self.dt)
        return Inputs(w, ps, pd, self.oil_k(k * self.dt))


def checked_inputs(profile: Profile, spec: BenchSpec, config: PumpConfig | None, bench_pump: BenchPump | None,
                   faults) -> tuple[PumpConfig, PumpConfig, FaultScenario]:
    """Every input of :func:`synthesize` checked before any work: the nominal config, the emulated pump's
    and the faults resolved for the profile's duration.

    Raises
    ------
    InputError
        The outer-gear model, a set-point outside the pump's range, a publish rate, the emulated pump, a
        fault (its start after the end of the run, a severity the emulated pump cannot take).
    """
    if spec.bearing not in BEARING_MODELS:
        raise InputError("bearing", spec.bearing, " | ".join(BEARING_MODELS))
    nominal = config or load_config()
    profile.check_within(nominal.range)
    cfg = emulated_config(nominal, spec.clearance_factor, bench_pump)
    for rate, name in ((spec.speed_rate_hz, "speed_rate_hz"), (spec.pressure_rate_hz, "pressure_rate_hz"),
                       (spec.flow_rate_hz, "flow_rate_hz"), (spec.temperature_rate_hz, "temperature_rate_hz")):
        spec.decimation(rate, name)
    scenario = FaultScenario(faults, profile.duration_s)
    wear_end = spec.wear_clearance_factor_end / spec.clearance_factor if spec.wear_clearance_factor_end else 1.0
    scenario.check(cfg, wear_end)
    return nominal, cfg, scenario


def fault_truth(scenario: FaultScenario, cfg: PumpConfig, dt: float, q: np.ndarray, ps: np.ndarray,
                ecc: np.ndarray) -> dict[str, list[float]]:
    """The faults' truth every :data:`WEAR_UPDATE_TICKS` ticks of ``dt`` [s]: each fault's value (unit per kind,
    :meth:`FaultScenario.series`) and, at the tick before, the emulated pump's delivered flow [m³/s], suction
    pressure [Pa absolute] and outer-gear eccentricity [m], from the per-tick arrays ``q``, ``ps``, ``ecc``."""
    out = scenario.series(WEAR_UPDATE_TICKS, dt, cfg.air.air_fraction)
    idx = np.clip(np.asarray(out["tick"]) - 1, 0, len(q) - 1)
    return {**out, "delivery_flow_m3s": q[idx].tolist(), "suction_pa": ps[idx].tolist(),
            "eccentricity_m": ecc[idx].tolist()}


#: The wear scenario updates the emulated clearances every this many ticks (0.1 s at 1 kHz).
WEAR_UPDATE_TICKS = 100


def wear_factor(spec: BenchSpec, t_s: float, duration_s: float) -> float:
    """Clearance factor of the emulated pump at time ``t_s`` [s] of the run (wear scenario) [-].

    ``spec.clearance_factor`` until ``spec.wear_start_s``, then linear to
    ``spec.wear_clearance_factor_end`` at ``duration_s``; constant when the end factor is 0.
    """
    f0, f1 = spec.clearance_factor, spec.wear_clearance_factor_end
    if f1 == 0 or t_s <= spec.wear_start_s or duration_s <= spec.wear_start_s:
        return f0
    frac = min(1.0, (t_s - spec.wear_start_s) / (duration_s - spec.wear_start_s))
    return f0 + (f1 - f0) * frac


def apply_wear(model: PumpModel, emulated: PumpConfig, spec: BenchSpec, dt: float, duration_s: float,
               tick: int) -> float:
    """Every :data:`WEAR_UPDATE_TICKS` ticks (of ``dt`` [s]) give the model the worn clearances;
    returns the factor in use [-]."""
    if spec.wear_clearance_factor_end == 0:
        return spec.clearance_factor
    f = wear_factor(spec, (tick - tick % WEAR_UPDATE_TICKS) * dt, duration_s)
    if tick % WEAR_UPDATE_TICKS == 0:
        scale_clearances(model, emulated, f / spec.clearance_factor)
    return f


def update_pump(model: PumpModel, emulated: PumpConfig, spec: BenchSpec, faults: FaultScenario, dt: float,
                duration_s: float, tick: int, state):
    """The emulated pump at tick ``tick`` (of ``dt`` [s]): every :data:`WEAR_UPDATE_TICKS` ticks the worn
    clearances of the wear scenario (:func:`apply_wear`) and of the pump faults (tip, lateral, housing wear, air
    ingress: :meth:`FaultScenario.pump_config`); a changed state equation (air) converts ``state`` to the same
    pressures.  Returns the wear scenario's clearance factor [-] and the state."""
    if not faults.changes_pump:
        return apply_wear(model, emulated, spec, dt, duration_s, tick), state
    t = (tick - tick % WEAR_UPDATE_TICKS) * dt
    f = wear_factor(spec, t, duration_s)
    if tick % WEAR_UPDATE_TICKS == 0:
        old = model.kernel.eos
        take_config(model, faults.pump_config(emulated, t, f / spec.clearance_factor))
        if "air_ingress" in faults.by_kind:
            state = replace(state, log_density=convert_log_density(state.log_density, old, model.kernel.eos))
    return f, state


def wear_truth(rows: list[dict], factor: np.ndarray, dt: float, spec: BenchSpec) -> list[dict]:
    """Add the emulated clearance factor (mean over the same second half) to the ground-truth rows."""
    if spec.wear_clearance_factor_end == 0:
        return rows
    for r in rows:
        a, b = int(round((r["t0_s"] + r["t1_s"]) / 2 / dt)), int(round(r["t1_s"] / dt))
        r["clearance_factor"] = float(factor[a:b].mean())
    return rows


def tick_mean_flow(out) -> float:
    """Net delivered flow over one emulator tick [m³/s]: the integrated delivered volume / tick.

    (The unweighted mean of the step-end samples ``out.delivery_flow`` read ≈ 0.1 % low at 0.5°
    steps with the flow ripple — the twin's summaries integrate the volume, so the bench must too.)
    """
    return float(out.volumetric_efficiency * out.theoretical_flow)


def _truth(profile: Profile, cfg: PumpConfig, model: PumpModel, q: np.ndarray, w: np.ndarray, temp: np.ndarray,
           dt: float) -> list[dict]:
    """Ground truth on the second half of each plateau: mean flows, efficiency and oil temperature [°C]."""
    rows = []
    for t0, t1, rpm, bar in profile.plateaus():
        a, b = int(round((t0 + t1) / 2 / dt)), int(round(t1 / dt))
        if b <= a:
            continue
        qm = float(q[a:b].mean())
        qth = float(model.displacement * w[a:b].mean() / (2 * math.pi))
        rows.append({"t0_s": t0, "t1_s": t1, "rpm": rpm, "bar": bar, "true_mean_flow_m3s": qm,
                     "theoretical_flow_m3s": qth, "true_volumetric_efficiency": qm / qth if qth > 0 else None,
                     "oil_temperature_c": float(temp[a:b].mean())})
    return rows


def default_output_name(profile: Profile, directory: str | Path = "bags") -> Path:
    """``bags/bench_<profile>.mcap``."""
    return Path(directory) / f"bench_{profile.name}.mcap"
