"""The digital-twin core, ROS-free: used by the ROS node and by offline runs alike.

Example (offline: the same calls the node makes)::

    from gerotor_twin.config import load_config
    from gerotor_twin.model.pump import PumpModel
    from gerotor_twin.twin import TwinCore, TwinSettings

    core = TwinCore(PumpModel(load_config(), "mobility"), TwinSettings(max_span_s=float("inf")))
    t = 0
    for k in range(400):                         # 2 s of a bench at 1500 rpm, 20 bar gauge
        t = k * 5_000_000                        # [ns], the node's clock
        core.add_sample("shaft_speed", 157.08, t, t)             # value, header stamp, receive time
        core.add_sample("delivery_pressure", 2.101325e6, t, t)   # [Pa absolute]
        result = core.tick(t)
        for msg in result.messages:   # OutputMessage(topic, msgtype, stamp_ns, msg dict)
            ...                       # publish / log msg.msg under msg.topic
    print(core.snapshot(t)["last_summary"])      # mean delivery, theoretical, leakage, eta

==================  =======================================================
module              content
==================  =======================================================
``core``            :class:`TwinCore`, :class:`TickResult`: the façade the node
                    and run-bag call; the lag / bad-input policy (documented
                    in its module docstring); reporting (snapshot, diagnostics)
``input_book``      :class:`InputBook`: channels, validation, stamp guard,
                    sources, sequence gaps, input report
``clock_driver``    :class:`ClockDriver`: the model state advanced cell by cell
                    to the clock (hold, skip, reset, instantaneous outputs)
``revolution``      :class:`RevolutionRecorder`, :class:`Revolution`: flow
                    summary and waveform of each completed revolution
``events``          :class:`EventLog`: rate-limited ``(level, text)`` events
``settings``        :class:`TwinSettings` (sample grid, publish period, lag,
                    staleness, filtering, waveform)
``inputs``          :data:`INPUTS` (kinds, default topics, types, units),
                    :func:`sample_from_message`, :class:`InputChannel`
``outputs``         :data:`OUTPUT_TOPICS`, :class:`OutputMessage`, flow-summary
                    layout
``diagnostics``     DiagnosticStatus dicts from :meth:`TwinCore.snapshot`
``sequence``        :class:`SequenceGaps`: inputs lost before reception, from
                    gaps in the publishers' sequence numbers; the
                    ``gerotor_twin.input_accounting`` MCAP record
``inbox``           :class:`Inbox`: receiving thread -> model thread hand-over
``startup_rtf``     :func:`measure`, :class:`StartupRtf`: the model's real-time
                    factor on this machine at the pump's top speed, measured
                    at start (``gerotor_twin: real time`` status)
==================  =======================================================
"""
from gerotor_twin.twin.core import TickResult, TwinCore
from gerotor_twin.twin.inputs import INPUTS, REQUIRED, InputSpec, sample_from_message
from gerotor_twin.twin.outputs import (DIAGNOSTICS_TOPIC, OUTPUT_TOPICS, SUMMARY_FIELDS, SUMMARY_LABEL,
                                       OutputMessage)
from gerotor_twin.twin.settings import TwinSettings

__all__ = ["TwinCore", "TickResult", "TwinSettings", "INPUTS", "REQUIRED", "InputSpec",
           "sample_from_message", "OUTPUT_TOPICS", "OutputMessage", "SUMMARY_FIELDS", "SUMMARY_LABEL",
           "DIAGNOSTICS_TOPIC"]
