"""Parameters of ``twin_node``: names, defaults, units, ranges; validation of every value given.

:data:`PARAMETERS` is plain data (no rclpy), so the parameter table of docs/node.md, the MCAP
metadata and the node share one definition.

Validation (:func:`check_overrides`, no rclpy): every value given to the node
(params files and ``-p``, read by :mod:`gerotor_twin.ros.param_args`, or the
overrides rclpy holds) is checked the same way: an unknown name is refused
with the closest known names (``difflib``), a value of the wrong type, out of
range or not in a choice list is refused naming the parameter, the value, the
allowed range and where it came from.  The node exits 2 with that one line.

:func:`declare` declares the parameters on an rclpy node with
``ParameterDescriptor`` (description with the unit, ``FloatingPointRange`` /
``IntegerRange``) using the validated values (rclpy's own merge of the
overrides is bypassed, see :mod:`~gerotor_twin.ros.param_args`), then
registers a set-parameters callback that refuses every change at run time
with the reason it cannot be honoured live (:func:`fixed_reason`); none of
the parameters, ``use_sim_time`` included, is applied live.
"""
from __future__ import annotations

import difflib
from dataclasses import dataclass
from typing import Any, Mapping

from gerotor_twin.errors import InputError, check_range, short_repr
from gerotor_twin.hydraulics.meter import FLOW_METERS
from gerotor_twin.twin.settings import TwinSettings

__all__ = ["Param", "PARAMETERS", "BUILTIN", "CORE_SETTINGS", "declare", "values", "check_value",
           "check_overrides", "fixed_reason", "refuse_change", "twin_settings"]

#: Node parameters that set a field of the twin core's :class:`TwinSettings` (parameter -> field).  Their
#: defaults are the core's own (one place: run-bag, batch and the node share them); ``publish_rate_hz`` is
#: the inverse of ``publish_period_s``.
CORE_SETTINGS: dict[str, str] = {
    "sample_period_s": "sample_period_s", "oil_sensor_tau_s": "oil_sensor_tau_s",
    "input_filter_tau_s": "filter_tau_s", "stale_timeout_s": "stale_timeout_s",
    "stamp_restart_s": "stamp_restart_s", "stamp_ahead_s": "stamp_ahead_s",
    "stamp_rebase_samples": "stamp_rebase_samples", "max_span_s": "max_span_s",
    "waveform_every": "waveform_every", "waveform_samples": "waveform_samples", "flow_meter": "flow_meter",
}
_CORE = TwinSettings()


def _core(name: str):
    """Default of the node parameter ``name``: the twin core's default of the field it sets."""
    return getattr(_CORE, CORE_SETTINGS[name])


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
    Param("sample_period_s", _core("sample_period_s"), "input sampling grid: zero-order hold cell and finest output step [s]",
          0.0005, 0.1),
    Param("publish_rate_hz", 1.0 / _CORE.publish_period_s, "rate of chamber pressures, delivery flow, eccentricity, tooth gaps [Hz] "
                                   "(rounded to a whole number of sample periods)", 0.1, 2000.0),
    Param("diagnostics_rate_hz", 1.0, "rate of /diagnostics [Hz]", 0.1, 10.0),
    Param("startup_rtf_threshold", 1.5, "start-up real-time check: the model's real-time factor is measured at "
                                       "start (top speed of the pump config, lowest and highest delivery "
                                       "pressure, <= 1 s); below this, WARN on /diagnostics ('gerotor_twin: real "
                                       "time'). 1.5: the running node advances the model at about 0.75 x this "
                                       "figure (bench node) and its model thread also decodes the inputs and "
                                       "publishes and logs the outputs; 0 = no check [-]",
          0.0, 1000.0),
    Param("clock_stall_s", 1.0, "the node clock unchanged this long in wall time is reported as stalled on "
                                "/diagnostics (use_sim_time: /clock stopped) [s]", 0.01, 3600.0),
    Param("shaft_speed_topic", "bench/shaft_speed", "sensor_msgs/JointState input, velocity[0] [rad/s]"),
    Param("delivery_pressure_topic", "bench/delivery_pressure", "sensor_msgs/FluidPressure input, absolute [Pa]"),
    Param("suction_pressure_topic", "bench/suction_pressure",
          "sensor_msgs/FluidPressure input, absolute [Pa] (optional; '' = not subscribed, config default used)"),
    Param("delivery_flow_topic", "bench/delivery_flow",
          "std_msgs/Float64 measured delivery flow [m^3/s] (optional, for live residuals; '' = off)"),
    Param("oil_temperature_topic", "bench/oil_temperature",
          "sensor_msgs/Temperature oil temperature [degC] (optional; sets the oil properties, else the "
          "config's reference temperature; '' = off)"),
    Param("oil_sensor_tau_s", _core("oil_sensor_tau_s"), "time constant of the oil thermometer [s]: the model runs at the reading "
                                   "plus tau x its rate of change (lag compensation); 0 = the reading as is",
          0.0, 120.0),
    Param("flow_meter", _core("flow_meter"), "where the bench's flow meter reads: 'delivery' (at the delivery "
                                             "pressure, as the twin's flow) or 'atmospheric' (in the return line: "
                                             "each reading taken to the delivery pressure's volume before the "
                                             "residual and the health monitor compare it)",
          choices=FLOW_METERS),
    Param("input_queue_depth", 2000, "subscription history depth per input (sensor-data QoS) [messages]; "
                                     "2000 = a 1 s stall of a 1 kHz bench with 2x margin", 1, 100000),
    Param("input_coalesce_s", 0.002, "receiving thread: after a wake-up, wait this long, then take every "
                                     "message waiting, so one wake-up takes a batch [s] (0 = take at once; "
                                     "delays receive stamps and logging by at most this)", 0.0, 0.05),
    Param("input_filter_tau_s", _core("input_filter_tau_s"), "first-order low-pass time constant on every input [s] (0 = off)",
          0.0, 60.0),
    Param("stale_timeout_s", _core("stale_timeout_s"), "a required input older than this holds the model [s]", 0.001, 3600.0),
    Param("stamp_restart_s", _core("stamp_restart_s"), "a header stamp this much older than the last one is a source restart [s]",
          0.0, 3600.0),
    Param("stamp_ahead_s", _core("stamp_ahead_s"), "a header stamp this much further ahead of its receive time than the stream's "
                                "usual offset is implausible: that sample alone is rejected [s]", 0.001, 3600.0),
    Param("stamp_rebase_samples", _core("stamp_rebase_samples"), "consecutive consistent samples rejected for their stamp after which the "
                                     "stamp order re-anchors on them [samples]", 1, 1000),
    Param("max_span_s", _core("max_span_s"), "lag policy: most clock time integrated per tick; older backlog is skipped [s]",
          0.001, 3600.0),
    Param("waveform_every", _core("waveform_every"), "publish the chamber-pressure waveform every N revolutions (0 = never) [-]",
          0, 10000),
    Param("waveform_samples", _core("waveform_samples"), "shaft-angle samples of the waveform per revolution [-]", 8, 100000),
    Param("log_dir", "", "directory of the MCAP log (one file per run); '~' and $VARS are expanded; "
                         "'' = no log"),
    Param("log_compression", "zstd", "MCAP chunk compression", choices=("zstd", "lz4", "none")),
    Param("log_waveforms", True, "also log twin/chamber_waveform to MCAP (large) [-]"),
    Param("log_summary_values", False, "also log the topics that repeat another logged output: "
                                       "twin/flow_summary/<name> and twin/flow_residual/<name> (Float64), "
                                       "twin/revolution (= twin/flow_summary, which the shipped layouts label "
                                       "by name), twin/health_update (= twin/health) [-]"),
    Param("log_waveform_every", 500, "log every N-th published chamber waveform (1 = all) [-]", 1, 1000000),
    Param("log_outputs_every", 10, "log every N-th publication of chamber pressures (array and per "
                                  "chamber), delivery flow, eccentricity, tooth gaps, chamber peaks, twin/sample "
                                  "(1 = all; inputs, flow_summary and flow_residual: always all) [-]",
          1, 1000000),
    Param("log_diagnostics_every", 10, "log every N-th /diagnostics message (1 = all; ERROR/WARN changes "
                                      "are always logged) [-]", 1, 1000000),
    Param("log_rotate_mb", 100.0, "start a new MCAP file after this size [MB] (0 = never)", 0.0, 1e6),
    Param("log_rotate_s", 0.0, "start a new MCAP file after this duration [s] (0 = never)", 0.0, 1e7),
    Param("log_queue", 200000, "background MCAP writer queue [messages] (overflow is counted and dropped)",
          100, 10000000),
    Param("log_flush_s", 0.2, "write the open chunk to the file at least this often [s]: what a kill of "
                              "the process can lose", 0.01, 60.0),
    Param("log_chunk_kb", 1024, "MCAP chunk size that triggers a write before log_flush_s [KiB]", 1, 65536),
    Param("log_fsync", False, "fsync the log at each flush (also survives a power cut; more disk load) [-]"),
    Param("log_min_free_mb", 50.0, "after a write error (disk full) a new log file is started once this much "
                                   "space is free [MB]", 0.0, 1e6),
    Param("log_retry_s", 5.0, "period of the free-space check after a write error [s]", 0.1, 3600.0),
) + (
    # health monitor (gerotor_twin.twin.health); names = "health_" + HealthSettings field
    Param("diagnosis_in_background", True, "true: the health monitor's fault classifier runs in a worker thread "
                                           "beside the model thread, its naming published from the update after it "
                                           "finished; false: inside the model's tick (a classification holds the "
                                           "model up to a quarter second) [-]"),
    Param("health_adapt", False, "true: the estimated leakage factor feeds back into the model; false: pure monitor [-]"),
    Param("health_warn_pt", 2.0, "WARN when the reference efficiency fell this far below the calibrated one [%-pt]",
          0.0, 100.0),
    Param("health_error_pt", 5.0, "ERROR beyond this fall [%-pt] (>= health_warn_pt)", 0.0, 100.0),
    Param("health_reference_rpm", 1500.0, "speed of the reference operating point [rpm]", 1.0, 100000.0),
    Param("health_reference_bar", 20.0, "delivery pressure of the reference point [bar gauge] (capped at the pump's range.max_delivery_bar)", 0.0, 1000.0),
    Param("health_reference_oil_c", 50.0, "oil temperature of the reference point [degC] (used once the model "
                                          "takes the oil temperature)", -50.0, 300.0),
    Param("health_window_s", 1.0, "settled interval: one estimator update per window [s]", 0.05, 600.0),
    Param("health_settle_s", 1.0, "speed and pressure steady this long before a window counts [s] "
                                  "(>= 5 flow-meter time constants)", 0.0, 600.0),
    Param("health_flow_sensor_tau_s", 0.0, "time constant of the bench's flow meter [s]: the model's flows are "
                                           "read through the same lag before the windows and twin/flow_residual "
                                           "compare them (0: off)",
          0.0, 60.0),
    Param("health_drift_per_sqrt_s", 0.02, "random-walk drift of the leakage factor [1/sqrt(s)]: tracking speed "
                                           "vs noise", 0.0, 10.0),
    Param("health_model_sd_rel", 0.003, "model error of the mean flow, relative, in the measurement noise [-]",
          0.0, 1.0),
)


def twin_settings(prm: Mapping[str, Any]) -> TwinSettings:
    """The twin core's :class:`TwinSettings` from the node's parameter values.

    The publish period is ``publish_rate_hz`` rounded to a whole number of sample periods.
    """
    sp = prm["sample_period_s"]
    every = max(1, round(1.0 / (prm["publish_rate_hz"] * sp)))
    fields = {field: prm[name] for name, field in CORE_SETTINGS.items()}
    return TwinSettings(**fields, publish_period_s=every * sp)


def health_settings(prm: Mapping[str, Any]):
    """:class:`~gerotor_twin.twin.health.HealthSettings` from the node's ``health_*`` parameter values."""
    from gerotor_twin.twin.health import HealthSettings
    fields = {p.name[len("health_"):]: prm[p.name] for p in PARAMETERS if p.name.startswith("health_")}
    return HealthSettings(**fields)


#: Parameters rclpy declares itself on every node (Jazzy): name -> default.
BUILTIN: dict[str, Any] = {"use_sim_time": False, "start_type_description_service": True}

_BY_NAME = {p.name: p for p in PARAMETERS}


_TYPE_WORDS = {str: "a string", int: "an integer", float: "a double", bool: "a bool", list: "a list",
               dict: "a mapping", type(None): "no value"}


def _kind(default: Any) -> str:
    if isinstance(default, bool):
        return "bool"
    if isinstance(default, int):
        return "integer"
    if isinstance(default, float):
        return "double"
    return "string"


def check_value(name: str, value: Any, source: str = "") -> Any:
    """Validate one value for parameter ``name``; returns it typed (an integer given for a double becomes float).

    Raises
    ------
    InputError
        Unknown name (with the closest known ones), wrong type, out of range,
        not in the choice list; the field reads ``<source>: <name>``.
    """
    field = f"{source}: {name}" if source else name
    spec = _BY_NAME.get(name)
    default = spec.default if spec is not None else BUILTIN.get(name, None)
    if spec is None and name not in BUILTIN:
        known = [p.name for p in PARAMETERS] + list(BUILTIN)
        close = difflib.get_close_matches(name, known, n=3, cutoff=0.6)
        hint = f"did you mean {' or '.join(close)}?" if close else "see `ros2 param list` / docs/node.md for the names"
        raise InputError(field, value, "a parameter of twin_node", f"unknown parameter; {hint}")
    kind = _kind(default)
    ok = {"bool": isinstance(value, bool),
          "integer": isinstance(value, int) and not isinstance(value, bool),
          "double": isinstance(value, (int, float)) and not isinstance(value, bool),
          "string": isinstance(value, str)}[kind]
    if not ok:
        quote = " (quote it to make it a string)" if kind == "string" else ""
        got = _TYPE_WORDS.get(type(value), type(value).__name__)
        raise InputError(field, value, f"{'an' if kind == 'integer' else 'a'} {kind}{quote}", f"got {got}")
    if kind == "double":
        value = float(value)
    if spec is not None and spec.lo is not None:
        unit = spec.description.rsplit("[", 1)[-1].split("]")[0] if "[" in spec.description else ""
        if kind == "integer":
            if not spec.lo <= value <= spec.hi:
                raise InputError(field, value, f"an integer in [{int(spec.lo)}, {int(spec.hi)}] {unit}".strip())
        else:
            check_range(field, value, spec.lo, spec.hi, unit=unit)       # also refuses NaN / inf
    if spec is not None and spec.choices and value not in spec.choices:
        raise InputError(field, value, " | ".join(spec.choices))
    return value


def check_overrides(overrides: Mapping[str, Any]) -> dict[str, Any]:
    """Validate every given value: ``{name: Override or plain value}`` -> ``{name: typed value}``.

    Raises
    ------
    InputError
        For the first bad one (unknown names first, so a typo is reported even
        when another value is also wrong).
    """
    items = [(n, getattr(o, "value", o), getattr(o, "source", "")) for n, o in overrides.items()]
    items.sort(key=lambda it: (it[0] in _BY_NAME or it[0] in BUILTIN))
    return {n: check_value(n, v, src) for n, v, src in items}


def fixed_reason(name: str) -> str:
    """Why ``name`` cannot change while the node runs (the text of a refused ``ros2 param set``)."""
    if name == "use_sim_time":
        why = ("the clock source, the timers and the time base of the log are set up at start "
               "(switching it would silently stop all outputs)")
    elif name in ("pump_config", "bearing_model"):
        why = "the pump model is built from it at start"
    elif name == "startup_rtf_threshold":
        why = "the real-time factor is measured once, at start"
    elif name.endswith("_topic") or name in ("input_queue_depth", "input_coalesce_s"):
        why = "the subscriptions are created with it at start"
    elif name.startswith("log_"):
        why = "the MCAP log is opened with it at start"
    else:
        why = "the twin core and its timers are configured with it at start"
    return f"{name} cannot change while the node runs: {why}; restart the node with -p {name}:=<value>"


def refuse_change(current: Mapping[str, Any], params) -> tuple[bool, str]:
    """Decision of the run-time set-parameters callback: ``(ok, reason)``.

    ``params`` are objects with ``name`` and ``value``; setting a parameter to
    its current value is allowed (a no-op), any other value of a known
    parameter is refused with :func:`fixed_reason`.
    """
    for prm in params:
        if prm.name in current and prm.value != current[prm.name]:
            return False, fixed_reason(prm.name) + f" (asked: {short_repr(prm.value)})"
    return True, ""


def declare(node, given: Mapping[str, Any] | None = None) -> dict[str, Any]:
    """Declare :data:`PARAMETERS` on ``node`` (rclpy) with validated values; return all values.

    Parameters
    ----------
    node : rclpy.node.Node
    given : mapping, optional
        Values already validated by :func:`check_overrides` (from the command
        line, :func:`gerotor_twin.ros.param_args.overrides_from_args`).  If
        omitted, the overrides rclpy holds for the node are validated here
        (unknown names refused the same way).

    Raises
    ------
    InputError
        An unknown or invalid value (one line naming it).
    """
    from rcl_interfaces.msg import (FloatingPointRange, IntegerRange, ParameterDescriptor,
                                    SetParametersResult)
    from rclpy.parameter import Parameter

    if given is None:
        given = check_overrides({k: p.value for k, p in getattr(node, "_parameter_overrides", {}).items()})
    for p in PARAMETERS:
        d = ParameterDescriptor(description=p.description + " [fixed at start]")
        if p.choices:
            d.additional_constraints = "one of: " + ", ".join(p.choices)
        if p.lo is not None:
            if isinstance(p.default, int) and not isinstance(p.default, bool):
                d.integer_range = [IntegerRange(from_value=int(p.lo), to_value=int(p.hi), step=1)]
            else:
                d.floating_point_range = [FloatingPointRange(from_value=float(p.lo), to_value=float(p.hi),
                                                             step=0.0)]
        node.declare_parameter(p.name, given.get(p.name, p.default), d, ignore_override=True)
    if "use_sim_time" in given and node.get_parameter("use_sim_time").value != given["use_sim_time"]:
        node.set_parameters([Parameter("use_sim_time", value=given["use_sim_time"])])
    current = values(node)

    def on_set(params):
        ok, reason = refuse_change(current, params)
        return SetParametersResult(successful=ok, reason=reason)

    node.add_on_set_parameters_callback(on_set)
    return current


def values(node) -> dict[str, Any]:
    """Current values of :data:`PARAMETERS` (plus ``use_sim_time``)."""
    out = {p.name: node.get_parameter(p.name).value for p in PARAMETERS}
    out["use_sim_time"] = node.get_parameter("use_sim_time").value
    return out
