"""Reference tests of schema building and QoS metadata (gerotor_twin.io.schemas, .qos).

The ``ros2msg`` text must be exactly rosbag2's (LocalMessageDefinitionSource:
top-level .msg, then per dependency, depth first in sorted order, each once,
``"\\n" + 80*"=" + "\\nMSG: pkg/Type\\n" + .msg``); the type hash must be the
one in the installed ``.json`` and the one ``rosbags`` recomputes.  The QoS
YAML must be rosbag2 Jazzy's (names, key order, infinite durations) and be
accepted by ``rosbags``' independent parser.  Unknown types and bad QoS give
clear errors.
"""
from __future__ import annotations

import json
import tempfile
from pathlib import Path

import pytest
from rosbags.rosbag2.metadata import parse_qos
from rosbags.typesys import Stores, get_types_from_msg, get_typestore

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.io import schemas
from gerotor_twin.io.qos import (DURATION_INFINITE_NS, RELIABLE, SENSOR_DATA, QosProfile,
                                 offered_qos_yaml, parse_offered_qos, resolve_qos)

SEP = "\n" + "=" * 80 + "\n"
PROJECT_TYPES = [m.JOINT_STATE, m.FLUID_PRESSURE, m.TEMPERATURE, m.FLOAT64, m.FLOAT64_MULTIARRAY,
                 m.VECTOR3_STAMPED, m.DIAGNOSTIC_ARRAY, m.CLOCK]


def msg_file(name: str) -> str:
    pkg, typ = name.split("/")
    return next(d / pkg / "msg" / f"{typ}.msg" for d in schemas.share_dirs()
                if (d / pkg / "msg" / f"{typ}.msg").is_file()).read_text()


def test_joint_state_schema_is_rosbag2s():
    d = schemas.message_definition("sensor_msgs/JointState")
    assert d.msgtype == "sensor_msgs/msg/JointState"
    expected = (msg_file("sensor_msgs/JointState")
                + SEP + "MSG: std_msgs/Header\n" + msg_file("std_msgs/Header")
                + SEP + "MSG: builtin_interfaces/Time\n" + msg_file("builtin_interfaces/Time"))
    assert d.text == expected


def test_dependencies_once_depth_first_sorted():
    text = schemas.message_definition(m.DIAGNOSTIC_ARRAY).text
    heads = [line for line in text.splitlines() if line.startswith("MSG: ")]
    # DiagnosticArray uses DiagnosticStatus (relative KeyValue inside) and std_msgs/Header.
    assert heads == ["MSG: diagnostic_msgs/DiagnosticStatus", "MSG: diagnostic_msgs/KeyValue",
                     "MSG: std_msgs/Header", "MSG: builtin_interfaces/Time"]
    text = schemas.message_definition(m.FLOAT64_MULTIARRAY).text
    assert [ln for ln in text.splitlines() if ln.startswith("MSG: ")] == [
        "MSG: std_msgs/MultiArrayLayout", "MSG: std_msgs/MultiArrayDimension"]


@pytest.mark.parametrize("msgtype", PROJECT_TYPES)
def test_type_hash_matches_json_and_rosbags(msgtype: str):
    d = schemas.message_definition(msgtype)
    hashes = json.loads(d.msg_path.with_suffix(".json").read_text())["type_hashes"]
    assert d.type_hash == next(h["hash_string"] for h in hashes if h["type_name"] == msgtype)
    store = get_typestore(Stores.EMPTY)
    store.register(get_types_from_msg(d.text, msgtype))
    assert store.hash_rihs01(msgtype) == d.type_hash


@pytest.fixture
def short_tmp():
    """A temporary directory with a short path: an error's reason is clipped at 120 characters
    (``errors.clip``), and pytest's ``tmp_path`` (longer still under xdist, ``.../popen-gw1/...``)
    would cut off the directory the message names."""
    with tempfile.TemporaryDirectory(prefix="gt") as d:
        yield Path(d)


def test_search_path_cache_and_unknown_types(short_tmp: Path, monkeypatch: pytest.MonkeyPatch):
    msg_dir = short_tmp / "share" / "bench_msgs" / "msg"
    msg_dir.mkdir(parents=True)
    (msg_dir / "Pair.msg").write_text("float64 a\nInner inner\nbench_msgs/Missing[] m\n")
    (msg_dir / "Inner.msg").write_text("int32 k\n")
    monkeypatch.setenv("AMENT_PREFIX_PATH", str(short_tmp))
    schemas.clear_cache()
    try:
        assert schemas.share_dirs()[0] == short_tmp / "share"
        with pytest.raises(schemas.UnknownMessageType, match=r"bench_msgs/msg/Pair.*uses "
                           r"bench_msgs/Missing.*no bench_msgs/msg/Missing.msg"):
            schemas.message_definition("bench_msgs/msg/Pair")
        with pytest.raises(schemas.UnknownMessageType, match=r"no foo_msgs/msg/Bar.msg under .*share"):
            schemas.message_definition("foo_msgs/msg/Bar")
        with pytest.raises(InputError, match="'pkg/msg/Type' or 'pkg/Type'"):
            schemas.message_definition("Float64")
        # Inner exists but has no .json: a clear error, not a KeyError
        with pytest.raises(schemas.UnknownMessageType, match="Inner"):
            schemas.message_definition("bench_msgs/Inner")
        # interfaces installed in the venv are still found (sys.prefix fallback)
        assert schemas.message_definition(m.FLOAT64).type_hash.startswith("RIHS01_")
    finally:
        schemas.clear_cache()
    assert schemas.message_definition(m.FLOAT64) is schemas.message_definition(m.FLOAT64)  # cached


def test_qos_yaml_is_rosbag2_jazzy_form():
    inf = "    sec: 9223372036\n    nsec: 854775807\n"
    assert offered_qos_yaml(SENSOR_DATA) == (
        "- history: keep_last\n  depth: 5\n  reliability: best_effort\n  durability: volatile\n"
        f"  deadline:\n{inf}  lifespan:\n{inf}  liveliness: automatic\n"
        f"  liveliness_lease_duration:\n{inf}  avoid_ros_namespace_conventions: false")
    assert resolve_qos("reliable") == offered_qos_yaml(RELIABLE)
    assert "reliability: reliable" in resolve_qos("reliable") and "depth: 10" in resolve_qos("reliable")
    both = offered_qos_yaml([SENSOR_DATA, RELIABLE])
    assert parse_offered_qos(both) == [SENSOR_DATA, RELIABLE]
    assert resolve_qos(both) == both  # a valid YAML string is kept as given
    (q,) = parse_qos(offered_qos_yaml(SENSOR_DATA))  # rosbags' own parser
    assert (q.history.name, q.depth, q.reliability.name, q.durability.name, q.liveliness.name) == (
        "KEEP_LAST", 5, "BEST_EFFORT", "VOLATILE", "AUTOMATIC")
    assert (q.deadline.sec, q.deadline.nsec) == divmod(DURATION_INFINITE_NS, 10**9)
    finite = QosProfile(deadline_ns=1_500_000_000)
    assert parse_offered_qos(offered_qos_yaml(finite)) == [finite]
    assert "deadline:\n    sec: 1\n    nsec: 500000000" in offered_qos_yaml(finite)


def test_qos_errors():
    with pytest.raises(InputError, match="'sensor' | 'reliable'"):
        resolve_qos("sensors")
    with pytest.raises(InputError, match="qos.reliability"):
        QosProfile(reliability="sometimes")
    with pytest.raises(InputError, match="qos.depth"):
        QosProfile(depth=-1)
    with pytest.raises(InputError, match="offered_qos_profiles"):
        resolve_qos("- history: keep_last\n  depth: 5\n")  # incomplete profile
    with pytest.raises(InputError, match="offered_qos_profiles"):
        resolve_qos("a: [unclosed\n")
