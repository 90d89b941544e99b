"""QoS profiles as rosbag2 (Jazzy) stores them in MCAP channel metadata.

rosbag2 puts the QoS offered by the publishers of a topic into the channel
metadata key ``offered_qos_profiles`` as a YAML sequence of maps, written by
``rosbag2_storage::serialize_rclcpp_qos_vector`` (yaml-cpp, block style, key
order below, no trailing newline).  Since metadata version 9 (Jazzy) the
policies are stored by name (``keep_last``, ``best_effort``, ...), durations as
``{sec, nsec}`` with ``RMW_DURATION_INFINITE`` = 9223372036 s 854775807 ns::

    - history: keep_last
      depth: 5
      reliability: best_effort
      durability: volatile
      deadline:
        sec: 9223372036
        nsec: 854775807
      lifespan:
        ...
      liveliness: automatic
      liveliness_lease_duration:
        ...
      avoid_ros_namespace_conventions: false

``ros2 bag play`` re-offers the recorded profile (with its default history),
so the two profiles used here reproduce what a Jazzy recorder would store for
the node's own publishers: :data:`SENSOR_DATA` (bench inputs, like rclpy's
``qos_profile_sensor_data``) and :data:`RELIABLE` (twin outputs).  Durations
and liveliness are the values a Fast DDS endpoint reports for "default"
(infinite, automatic).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Sequence, Union


from gerotor_twin.errors import InputError

__all__ = [
    "DURATION_INFINITE_NS",
    "QosProfile",
    "SENSOR_DATA",
    "RELIABLE",
    "offered_qos_yaml",
    "parse_offered_qos",
    "resolve_qos",
]

#: RMW_DURATION_INFINITE [ns] (= 2**63 - 1).
DURATION_INFINITE_NS = 2**63 - 1

_HISTORY = ("system_default", "keep_last", "keep_all", "unknown")
_RELIABILITY = ("system_default", "reliable", "best_effort", "best_available", "unknown")
_DURABILITY = ("system_default", "transient_local", "volatile", "best_available", "unknown")
_LIVELINESS = ("system_default", "automatic", "manual_by_topic", "best_available", "unknown")
_KEYS = ("history", "depth", "reliability", "durability", "deadline", "lifespan",
         "liveliness", "liveliness_lease_duration", "avoid_ros_namespace_conventions")


def _check_choice(field: str, value: str, allowed: tuple[str, ...]) -> str:
    if value not in allowed:
        raise InputError(f"qos.{field}", value, " | ".join(allowed))
    return value


def _check_ns(field: str, value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= DURATION_INFINITE_NS:
        raise InputError(f"qos.{field}", value, f"an integer in [0, {DURATION_INFINITE_NS}] ns")
    return value


@dataclass(frozen=True)
class QosProfile:
    """One offered QoS profile (the fields rosbag2 records).

    Attributes
    ----------
    history : str
        ``keep_last`` | ``keep_all`` | ``system_default`` | ``unknown``.
    depth : int
        History depth [messages] (meaningful for ``keep_last``).
    reliability : str
        ``reliable`` | ``best_effort`` | ``system_default`` | ``best_available`` | ``unknown``.
    durability : str
        ``volatile`` | ``transient_local`` | ``system_default`` | ``best_available`` | ``unknown``.
    deadline_ns, lifespan_ns, liveliness_lease_duration_ns : int
        Durations [ns]; :data:`DURATION_INFINITE_NS` means infinite.
    liveliness : str
        ``automatic`` | ``manual_by_topic`` | ``system_default`` | ``best_available`` | ``unknown``.
    avoid_ros_namespace_conventions : bool
    """

    history: str = "keep_last"
    depth: int = 10
    reliability: str = "reliable"
    durability: str = "volatile"
    deadline_ns: int = DURATION_INFINITE_NS
    lifespan_ns: int = DURATION_INFINITE_NS
    liveliness: str = "automatic"
    liveliness_lease_duration_ns: int = DURATION_INFINITE_NS
    avoid_ros_namespace_conventions: bool = False

    def __post_init__(self) -> None:
        _check_choice("history", self.history, _HISTORY)
        _check_choice("reliability", self.reliability, _RELIABILITY)
        _check_choice("durability", self.durability, _DURABILITY)
        _check_choice("liveliness", self.liveliness, _LIVELINESS)
        if isinstance(self.depth, bool) or not isinstance(self.depth, int) or self.depth < 0:
            raise InputError("qos.depth", self.depth, "an integer >= 0")
        for f in ("deadline_ns", "lifespan_ns", "liveliness_lease_duration_ns"):
            _check_ns(f[:-3], getattr(self, f))
        if not isinstance(self.avoid_ros_namespace_conventions, bool):
            raise InputError("qos.avoid_ros_namespace_conventions",
                             self.avoid_ros_namespace_conventions, "true | false")

    def yaml_lines(self) -> list[str]:
        """This profile as one item of the YAML sequence (yaml-cpp layout)."""
        def dur(name: str, ns: int) -> list[str]:
            return [f"  {name}:", f"    sec: {ns // 1_000_000_000}", f"    nsec: {ns % 1_000_000_000}"]

        return [f"- history: {self.history}",
                f"  depth: {self.depth}",
                f"  reliability: {self.reliability}",
                f"  durability: {self.durability}",
                *dur("deadline", self.deadline_ns),
                *dur("lifespan", self.lifespan_ns),
                f"  liveliness: {self.liveliness}",
                *dur("liveliness_lease_duration", self.liveliness_lease_duration_ns),
                f"  avoid_ros_namespace_conventions: {str(self.avoid_ros_namespace_conventions).lower()}"]


#: Sensor-data QoS (bench inputs): best effort, volatile, keep last 5.
SENSOR_DATA = QosProfile(history="keep_last", depth=5, reliability="best_effort", durability="volatile")
#: Twin outputs: reliable, volatile, keep last 10.
RELIABLE = QosProfile(history="keep_last", depth=10, reliability="reliable", durability="volatile")

QosSpec = Union[str, QosProfile, Sequence[QosProfile]]


def offered_qos_yaml(profiles: QosProfile | Sequence[QosProfile]) -> str:
    """The ``offered_qos_profiles`` string for one or several profiles.

    An empty sequence gives ``"[]"`` (what yaml-cpp dumps for no profiles).
    """
    if isinstance(profiles, QosProfile):
        profiles = [profiles]
    if len(profiles) == 0:
        return "[]"
    return "\n".join(line for p in profiles for line in p.yaml_lines())


def _duration_ns(field: str, node: object) -> int:
    if not isinstance(node, dict) or set(node) != {"sec", "nsec"}:
        raise InputError(f"qos.{field}", node, "a map {sec, nsec}")
    sec, nsec = node["sec"], node["nsec"]
    if not all(isinstance(v, int) and not isinstance(v, bool) and v >= 0 for v in (sec, nsec)):
        raise InputError(f"qos.{field}", node, "non-negative integers sec, nsec")
    return min(sec * 1_000_000_000 + nsec, DURATION_INFINITE_NS)


def parse_offered_qos(text: str) -> list[QosProfile]:
    """Parse an ``offered_qos_profiles`` YAML string (Jazzy, names) into profiles.

    Raises
    ------
    InputError
        If the text is not a YAML sequence of complete profile maps.
    """
    from gerotor_twin.yaml_safe import load_yaml
    node = load_yaml(text, "offered_qos_profiles", max_nodes=10_000) if text.strip() else []
    if not isinstance(node, list):
        raise InputError("offered_qos_profiles", text, "a YAML sequence of QoS maps")
    out = []
    for item in node:
        if not isinstance(item, dict) or set(item) != set(_KEYS):
            keys = sorted(item) if isinstance(item, dict) else item
            raise InputError("offered_qos_profiles", keys, "maps with keys " + ", ".join(_KEYS))
        out.append(QosProfile(
            history=item["history"], depth=item["depth"],
            reliability=item["reliability"], durability=item["durability"],
            deadline_ns=_duration_ns("deadline", item["deadline"]),
            lifespan_ns=_duration_ns("lifespan", item["lifespan"]),
            liveliness=item["liveliness"],
            liveliness_lease_duration_ns=_duration_ns("liveliness_lease_duration",
                                                      item["liveliness_lease_duration"]),
            avoid_ros_namespace_conventions=item["avoid_ros_namespace_conventions"]))
    return out


def resolve_qos(qos: QosSpec) -> str:
    """Turn ``"sensor"`` | ``"reliable"`` | a profile (list) | a YAML string into channel metadata.

    A YAML string is validated with :func:`parse_offered_qos` and stored as given.

    Raises
    ------
    InputError
        For an unknown name or invalid YAML.
    """
    if isinstance(qos, str):
        if qos == "sensor":
            return offered_qos_yaml(SENSOR_DATA)
        if qos == "reliable":
            return offered_qos_yaml(RELIABLE)
        if "\n" not in qos and ":" not in qos:
            raise InputError("qos", qos, "'sensor' | 'reliable' | a QosProfile | offered_qos_profiles YAML")
        parse_offered_qos(qos)
        return qos
    return offered_qos_yaml(qos)
