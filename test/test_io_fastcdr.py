"""The node's fast CDR paths against an independent implementation (mcap_ros2).

Tier: independent tool.  Bytes are produced by ``mcap_ros2``'s dynamic
serializer from the installed ``.msg`` definitions and decoded both by
:func:`gerotor_twin.io.fastcdr.decode_fast` and by ``mcap_ros2``'s dynamic
decoder; every field must be equal.  The fast encoders must give the bytes of
the project codec (itself tested against ``rosbags`` in test_io_roundtrip).
A buffer the fast path cannot read must still give the generic decoder's
:class:`InputError`, never a wrong message.
"""
from __future__ import annotations

import math

import numpy as np
import pytest
from mcap_ros2._dynamic import generate_dynamic, serialize_dynamic

from gerotor_twin.errors import InputError
from gerotor_twin.io import messages as m
from gerotor_twin.io.codec import encode as generic_encode
from gerotor_twin.io.decode import decode
from gerotor_twin.io.fastcdr import FAST_DECODERS, decode_fast, encode
from gerotor_twin.io.schemas import message_definition


def _independent(msgtype: str):
    d = message_definition(msgtype)
    return serialize_dynamic(d.msgtype, d.text)[d.msgtype], generate_dynamic(d.msgtype, d.text)[d.msgtype]


def _same(fast, ref, path="msg"):
    """Field-by-field equality of a fast message object and an mcap_ros2 namespace."""
    if hasattr(fast, "__slots__") and not isinstance(fast, (list, float, int, str)):
        assert not isinstance(fast, tuple), path             # walkers take tuples for arrays
        for f in fast.__slots__:
            _same(getattr(fast, f), getattr(ref, f), f"{path}.{f}")
    elif isinstance(fast, list):
        assert len(fast) == len(ref), path
        for i, (a, b) in enumerate(zip(fast, ref)):
            _same(a, b, f"{path}[{i}]")
    elif isinstance(fast, float) and math.isnan(fast):
        assert math.isnan(ref), path
    else:
        assert fast == ref and type(fast) is type(ref), (path, fast, ref)


def _stamp(sec, nsec, frame):
    return {"stamp": {"sec": sec, "nanosec": nsec}, "frame_id": frame}


RNG = np.random.default_rng(7)
CASES = [
    (m.JOINT_STATE, {"header": _stamp(1_700_000_000, 123_456_789, ""), "name": ["shaft"], "position": [],
                     "velocity": [314.159], "effort": []}),
    (m.JOINT_STATE, {"header": _stamp(-5, 0, "bench_frame"), "name": ["a", "bb", "ccc", ""],
                     "position": list(RNG.normal(size=4)), "velocity": list(RNG.normal(size=3)),
                     "effort": [float("nan"), float("inf")]}),
    (m.JOINT_STATE, {"header": _stamp(0, 0, "xyz"), "name": [], "position": [1.0], "velocity": [],
                     "effort": [2.0, 3.0]}),
    (m.JOINT_STATE, {"header": _stamp(2, 3, "é-unicode"), "name": ["wälle"], "position": [], "velocity": [1e300],
                     "effort": []}),
    (m.FLUID_PRESSURE, {"header": _stamp(1_700_000_000, 999_999_999, ""), "fluid_pressure": 2.851325e6,
                        "variance": 0.0}),
    (m.FLUID_PRESSURE, {"header": _stamp(7, 1, "p1"), "fluid_pressure": -1.5, "variance": 4.0}),
    (m.FLUID_PRESSURE, {"header": _stamp(7, 1, "abcdefg"), "fluid_pressure": float("nan"), "variance": 1.0}),
    (m.TEMPERATURE, {"header": _stamp(9, 8, "oil"), "temperature": 47.25, "variance": 0.01}),
    (m.TEMPERATURE, {"header": _stamp(9, 8, "oil_sump_1"), "temperature": -20.0, "variance": 0.0}),
    (m.FLOAT64, {"data": 1.25e-4}),
    (m.FLOAT64, {"data": float("-inf")}),
    (m.VECTOR3_STAMPED, {"header": _stamp(3, 4, "pump_housing"), "vector": {"x": 1e-6, "y": -2e-6, "z": 0.0}}),
    (m.VECTOR3_STAMPED, {"header": _stamp(3, 4, "ab"), "vector": {"x": 1.0, "y": 2.0, "z": 3.0}}),
]


@pytest.mark.parametrize("msgtype,msg", CASES)
def test_decode_fast_equals_mcap_ros2(msgtype, msg):
    ser, deser = _independent(msgtype)
    data = bytes(ser(msg))
    fast = decode_fast(msgtype, data)
    assert fast is not None
    _same(fast, deser(data))
    _same(decode(msgtype, data), deser(data))


def test_every_fast_decoder_is_covered():
    assert {t for t, _ in CASES} == set(FAST_DECODERS)


@pytest.mark.parametrize("msgtype,msg", [
    (m.FLOAT64, m.float64(3.5e-4)), (m.FLOAT64, m.float64(float("nan"))),
    (m.VECTOR3_STAMPED, m.vector3_stamped(1_700_000_000_123_456_789, 1e-6, -2e-6)),
    (m.VECTOR3_STAMPED, m.vector3_stamped(5, 1.0, 2.0, 3.0, frame_id="abc")),
    (m.VECTOR3_STAMPED, m.vector3_stamped(5, 1.0, 2.0, 3.0, frame_id="")),
    (m.FLUID_PRESSURE, m.fluid_pressure(1_700_000_000_123_456_789, 2.101325e6, frame_id="pump_housing")),
    (m.FLUID_PRESSURE, m.fluid_pressure(5, 101325.0, variance=4.0e6, frame_id="")),
    (m.JOINT_STATE, m.joint_state(5, name=["a", "chamber_01_peak_pressure_pa"], position=[1.5, 2e6],
                                  frame_id="pump_housing")),
    (m.JOINT_STATE, m.joint_state(1_700_000_000_123_456_789, name=["abc"], position=[1.0], velocity=[2.0],
                                  effort=[3.0], frame_id="xy")),
    (m.JOINT_STATE, m.joint_state(7, name=["ab", "cde", "f"], position=np.arange(3.0), frame_id="")),
    (m.JOINT_STATE, m.joint_state(7, frame_id="p")),
    (m.FLOAT64_MULTIARRAY, m.float64_multiarray(np.arange(7.0), ("chamber",))),
    (m.FLOAT64_MULTIARRAY, m.float64_multiarray(np.arange(7.0) + 0.5, ("chamber",))),   # cached layout, new data
    (m.FLOAT64_MULTIARRAY, m.float64_multiarray(np.random.default_rng(1).random((360, 8)), ("sample", "angle_p"))),
    (m.FLOAT64_MULTIARRAY, m.float64_multiarray(np.zeros(0), ("gap",))),
    (m.FLOAT64_MULTIARRAY, {"layout": m.multiarray_layout(("ab",), (3,)), "data": [1.0, 2.0, 3.0]}),  # a list too
])
def test_fast_encode_equals_codec(msgtype, msg):
    """Independent: mcap_ros2's encoder (through the project codec) writes the same bytes."""
    assert encode(msgtype, msg) == generic_encode(msgtype, msg)


@pytest.mark.parametrize("msgtype", sorted(FAST_DECODERS))
def test_truncated_buffer_gives_the_generic_error(msgtype):
    """Every proper prefix of a valid message: never a message from the fast path, an InputError from decode."""
    ser, _ = _independent(msgtype)
    data = bytes(ser(next(msg for t, msg in CASES if t == msgtype)))
    for n in range(len(data)):
        cut = data[:n]
        fast = decode_fast(msgtype, cut)
        if fast is None:
            with pytest.raises(InputError):
                decode(msgtype, cut)
        else:     # only trailing padding may be cut (mcap_ros2 reads such a prefix too)
            _same(fast, _independent(msgtype)[1](cut))


def test_big_endian_and_unknown_types_go_generic():
    data = bytes(_independent(m.FLOAT64)[0]({"data": 2.0}))
    assert decode_fast(m.FLOAT64, b"\x00\x00" + data[2:]) is None
    assert decode_fast(m.DIAGNOSTIC_ARRAY, data) is None
    with pytest.raises(InputError):
        decode(m.JOINT_STATE, b"\x00\x01\x00\x00" + b"\xff" * 40)


def test_the_log_writes_the_outputs_with_the_fast_encoders(tmp_path, monkeypatch):
    """Behaviour: ``McapLog.encode`` (what ``run-bag`` and the offline tools log through) takes the fast encoder
    of each periodic output type for a dict, and its bytes are mcap_ros2's (through the project codec); an
    object (a decoded message) still goes to the generic encoder."""
    import gerotor_twin.io.codec as codec
    from gerotor_twin.io.fastcdr import FAST_ENCODERS
    from gerotor_twin.io.mcap_log import McapLog
    samples = {m.FLOAT64: m.float64(2.5), m.VECTOR3_STAMPED: m.vector3_stamped(5, 1.0, 2.0, 3.0),
               m.FLUID_PRESSURE: m.fluid_pressure(5, 101325.0, frame_id="pump_housing"),
               m.JOINT_STATE: m.joint_state(7, name=["a", "b"], position=[1.0, 2.0], frame_id="p"),
               m.FLOAT64_MULTIARRAY: m.float64_multiarray(np.arange(7.0), ("chamber",))}
    assert set(samples) == set(FAST_ENCODERS)
    generic = {t: generic_encode(t, msg) for t, msg in samples.items()}
    used = []
    real = codec.encoder_for
    monkeypatch.setattr("gerotor_twin.io.mcap_log.encoder_for", lambda t: used.append(t) or real(t))
    with McapLog(tmp_path / "x.mcap", overwrite=True) as log:
        for k, (t, msg) in enumerate(samples.items()):
            log.add_topic(f"/t{k}", t)
            assert log.encode(f"/t{k}", msg) == generic[t]
        assert used == []                                   # every dict by its fast encoder
        obj = decode(m.VECTOR3_STAMPED, generic[m.VECTOR3_STAMPED])
        assert log.encode("/t1", obj) == generic[m.VECTOR3_STAMPED] and used == [m.VECTOR3_STAMPED]


@pytest.mark.parametrize("msg,named", [({"dat": 1.0}, "dat"), ({"data": 1.0, "extra": 2.0}, "extra"),
                                       ({"data": "x"}, "Float64")])
def test_the_log_names_a_bad_output_dict_as_the_generic_encoder_does(tmp_path, msg, named):
    """Behaviour: a dict whose fields differ from the type's (misspelt, unknown) or whose value is not a number
    does not go through the fast encoder silently: the log raises the generic encoder's InputError."""
    from gerotor_twin.io.mcap_log import McapLog
    with McapLog(tmp_path / "x.mcap", overwrite=True) as log:
        log.add_topic("/f", m.FLOAT64)
        with pytest.raises(InputError, match=named):
            log.encode("/f", msg)


def test_the_log_names_a_misspelt_nested_field_as_the_generic_encoder_does(tmp_path):
    """Behaviour: a nested field misspelt (the header's stamp) takes the generic encoder's InputError too."""
    from gerotor_twin.io.mcap_log import McapLog
    msg = m.vector3_stamped(5, 1.0, 2.0, 3.0)
    msg["header"] = {"stmp": msg["header"]["stamp"], "frame_id": ""}
    with McapLog(tmp_path / "x.mcap", overwrite=True) as log:
        log.add_topic("/v", m.VECTOR3_STAMPED)
        with pytest.raises(InputError, match="stmp"):
            log.encode("/v", msg)
