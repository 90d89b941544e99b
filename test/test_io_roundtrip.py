"""Round-trip and independent-reader tests of the MCAP writer (gerotor_twin.io).

Round trip: every project message type is written with :class:`McapLog` (to an
``io.BytesIO``) and read back with our reader; values, times and counts must be
equal.  Raw CDR bytes logged with ``write_raw`` must come back identical.

Independent readers: the same log written to a file is read by ``rosbags``
(pure-Python, its own CDR decoder and RIHS01 hash computation) and by
``mcap_ros2.reader.read_ros2_messages``; the channel metadata is checked
against rosbag2's conventions (profile, encodings, offered_qos_profiles,
topic_type_hash from the installed ``.json``).
"""
from __future__ import annotations

import io
import json
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
import yaml
from mcap.reader import make_reader
from mcap_ros2._dynamic import serialize_dynamic

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.io.mcap_log import LIBRARY, McapLog
from gerotor_twin.io.qos import RELIABLE, SENSOR_DATA, offered_qos_yaml
from gerotor_twin.io.reader import (multiarray_series, multiarray_values, open_mcap, read_topics,
                                    scalar_series)
from gerotor_twin.io.schemas import message_definition

T0 = 1_700_000_000_123_456_789  # a wall-clock-like epoch [ns]
DT = 10_000_000  # 10 ms


def sample_log() -> dict[str, tuple[str, str, list[tuple[int, dict]]]]:
    """``{topic: (msgtype, qos, [(log_time_ns, message dict), ...])}`` for every project type."""
    n = 5
    t = [T0 + i * DT for i in range(n)]
    wave = np.arange(24, dtype=float).reshape(4, 6) * 1e5
    return {
        "/bench/shaft_speed": (m.JOINT_STATE, "sensor", [
            (ti, m.joint_state(ti - 1000, name=["shaft"], position=[0.1 * i], velocity=[314.159 + i]))
            for i, ti in enumerate(t)]),
        "/bench/delivery_pressure": (m.FLUID_PRESSURE, "sensor", [
            (ti, m.fluid_pressure(ti, 2.0e5 + 1e3 * i, variance=25.0)) for i, ti in enumerate(t)]),
        "/bench/oil_temperature": (m.TEMPERATURE, "sensor", [
            (ti, m.temperature(ti, 40.0 + 0.5 * i)) for i, ti in enumerate(t)]),
        "/bench/delivery_flow": (m.FLOAT64, "sensor", [
            (ti, m.float64(1.5e-4 * (1 + i))) for i, ti in enumerate(t)]),
        "/twin/chamber_pressures": (m.FLOAT64_MULTIARRAY, "reliable", [
            (ti, m.float64_multiarray(np.linspace(1e5, 7e5, 7) + i)) for i, ti in enumerate(t)]),
        "/twin/chamber_waveform": (m.FLOAT64_MULTIARRAY, "reliable", [
            (t[0], m.float64_multiarray(wave, labels=("sample", "angle_p")))]),
        "/twin/eccentricity": (m.VECTOR3_STAMPED, "reliable", [
            (ti, m.vector3_stamped(ti, 1e-5 * i, -2e-5 * i)) for i, ti in enumerate(t)]),
        "/diagnostics": (m.DIAGNOSTIC_ARRAY, "reliable", [
            (t[0], m.diagnostic_array(t[0], [
                m.diagnostic_status(m.DIAG_OK, "twin: real time", "ok",
                                    values={"real_time_factor": 1.75, "lag_ms": 2}),
                m.diagnostic_status(m.DIAG_WARN, "twin: inputs", "suction pressure missing",
                                    hardware_id="bench", values=[{"key": "age_s", "value": "3.5"}]),
            ]))]),
        "/clock": (m.CLOCK, "reliable", [(ti, m.clock(ti)) for ti in t]),
    }


def write_sample(output, compression: str = "zstd") -> dict:
    samples = sample_log()
    with McapLog(output, compression=compression,
                 metadata={"gerotor_twin.pump_config": {"yaml": "z: 7\n"}}) as log:
        for topic, (msgtype, qos, _) in samples.items():
            log.add_topic(topic, msgtype, qos)
        log.add_metadata("gerotor_twin.node_parameters", {"bearing_model": "mobility"})
        for topic, (_, _, rows) in samples.items():
            for k, (t, msg) in enumerate(rows):
                log.write(topic, msg, t, publish_time_ns=t - 7 * k)
    return samples


def assert_same(decoded, expected, where: str = "msg") -> None:
    """``decoded`` (mcap_ros2 or rosbags object) has the values of the dict ``expected``."""
    if isinstance(expected, dict):
        for key, value in expected.items():
            assert hasattr(decoded, key), f"{where}.{key} missing"
            assert_same(getattr(decoded, key), value, f"{where}.{key}")
    elif isinstance(expected, list) and expected and isinstance(expected[0], dict):
        assert len(decoded) == len(expected), where
        for i, (d, e) in enumerate(zip(decoded, expected)):
            assert_same(d, e, f"{where}[{i}]")
    elif isinstance(expected, list) and expected and isinstance(expected[0], str):
        assert list(decoded) == expected, where
    elif isinstance(expected, (list, np.ndarray)):
        np.testing.assert_array_equal(np.asarray(decoded, dtype=float), np.asarray(expected, float),
                                      err_msg=where)
    else:
        assert decoded == expected, f"{where}: {decoded!r} != {expected!r}"


def test_roundtrip_every_type_in_memory():
    buf = io.BytesIO()
    samples = write_sample(buf)
    series = read_topics(buf)
    assert set(series) == set(samples)
    for topic, (msgtype, _, rows) in samples.items():
        s = series[topic]
        assert s.msgtype == msgtype
        assert len(s) == len(rows)
        assert s.log_time_ns.dtype == np.int64
        np.testing.assert_array_equal(s.log_time_ns, [t for t, _ in rows])
        np.testing.assert_array_equal(s.publish_time_ns, [t - 7 * k for k, (t, _) in enumerate(rows)])
        for k, (_, msg) in enumerate(rows):
            assert_same(s.messages[k], msg, f"{topic}[{k}]")
    f = open_mcap(buf)
    assert f.complete and f.profile == "ros2" and f.library == LIBRARY
    assert set(f.metadata) == {"gerotor_twin.pump_config", "gerotor_twin.node_parameters", "rosbag2"}
    assert f.metadata["gerotor_twin.pump_config"] == {"yaml": "z: 7\n"}
    assert f.metadata["gerotor_twin.node_parameters"] == {"bearing_model": "mobility"}
    assert f.message_count == sum(len(r) for _, _, r in samples.values())


def test_numeric_helpers():
    buf = io.BytesIO()
    samples = write_sample(buf)
    series = read_topics(buf, ["/bench/shaft_speed", "/bench/delivery_pressure", "/twin/eccentricity",
                               "/bench/delivery_flow", "/twin/chamber_pressures",
                               "/twin/chamber_waveform"])
    t, w = scalar_series(series["/bench/shaft_speed"], "velocity[0]", t0_ns=T0)
    np.testing.assert_allclose(t, np.arange(5) * 0.01, atol=1e-12)
    np.testing.assert_array_equal(w, 314.159 + np.arange(5))
    th, _ = scalar_series(series["/bench/shaft_speed"], "velocity[0]", stamp="header", t0_ns=T0)
    np.testing.assert_allclose(th, np.arange(5) * 0.01 - 1e-6, atol=1e-12)  # stamped 1 µs earlier
    _, p = scalar_series(series["/bench/delivery_pressure"], "fluid_pressure")
    np.testing.assert_array_equal(p, 2.0e5 + 1e3 * np.arange(5))
    _, x = scalar_series(series["/twin/eccentricity"], "vector.x")
    np.testing.assert_array_equal(x, 1e-5 * np.arange(5))
    _, q = scalar_series(series["/bench/delivery_flow"], "data")
    np.testing.assert_array_equal(q, 1.5e-4 * (1 + np.arange(5)))
    _, e = scalar_series(series["/bench/shaft_speed"], "effort[0]", missing="nan")
    assert np.isnan(e).all()
    with pytest.raises(InputError, match="effort"):
        scalar_series(series["/bench/shaft_speed"], "effort[0]")
    with pytest.raises(InputError, match="field_path"):
        scalar_series(series["/bench/shaft_speed"], "velocity[")
    t, pc, labels = multiarray_series(series["/twin/chamber_pressures"])
    assert pc.shape == (5, 7) and labels == ("chamber",)
    np.testing.assert_array_equal(pc[2], np.linspace(1e5, 7e5, 7) + 2)
    _, wave, labels = multiarray_series(series["/twin/chamber_waveform"])
    assert wave.shape == (1, 4, 6) and labels == ("sample", "angle_p")
    np.testing.assert_array_equal(wave[0], np.arange(24).reshape(4, 6) * 1e5)
    msg = series["/twin/chamber_waveform"].messages[0]
    assert [(d.size, d.stride) for d in msg.layout.dim] == [(4, 24), (6, 6)]
    np.testing.assert_array_equal(multiarray_values(msg), wave[0])
    with pytest.raises(InputError, match="Float64MultiArray"):
        multiarray_series(series["/twin/eccentricity"])
    assert samples  # keep the sample used


def test_raw_bytes_logged_untouched():
    definition = message_definition(m.JOINT_STATE)
    encoder = serialize_dynamic(definition.msgtype, definition.text)[definition.msgtype]
    blobs = [encoder(m.joint_state(i, name=["shaft", "aux"], velocity=[1.0 * i, 2.0])) for i in range(4)]
    blobs.append(bytes.fromhex("000100000000000000000000"))  # any bytes: not re-encoded
    buf = io.BytesIO()
    with McapLog(buf, compression="lz4") as log:
        log.add_topic("/bench/shaft_speed", m.JOINT_STATE, "sensor")
        for i, b in enumerate(blobs):
            log.write_raw("/bench/shaft_speed", bytearray(b), 100 + i, 50 + i, sequence=1000 + i)
    got = list(open_mcap(buf).iter_raw())
    assert [msg.data for _, msg in got] == blobs
    assert [msg.sequence for _, msg in got] == [1000 + i for i in range(5)]
    assert [msg.publish_time for _, msg in got] == [50 + i for i in range(5)]


@pytest.mark.parametrize("compression", ["zstd", "lz4", "none"])
def test_rosbags_reads_log(tmp_path: Path, compression: str):
    from rosbags.highlevel import AnyReader
    from rosbags.typesys import Stores, get_types_from_msg, get_typestore

    path = tmp_path / "twin.mcap"
    samples = write_sample(path, compression)
    with AnyReader([path]) as reader:
        by_topic = {c.topic: c for c in reader.connections}
        assert set(by_topic) == set(samples)
        got: dict[str, list] = {t: [] for t in samples}
        for conn, t, raw in reader.messages():
            got[conn.topic].append((t, reader.deserialize(raw, conn.msgtype)))
        for topic, (msgtype, qos, rows) in samples.items():
            conn = by_topic[topic]
            assert conn.msgtype == msgtype and conn.msgcount == len(rows)
            assert conn.ext.serialization_format == "cdr"
            (offered,) = conn.ext.offered_qos_profiles
            want = SENSOR_DATA if qos == "sensor" else RELIABLE
            assert (offered.history.name, offered.depth, offered.reliability.name,
                    offered.durability.name, offered.liveliness.name) == (
                    want.history.upper(), want.depth, want.reliability.upper(),
                    want.durability.upper(), "AUTOMATIC")
            assert [t for t, _ in got[topic]] == [t for t, _ in rows]
            for (_, dec), (_, msg) in zip(got[topic], rows):
                assert_same(dec, msg, topic)
    # rosbags recomputes the REP-2011 hash from the embedded schema: it must match ours
    with open(path, "rb") as f:
        summary = make_reader(f).get_summary()
    for ch in summary.channels.values():
        schema = summary.schemas[ch.schema_id]
        store = get_typestore(Stores.EMPTY)
        store.register(get_types_from_msg(schema.data.decode(), schema.name))
        assert store.hash_rihs01(schema.name) == ch.metadata["topic_type_hash"]


def test_mcap_ros2_reads_log(tmp_path: Path):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", DeprecationWarning)  # module docstring warning of mcap_ros2
        from mcap_ros2.reader import read_ros2_messages
    path = tmp_path / "twin.mcap"
    samples = write_sample(path)
    got: dict[str, list] = {t: [] for t in samples}
    for rm in read_ros2_messages(str(path)):
        got[rm.channel.topic].append((rm.log_time_ns, rm.ros_msg))
    for topic, (_, _, rows) in samples.items():
        assert [t for t, _ in got[topic]] == [t for t, _ in rows]
        for (_, dec), (_, msg) in zip(got[topic], rows):
            assert_same(dec, msg, topic)


def test_rosbag2_conventions_in_file(tmp_path: Path):
    path = tmp_path / "twin.mcap"
    samples = write_sample(path)
    with open(path, "rb") as f:
        reader = make_reader(f)
        header = reader.get_header()
        summary = reader.get_summary()
    assert header.profile == "ros2" and header.library.startswith("gerotor_twin/")
    assert summary.statistics.message_count == sum(len(r) for _, _, r in samples.values())
    assert summary.statistics.channel_count == len(samples)
    assert summary.statistics.schema_count == len({t for t, _, _ in samples.values()})
    assert summary.chunk_indexes and all(ci.message_index_offsets for ci in summary.chunk_indexes)
    assert {ci.compression for ci in summary.chunk_indexes} == {"zstd"}
    assert [mi.name for mi in summary.metadata_indexes] == [
        "gerotor_twin.pump_config", "gerotor_twin.node_parameters", "rosbag2"]
    # the rosbag2 record, as rosbag2_storage_mcap writes it (BagMetadata v9, ros2/rosbag2 jazzy)
    with open(path, "rb") as f:
        (meta,) = [r.metadata for r in make_reader(f).iter_metadata() if r.name == "rosbag2"]
    assert set(meta) == {"serialized_metadata"}
    bag = yaml.safe_load(meta["serialized_metadata"])
    assert list(bag) == ["version", "storage_identifier", "duration", "starting_time", "message_count",
                         "topics_with_message_count", "compression_format", "compression_mode",
                         "relative_file_paths", "files", "custom_data", "ros_distro"]
    assert bag["version"] == 9 and bag["ros_distro"] == "jazzy" and bag["storage_identifier"] == "mcap"
    times = [t for _, _, rows in samples.values() for t, _ in rows]
    assert bag["starting_time"] == {"nanoseconds_since_epoch": min(times)}
    assert bag["duration"] == {"nanoseconds": max(times) - min(times)}
    assert bag["message_count"] == len(times) and bag["relative_file_paths"] == ["twin.mcap"]
    by_topic = {t["topic_metadata"]["name"]: t for t in bag["topics_with_message_count"]}
    assert {k: v["message_count"] for k, v in by_topic.items()} == {
        k: len(rows) for k, (_, _, rows) in samples.items()}
    share = Path(message_definition(m.JOINT_STATE).msg_path).parents[2]
    for ch in summary.channels.values():
        msgtype, qos, _ = samples[ch.topic]
        schema = summary.schemas[ch.schema_id]
        assert schema.name == msgtype and schema.encoding == "ros2msg"
        assert ch.message_encoding == "cdr"
        assert set(ch.metadata) == {"offered_qos_profiles", "topic_type_hash"}
        assert ch.metadata["offered_qos_profiles"] == offered_qos_yaml(
            SENSOR_DATA if qos == "sensor" else RELIABLE)
        (profile,) = yaml.safe_load(ch.metadata["offered_qos_profiles"])
        assert profile["reliability"] == ("best_effort" if qos == "sensor" else "reliable")
        pkg, _, typ = msgtype.split("/")
        hashes = json.loads((share / pkg / "msg" / f"{typ}.json").read_text())["type_hashes"]
        assert ch.metadata["topic_type_hash"] == next(
            h["hash_string"] for h in hashes if h["type_name"] == msgtype)
        tm = by_topic[ch.topic]["topic_metadata"]
        assert tm == {"name": ch.topic, "type": msgtype, "serialization_format": "cdr",
                      "offered_qos_profiles": yaml.safe_load(ch.metadata["offered_qos_profiles"]),
                      "type_description_hash": ch.metadata["topic_type_hash"]}


def test_writer_rejects_bad_input(tmp_path: Path):
    buf = io.BytesIO()
    with McapLog(buf) as log:
        with pytest.raises(InputError, match="compression"):
            McapLog(io.BytesIO(), compression="gzip")
        log.add_topic("/twin/delivery_flow", m.FLOAT64)
        assert log.add_topic("/twin/delivery_flow", "std_msgs/Float64") == 1  # same again: same id
        with pytest.raises(InputError, match="one type and QoS per topic"):
            log.add_topic("/twin/delivery_flow", m.TEMPERATURE)
        with pytest.raises(InputError, match="topic"):
            log.add_topic("twin flow", m.FLOAT64)
        with pytest.raises(InputError, match="registered with add_topic"):
            log.write("/twin/nope", m.float64(1.0), 1)
        with pytest.raises(InputError, match="dat"):
            log.write("/twin/delivery_flow", {"dat": 1.0}, 1)
        with pytest.raises(InputError, match="log_time_ns"):
            log.write("/twin/delivery_flow", m.float64(1.0), -1)
        with pytest.raises(InputError, match="log_time_ns"):
            log.write("/twin/delivery_flow", m.float64(1.0), 1.5)
        with pytest.raises(InputError, match="metadata"):
            log.add_metadata("x", {"a": 1})
        with pytest.raises(InputError, match="data"):
            log.write_raw("/twin/delivery_flow", b"\x00", 1)
    (tmp_path / "exists.mcap").write_bytes(b"keep me")
    with pytest.raises(InputError, match="does not exist yet"):
        McapLog(tmp_path / "exists.mcap")
    assert (tmp_path / "exists.mcap").read_bytes() == b"keep me"


def test_message_builders_validate():
    assert m.stamp_from_ns(-1_700_000_000) == {"sec": -2, "nanosec": 300_000_000}
    assert m.ns_from_stamp(m.stamp_from_ns(T0)) == T0
    with pytest.raises(InputError, match="stamp_ns"):
        m.stamp_from_ns(2**31 * 10**9)
    with pytest.raises(InputError, match="velocity"):
        m.joint_state(0, name=["shaft"], velocity=[1.0, 2.0])
    with pytest.raises(InputError, match="labels"):
        m.float64_multiarray(np.zeros((2, 3)))
    with pytest.raises(InputError, match="level"):
        m.diagnostic_status(7, "x")
    assert m.key_value("rtf", np.float64(0.1))["value"] == "0.1"
    assert m.vector3_stamped(0, 1, 2)["header"]["frame_id"] == "pump_housing"


def test_io_never_imports_rclpy():
    code = ("import sys, gerotor_twin.io, gerotor_twin.io.background, gerotor_twin.io.reader; "
            "sys.exit('rclpy' in sys.modules)")
    assert subprocess.run([sys.executable, "-c", code], timeout=60).returncode == 0
