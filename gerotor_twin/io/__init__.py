"""MCAP input/output of ROS 2 messages without rclpy (``mcap``, ``mcap-ros2-support``).

Files follow rosbag2's MCAP conventions (profile ``ros2``, ``ros2msg``
schemas from the installed interfaces, ``cdr`` messages, channel metadata
``offered_qos_profiles`` and ``topic_type_hash``), so ``ros2 bag play``,
Foxglove, PlotJuggler and ``rosbags`` read them.  See ``docs/mcap.md``.

==================  =============================================================
module              responsibility
==================  =============================================================
``schemas``         ``.msg`` lookup in ``AMENT_PREFIX_PATH``/``sys.prefix``, the
                    rosbag2 ``ros2msg`` complete definition, ``RIHS01`` type hash
``qos``             ``offered_qos_profiles`` YAML (Jazzy form); sensor / reliable
``codec``           dict/object -> CDR bytes (field names checked, NumPy accepted)
``fastcdr``         the node's fast encoder (Float64MultiArray by struct, the rest by codec)
``decode``          CDR bytes -> message (no rclpy), for raw subscriptions
``messages``        dict builders: JointState, FluidPressure, Temperature, Float64,
                    Float64MultiArray (labelled layout), Vector3Stamped,
                    DiagnosticArray, Clock; ``stamp_from_ns``
``mcap_log``        :class:`McapLog` (one file/stream), :class:`RotatingMcapLog`
``background``      :class:`BackgroundMcapLog`: writer thread, bounded queue,
                    counted drops, periodic flush, resume after a write error
                    (:class:`~gerotor_twin.io.background.Reopen`), signal-safe ``close()``
``rosbag2_meta``    the ``rosbag2`` Metadata record (BagMetadata v9, ``ros_distro: jazzy``)
``recover``         :func:`~gerotor_twin.io.recover.recover` (``gerotor-twin log recover``),
                    :func:`~gerotor_twin.io.recover.unfinalised_logs` of dead writers
``reader``          :func:`open_mcap` (clear errors, truncated-file recovery),
                    :func:`read_topics` -> :class:`TopicSeries`, :func:`require`,
                    :func:`scalar_series`, :func:`multiarray_series`, metadata
==================  =============================================================

Imports point one way: schemas, qos <- codec <- mcap_log <- background;
rosbag2_meta <- mcap_log; messages, schemas <- reader; reader, mcap_log <- recover.  Nothing here imports rclpy.
"""
from gerotor_twin.io.background import BackgroundMcapLog, LogStats
from gerotor_twin.io.mcap_log import McapLog, McapLogClosed, RotatingMcapLog
from gerotor_twin.io.qos import RELIABLE, SENSOR_DATA, QosProfile
from gerotor_twin.io.reader import (McapReadError, TopicSeries, TruncatedMcapWarning, metadata,
                                    multiarray_series, open_mcap, read_topics, require,
                                    scalar_series, topic_types)
from gerotor_twin.io.schemas import UnknownMessageType, message_definition

__all__ = [
    "BackgroundMcapLog", "LogStats", "McapLog", "McapLogClosed", "RotatingMcapLog",
    "QosProfile", "RELIABLE", "SENSOR_DATA",
    "McapReadError", "TopicSeries", "TruncatedMcapWarning", "open_mcap", "read_topics",
    "require", "topic_types", "metadata", "scalar_series", "multiarray_series",
    "UnknownMessageType", "message_definition",
]
