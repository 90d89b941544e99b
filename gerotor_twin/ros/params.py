"""Parameters of ``twin_node``: names, defaults, units, ranges (declared with descriptors).

:data:`PARAMETERS` is plain data (no rclpy), so the README table, the MCAP
metadata and the node share one definition.  :func:`declare` declares them on
an rclpy node with ``ParameterDescriptor`` (description with the unit,
``FloatingPointRange`` / ``IntegerRange``, read-only: they are read once at
start) after registering a set-parameters callback that refuses values outside
a choice list with a reason naming the parameter, the value and the allowed
set.  An out-of-range override from ``--params-file`` is refused by rclpy
itself (``InvalidParameterValueException``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

__all__ = ["Param", "PARAMETERS", "declare", "values"]


@dataclass(frozen=True)
class Param:
    name: str
    default: Any
    description: str            #: includes the unit in brackets
    lo: float | None = None     #: numeric range (inclusive)
    hi: float | None = None
    choices: tuple = ()


PARAMETERS: tuple[Param, ...] = (
    Param("pump_config", "", "pump YAML file (geometry, fluid, clearances); '' = the packaged config/pump.yaml"),
    Param("bearing_model", "mobility", "outer-gear model", choices=("mobility", "short", "fdm", "fixed")),
    Param("tick_rate_hz", 200.0, "model tick rate on the node clock [Hz] (under use_sim_time at most one "
                                 "tick per /clock message)", 1.0, 1000.0),
    Param("sample_period_s", 0.005, "input sampling grid: zero-order hold cell and finest output step [s]",
          0.0005, 0.1),
    Param("publish_rate_hz", 200.0, "rate of chamber pressures, delivery flow, eccentricity, tooth gaps [Hz] "
                                   "(rounded to a whole number of sample periods)", 0.1, 2000.0),
    Param("diagnostics_rate_hz", 1.0, "rate of /diagnostics [Hz]", 0.1, 10.0),
    Param("shaft_speed_topic", "bench/shaft_speed", "sensor_msgs/JointState input, velocity[0] [rad/s]"),
    Param("delivery_pressure_topic", "bench/delivery_pressure", "sensor_msgs/FluidPressure input, absolute [Pa]"),
    Param("suction_pressure_topic", "bench/suction_pressure",
          "sensor_msgs/FluidPressure input, absolute [Pa] (optional; '' = not subscribed, config default used)"),
    Param("delivery_flow_topic", "bench/delivery_flow",
          "std_msgs/Float64 measured delivery flow [m^3/s] (optional, for live residuals; '' = off)"),
    Param("oil_temperature_topic", "bench/oil_temperature",
          "sensor_msgs/Temperature oil temperature [degC] (optional, reported only; '' = off)"),
    Param("input_queue_depth", 2000, "subscription history depth per input (sensor-data QoS) [messages]; "
                                     "2000 = a 1 s stall of a 1 kHz bench with 2x margin", 1, 100000),
    Param("input_filter_tau_s", 0.0, "first-order low-pass time constant on every input [s] (0 = off)",
          0.0, 60.0),
    Param("stale_timeout_s", 0.5, "a required input older than this holds the model [s]", 0.001, 3600.0),
    Param("stamp_restart_s", 1.0, "a header stamp this much older than the last one is a source restart [s]",
          0.0, 3600.0),
    Param("max_span_s", 0.25, "lag policy: most clock time integrated per tick; older backlog is skipped [s]",
          0.001, 3600.0),
    Param("waveform_every", 1, "publish the chamber-pressure waveform every N revolutions (0 = never) [-]",
          0, 10000),
    Param("waveform_samples", 360, "shaft-angle samples of the waveform per revolution [-]", 8, 100000),
    Param("log_dir", "", "directory of the MCAP log (one file per run); '' = no log"),
    Param("log_compression", "zstd", "MCAP chunk compression", choices=("zstd", "lz4", "none")),
    Param("log_waveforms", True, "also log twin/chamber_waveform to MCAP (large) [-]"),
    Param("log_rotate_mb", 0.0, "start a new MCAP file after this size [MB] (0 = never)", 0.0, 1e6),
    Param("log_rotate_s", 0.0, "start a new MCAP file after this duration [s] (0 = never)", 0.0, 1e7),
    Param("log_queue", 200000, "background MCAP writer queue [messages] (overflow is counted and dropped)",
          100, 10000000),
)


def declare(node) -> dict[str, Any]:
    """Declare :data:`PARAMETERS` on ``node`` (rclpy) and return their values.

    Raises
    ------
    rclpy.exceptions.InvalidParameterValueException
        A value out of range or not in its choice list (the reason names both).
    """
    from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                    SetParametersResult)

    by_name = {p.name: p for p in PARAMETERS}

    def check(params):
        for prm in params:
            spec = by_name.get(prm.name)
            if spec is not None and spec.choices and prm.value not in spec.choices:
                return SetParametersResult(successful=False, reason=(
                    f"{prm.name} = {prm.value!r} is invalid; allowed: {' | '.join(spec.choices)}"))
        return SetParametersResult(successful=True)

    node.add_on_set_parameters_callback(check)
    for p in PARAMETERS:
        d = ParameterDescriptor(description=p.description, read_only=True)
        if p.choices:
            d.additional_constraints = "one of: " + ", ".join(p.choices)
        if p.lo is not None:
            if isinstance(p.default, int) and not isinstance(p.default, bool):
                d.integer_range = [IntegerRange(from_value=int(p.lo), to_value=int(p.hi), step=1)]
            else:
                d.floating_point_range = [FloatingPointRange(from_value=float(p.lo), to_value=float(p.hi),
                                                             step=0.0)]
        node.declare_parameter(p.name, p.default, d)
    return values(node)


def values(node) -> dict[str, Any]:
    """Current values of :data:`PARAMETERS` (plus ``use_sim_time``)."""
    out = {p.name: node.get_parameter(p.name).value for p in PARAMETERS}
    out["use_sim_time"] = node.get_parameter("use_sim_time").value
    return out
