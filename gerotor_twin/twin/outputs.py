"""Output topics of the twin and the dict messages the core emits (no rclpy).

==========================  ===============================  ==========================================
topic (relative)            type                             content (SI)
==========================  ===============================  ==========================================
``twin/chamber_pressures``  std_msgs/Float64MultiArray       N chamber pressures, absolute [Pa];
                                                             layout label ``chamber``
``twin/delivery_flow``      std_msgs/Float64                 instantaneous delivery flow [m³/s]
``twin/flow_summary``       std_msgs/Float64MultiArray       once per revolution, 4 values, layout label
                                                             :data:`SUMMARY_LABEL`: revolution-mean
                                                             delivery, theoretical, leakage [m³/s],
                                                             volumetric efficiency [-]
``twin/flow_summary/<name>`` std_msgs/Float64                 the same four values, one topic each, named
                                                             by :data:`SUMMARY_FIELDS` (so Foxglove and
                                                             PlotJuggler, which show a multi-array as
                                                             ``data[0..3]``, find each by name)
``twin/eccentricity``       geometry_msgs/Vector3Stamped     outer-gear centre displacement [m],
                                                             frame ``pump_housing`` (z = 0)
``twin/tooth_gaps``         std_msgs/Float64MultiArray       N minimum tooth-tip gap heights [m] since
                                                             the previous publication; label ``gap``
``twin/chamber_peak_pressures`` std_msgs/Float64MultiArray   N highest chamber pressures, absolute [Pa],
                                                             since the previous publication, from the
                                                             solver's sub-steps (a spike between two
                                                             output angles included); label ``chamber``
``twin/chamber_waveform``   std_msgs/Float64MultiArray       once per revolution: 2-D (``sample`` ×
                                                             ``angle_p``): column 0 the angle within the
                                                             revolution [rad], columns 1..N the chamber
                                                             pressures [Pa]
``twin/chambers/<chamber>/  sensor_msgs/FluidPressure        one topic per chamber, named by
pressure``                                                   :func:`chamber_names` (``chamber_01`` is
                                                             ``data[0]`` of ``twin/chamber_pressures``):
                                                             absolute pressure [Pa], header stamp = model
                                                             time of the sample, frame ``pump_housing``
``twin/flow_residual``      sensor_msgs/JointState           once per revolution with a measured flow:
                                                             ``name`` = :data:`RESIDUAL_FIELDS` (units in
                                                             the names), ``position`` = the values, header
                                                             stamp = the revolution's end (model time);
                                                             :mod:`gerotor_twin.twin.residual`
``twin/flow_residual/<name>`` std_msgs/Float64               the same values, one topic each
``twin/sample``             sensor_msgs/JointState           at each publication: the instantaneous
                                                             scalar and per-chamber values by name
                                                             (:func:`sample_names`), header stamp = model
                                                             time of the sample
``twin/revolution``         sensor_msgs/JointState           once per revolution: the ``twin/flow_summary``
                                                             values by name (:data:`SUMMARY_FIELDS`),
                                                             header stamp = the revolution's end
``twin/health_update``      sensor_msgs/JointState           the ``twin/health`` values by name, header
                                                             stamp = the end of the estimator's interval
==========================  ===============================  ==========================================

An :class:`OutputMessage` is ``(topic, msgtype, stamp_ns, msg)``; ``msg`` is a
:mod:`gerotor_twin.io.messages` dict ready for
:func:`gerotor_twin.io.codec.encode` or ``McapLog.write``.  ``stamp_ns`` is the
clock time of the prediction (the MCAP ``log_time``, and the header stamp of the stamped types):
the model time of the sample, computed over the sample cell that ends there with the bench
inputs received (node clock) at or before the cell's start.
"""
from __future__ import annotations

import functools
from typing import Callable, NamedTuple

import numpy as np

from gerotor_twin.io import messages as m

__all__ = ["OutputMessage", "OUTPUT_TOPICS", "SUMMARY_FIELDS", "SUMMARY_LABEL", "SUMMARY_VALUE_TOPICS",
           "INSTANT_TOPICS", "DIAGNOSTICS_TOPIC", "RESIDUAL_FIELDS", "RESIDUAL_VALUE_TOPICS", "VALUE_TOPICS",
           "summary_messages", "residual_messages", "named_values", "log_topics", "output_topics", "chamber_names",
           "chamber_pressure_topics", "sample_names", "is_instant", "all_finite"]

CHAMBER_PRESSURES = "twin/chamber_pressures"
DELIVERY_FLOW = "twin/delivery_flow"
FLOW_SUMMARY = "twin/flow_summary"
ECCENTRICITY = "twin/eccentricity"
TOOTH_GAPS = "twin/tooth_gaps"
CHAMBER_PEAKS = "twin/chamber_peak_pressures"
CHAMBER_WAVEFORM = "twin/chamber_waveform"
FLOW_RESIDUAL = "twin/flow_residual"
SAMPLE = "twin/sample"          #: stamped, named companion of the instantaneous scalar and per-chamber outputs
REVOLUTION = "twin/revolution"  #: stamped, named companion of ``twin/flow_summary``
HEALTH_UPDATE = "twin/health_update"   #: stamped, named companion of ``twin/health``
CHAMBERS = "twin/chambers"      #: prefix of the per-chamber topics ``twin/chambers/<chamber>/pressure``
HEALTH = "twin/health"          #: health estimate, once per settled interval (:mod:`gerotor_twin.twin.health`)
DIAGNOSTICS_TOPIC = "/diagnostics"

#: topic -> message type of every output of the core (``/diagnostics`` is separate).
OUTPUT_TOPICS: dict[str, str] = {
    CHAMBER_PRESSURES: m.FLOAT64_MULTIARRAY,
    DELIVERY_FLOW: m.FLOAT64,
    FLOW_SUMMARY: m.FLOAT64_MULTIARRAY,
    ECCENTRICITY: m.VECTOR3_STAMPED,
    TOOTH_GAPS: m.FLOAT64_MULTIARRAY,
    CHAMBER_PEAKS: m.FLOAT64_MULTIARRAY,
    CHAMBER_WAVEFORM: m.FLOAT64_MULTIARRAY,
    HEALTH: m.FLOAT64_MULTIARRAY,
    FLOW_RESIDUAL: m.JOINT_STATE,
    SAMPLE: m.JOINT_STATE,
    REVOLUTION: m.JOINT_STATE,
    HEALTH_UPDATE: m.JOINT_STATE,
}

#: The outputs published at ``publish_rate_hz`` (instantaneous values; also the per-chamber topics).
INSTANT_TOPICS = (CHAMBER_PRESSURES, DELIVERY_FLOW, ECCENTRICITY, TOOTH_GAPS, CHAMBER_PEAKS, SAMPLE)
#: Order of the values in ``twin/flow_summary``.
SUMMARY_FIELDS = ("mean_delivery_m3s", "theoretical_m3s", "leakage_m3s", "volumetric_efficiency")
#: One std_msgs/Float64 topic per summary value: ``twin/flow_summary/<field>``.
SUMMARY_VALUE_TOPICS = tuple(f"{FLOW_SUMMARY}/{f}" for f in SUMMARY_FIELDS)
OUTPUT_TOPICS.update({t: m.FLOAT64 for t in SUMMARY_VALUE_TOPICS})
#: Its layout label (the field names, comma separated).
SUMMARY_LABEL = ",".join(SUMMARY_FIELDS)
#: Names (= order) of the values in ``twin/flow_residual``; the unit is the name's suffix
#: (``m3s`` = m³/s, efficiencies [-]): measured, predicted and measured − predicted revolution-mean
#: delivery flow, then the same for the volumetric efficiency.
RESIDUAL_FIELDS = ("measured_delivery_m3s", "predicted_delivery_m3s", "delivery_residual_m3s",
                   "measured_volumetric_efficiency", "predicted_volumetric_efficiency",
                   "volumetric_efficiency_residual")
#: One std_msgs/Float64 topic per residual value: ``twin/flow_residual/<field>``.
RESIDUAL_VALUE_TOPICS = tuple(f"{FLOW_RESIDUAL}/{f}" for f in RESIDUAL_FIELDS)
OUTPUT_TOPICS.update({t: m.FLOAT64 for t in RESIDUAL_VALUE_TOPICS})
#: The topics that repeat another output's values at its log time (logged only with ``log_summary_values``):
#: the per-value Float64 topics, ``twin/revolution`` (= ``twin/flow_summary``) and ``twin/health_update``
#: (= ``twin/health``), whose originals are always logged.
VALUE_TOPICS = frozenset(SUMMARY_VALUE_TOPICS + RESIDUAL_VALUE_TOPICS + (REVOLUTION, HEALTH_UPDATE))


@functools.lru_cache(maxsize=64)
def chamber_names(n: int) -> tuple[str, ...]:
    """Stable names of the ``n`` chambers: ``chamber_01`` ... (index k of a chamber array = ``chamber_{k+1}``).

    Zero-padded to two digits (three from 100 chambers), so the names sort in chamber order.
    """
    width = max(2, len(str(n)))
    return tuple(f"chamber_{k + 1:0{width}d}" for k in range(n))


@functools.lru_cache(maxsize=64)
def sample_names(n: int) -> tuple[str, ...]:
    """Names of the ``twin/sample`` values of a pump with ``n`` chambers (unit = the name's suffix).

    ``delivery_flow_m3s``, ``eccentricity_x_m``, ``eccentricity_y_m``, then per chamber
    ``<chamber>_peak_pressure_pa`` (``twin/chamber_peak_pressures``), then per tooth-tip gap
    ``tooth_gap_<k>_min_m`` (``twin/tooth_gaps``), k numbered like the chambers.
    """
    names = chamber_names(n)
    return (("delivery_flow_m3s", "eccentricity_x_m", "eccentricity_y_m")
            + tuple(f"{c}_peak_pressure_pa" for c in names)
            + tuple(f"tooth_gap_{c[len('chamber_'):]}_min_m" for c in names))


@functools.lru_cache(maxsize=64)
def chamber_pressure_topics(n: int) -> tuple[str, ...]:
    """``twin/chambers/<chamber>/pressure`` for each of the ``n`` chambers, in chamber order."""
    return tuple(f"{CHAMBERS}/{name}/pressure" for name in chamber_names(n))


def output_topics(n_chambers: int) -> dict[str, str]:
    """Topic -> message type of every output of a twin of a pump with ``n_chambers`` chambers.

    :data:`OUTPUT_TOPICS` and the per-chamber ``twin/chambers/<chamber>/pressure`` topics.
    """
    return {**OUTPUT_TOPICS, **{t: m.FLUID_PRESSURE for t in chamber_pressure_topics(n_chambers)}}


def is_instant(topic: str) -> bool:
    """Whether ``topic`` is published at ``publish_rate_hz`` (an instantaneous output)."""
    return topic in INSTANT_TOPICS or topic.startswith(CHAMBERS + "/")


def log_topics(inputs: dict[str, str], names: dict[str, str] | None = None,
               logged: Callable[[str], bool] = lambda topic: True,
               outputs: dict[str, str] | None = None) -> list[tuple[str, str, str]]:
    """The channels of a twin log, the node's and run-bag's alike: ``(topic, msgtype, qos)``.

    Parameters
    ----------
    inputs : dict
        Input topic (as received) -> message type; logged with sensor-data QoS.
    names : dict, optional
        Relative output name -> fully qualified (remapped) topic; default ``"/" + name``.
    logged : callable
        Which outputs have a channel (the node's log policy); ``/diagnostics`` always.
    outputs : dict, optional
        Output topic -> message type (:func:`output_topics` of the pump); default :data:`OUTPUT_TOPICS`.
    """
    names = names or {}
    out = [(t, mt, "sensor") for t, mt in inputs.items()]
    out += [(names.get(t, "/" + t), mt, "reliable") for t, mt in (outputs or OUTPUT_TOPICS).items() if logged(t)]
    out.append((names.get(DIAGNOSTICS_TOPIC, DIAGNOSTICS_TOPIC), m.DIAGNOSTIC_ARRAY, "reliable"))
    return out


class OutputMessage(NamedTuple):
    """One message the core wants published (and logged)."""
    topic: str          #: relative topic name, e.g. ``twin/delivery_flow``
    msgtype: str        #: ``pkg/msg/Type``
    stamp_ns: int       #: clock time of the prediction [ns]
    msg: dict           #: :mod:`gerotor_twin.io.messages` dict


def all_finite(*arrays) -> bool:
    """True if every value of every argument is finite."""
    return all(bool(np.all(np.isfinite(np.asarray(a, dtype=float)))) for a in arrays)


def instantaneous(stamp_ns: int, pressures, flow: float, ecc, gaps_min, peaks) -> list[OutputMessage]:
    """The periodic outputs at one instant (caller checked finiteness).

    ``pressures`` [Pa], ``flow`` [m³/s], ``ecc`` [m] at the instant; ``gaps_min`` [m] and ``peaks``
    [Pa] per chamber since the previous publication.
    """
    values = np.concatenate(([flow, ecc[0], ecc[1]], peaks, gaps_min))
    return (_arrays(stamp_ns, pressures, flow, ecc, gaps_min, peaks) + chamber_messages(stamp_ns, pressures)
            + [named_values(SAMPLE, stamp_ns, sample_names(len(pressures)), values)])


def named_values(topic: str, stamp_ns: int, names, values) -> OutputMessage:
    """A stamped, named record: sensor_msgs/JointState with ``name`` = ``names`` and ``position`` = ``values``.

    The form of every named companion (``twin/sample``, ``twin/revolution``, ``twin/flow_residual``,
    ``twin/health_update``): header stamp = ``stamp_ns`` [ns], frame ``pump_housing``; ``velocity`` and
    ``effort`` empty; each value in the unit its name ends with.
    """
    return OutputMessage(topic, m.JOINT_STATE, stamp_ns,
                         m.joint_state(stamp_ns, name=names, position=values, frame_id=m.PUMP_FRAME))


def chamber_messages(stamp_ns: int, pressures) -> list[OutputMessage]:
    """``twin/chambers/<chamber>/pressure`` (sensor_msgs/FluidPressure [Pa]) of each chamber at one instant."""
    return [OutputMessage(topic, m.FLUID_PRESSURE, stamp_ns, m.fluid_pressure(stamp_ns, p, frame_id=m.PUMP_FRAME))
            for topic, p in zip(chamber_pressure_topics(len(pressures)), pressures)]


def _arrays(stamp_ns: int, pressures, flow: float, ecc, gaps_min, peaks) -> list[OutputMessage]:
    """The array, flow and eccentricity topics at one instant."""
    return [
        OutputMessage(CHAMBER_PRESSURES, m.FLOAT64_MULTIARRAY, stamp_ns,
                      m.float64_multiarray(pressures, ("chamber",))),
        OutputMessage(DELIVERY_FLOW, m.FLOAT64, stamp_ns, m.float64(flow)),
        OutputMessage(ECCENTRICITY, m.VECTOR3_STAMPED, stamp_ns,
                      m.vector3_stamped(stamp_ns, float(ecc[0]), float(ecc[1]), 0.0)),
        OutputMessage(TOOTH_GAPS, m.FLOAT64_MULTIARRAY, stamp_ns, m.float64_multiarray(gaps_min, ("gap",))),
        OutputMessage(CHAMBER_PEAKS, m.FLOAT64_MULTIARRAY, stamp_ns, m.float64_multiarray(peaks, ("chamber",))),
    ]


def summary(stamp_ns: int, values) -> OutputMessage:
    """``twin/flow_summary`` (values in :data:`SUMMARY_FIELDS` order)."""
    return OutputMessage(FLOW_SUMMARY, m.FLOAT64_MULTIARRAY, stamp_ns,
                         m.float64_multiarray(values, (SUMMARY_LABEL,)))


def summary_messages(stamp_ns: int, values) -> list[OutputMessage]:
    """``twin/flow_summary``, its stamped companion ``twin/revolution`` (sensor_msgs/JointState, names
    :data:`SUMMARY_FIELDS`) and one ``twin/flow_summary/<field>`` Float64 per value."""
    return [summary(stamp_ns, values), named_values(REVOLUTION, stamp_ns, SUMMARY_FIELDS, values)] + [
        OutputMessage(topic, m.FLOAT64, stamp_ns, m.float64(float(v)))
        for topic, v in zip(SUMMARY_VALUE_TOPICS, values)]


def waveform(stamp_ns: int, table) -> OutputMessage:
    """``twin/chamber_waveform`` from a (samples, 1 + N) table."""
    return OutputMessage(CHAMBER_WAVEFORM, m.FLOAT64_MULTIARRAY, stamp_ns,
                         m.float64_multiarray(table, ("sample", "angle_p")))


def residual_messages(stamp_ns: int, values) -> list[OutputMessage]:
    """``twin/flow_residual`` (sensor_msgs/JointState, names :data:`RESIDUAL_FIELDS`, values in ``position``)
    and one ``twin/flow_residual/<field>`` Float64 per value."""
    return [named_values(FLOW_RESIDUAL, stamp_ns, RESIDUAL_FIELDS, values)] + [
        OutputMessage(topic, m.FLOAT64, stamp_ns, m.float64(float(v)))
        for topic, v in zip(RESIDUAL_VALUE_TOPICS, values)]
