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
``residual``        :class:`FlowResidual`: measured against predicted
                    revolution-mean flow (``twin/flow_residual``);
                    :class:`FlowSamples`, the flow-meter samples
``events``          :class:`EventLog`: rate-limited ``(level, text)`` events
``settings``        :class:`TwinSettings` (sample grid, publish period, lag,
                    staleness, filtering, waveform)
``inputs``          :data:`INPUTS` (kinds, default topics, types, units),
                    :func:`sample_from_message`, :class:`InputChannel`
``outputs``         :data:`OUTPUT_TOPICS`, :func:`output_topics` (with the
                    per-chamber topics), :class:`OutputMessage`, flow-summary
                    and residual layout, chamber names
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
from importlib import import_module

#: Public name -> the module that defines it.  Loaded on first use (PEP 562), so that importing a light
#: module such as ``gerotor_twin.twin.settings`` (the node's parameter table takes its defaults from it)
#: does not load the model and numba.
_EXPORTS = {
    "TwinCore": "core", "TickResult": "core", "TwinSettings": "settings",
    "INPUTS": "inputs", "REQUIRED": "inputs", "InputSpec": "inputs", "sample_from_message": "inputs",
    "OUTPUT_TOPICS": "outputs", "OutputMessage": "outputs", "SUMMARY_FIELDS": "outputs",
    "SUMMARY_LABEL": "outputs", "DIAGNOSTICS_TOPIC": "outputs",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    """The public name ``name``, imported from its module on first use."""
    if name not in _EXPORTS:
        raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
    value = getattr(import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    globals()[name] = value
    return value
