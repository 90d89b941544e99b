"""The ``rosbag2`` Metadata record, as rosbag2's MCAP storage plugin writes it (Jazzy).

``rosbag2_storage_mcap`` (``MCAPStorage::update_metadata``, ros2/rosbag2 branch
``jazzy``) writes one MCAP Metadata record named ``rosbag2`` with the key
``serialized_metadata``: the bag's ``BagMetadata`` (metadata version 9) dumped
as YAML by ``YAML::convert<BagMetadata>::encode`` (rosbag2_storage/yaml.hpp)::

    version: 9
    storage_identifier: mcap
    duration:
      nanoseconds: <last - first message log time>
    starting_time:
      nanoseconds_since_epoch: <first message log time>
    message_count: <n>
    topics_with_message_count:
      - topic_metadata:
          name: /bench/shaft_speed
          type: sensor_msgs/msg/JointState
          serialization_format: cdr
          offered_qos_profiles: [<QoS maps, by policy name>]
          type_description_hash: RIHS01_...
        message_count: <n>
    compression_format: ""
    compression_mode: ""
    relative_file_paths: [<file name>]
    files: [{path, starting_time, duration, message_count}]
    custom_data: {}
    ros_distro: jazzy

``ros2 bag info`` reads ``ros_distro`` (and custom data) from it; message
counts and times it takes from the Statistics record.  The record is
written at close (rosbag2 does the same, at close and at each split) and by
:func:`gerotor_twin.io.recover.recover`.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import yaml

from gerotor_twin.yaml_safe import load_yaml

__all__ = ["ROSBAG2_METADATA", "ROS_DISTRO", "BAG_METADATA_VERSION", "TopicCount", "rosbag2_record"]

#: Metadata record name and its key, as in rosbag2_storage_mcap.
ROSBAG2_METADATA = "rosbag2"
_KEY = "serialized_metadata"
ROS_DISTRO = "jazzy"
#: ``BagMetadata::version`` of Jazzy's rosbag2_storage.
BAG_METADATA_VERSION = 9


@dataclass(frozen=True)
class TopicCount:
    """One topic of a file and its message count.

    Attributes
    ----------
    name, msgtype : str
        Topic and ``pkg/msg/Type``.
    qos_yaml : str
        The channel's ``offered_qos_profiles`` (YAML sequence, Jazzy form).
    type_hash : str
        The channel's ``topic_type_hash`` (``RIHS01_...``; '' if unknown).
    count : int
        Messages [-].
    """

    name: str
    msgtype: str
    qos_yaml: str
    type_hash: str
    count: int


def rosbag2_record(file_name: str, topics: Iterable[TopicCount], first_ns: int | None,
                   last_ns: int | None, compression: str = "") -> dict[str, str]:
    """The key/value map of the ``rosbag2`` Metadata record of one MCAP file.

    Parameters
    ----------
    file_name : str
        The file's name (``relative_file_paths``; rosbag2 stores names relative to the bag).
    topics : iterable of TopicCount
    first_ns, last_ns : int or None
        First and last message log time [ns] (None: no messages).
    compression : str
        Chunk compression (informative only; rosbag2 leaves ``compression_format``
        empty for MCAP chunk compression, and so do we).

    Returns
    -------
    dict[str, str]
        ``{"serialized_metadata": <YAML>}``.
    """
    del compression  # chunk compression is a storage detail, not rosbag2 file compression
    topics = list(topics)
    start = int(first_ns or 0)
    duration = 0 if first_ns is None or last_ns is None else int(last_ns - first_ns)
    count = sum(t.count for t in topics)
    doc = {
        "version": BAG_METADATA_VERSION,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": count,
        "topics_with_message_count": [
            {"topic_metadata": {"name": t.name, "type": t.msgtype, "serialization_format": "cdr",
                                "offered_qos_profiles": load_yaml(t.qos_yaml, "offered_qos_profiles") or [],
                                "type_description_hash": t.type_hash},
             "message_count": t.count} for t in topics],
        "compression_format": "",
        "compression_mode": "",
        "relative_file_paths": [file_name],
        "files": [{"path": file_name, "starting_time": {"nanoseconds_since_epoch": start},
                   "duration": {"nanoseconds": duration}, "message_count": count}],
        "custom_data": {},
        "ros_distro": ROS_DISTRO,
    }
    return {_KEY: yaml.safe_dump(doc, sort_keys=False, default_flow_style=False)}
