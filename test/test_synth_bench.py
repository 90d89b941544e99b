"""Bench emulator (``gerotor-twin synth-bench``): regenerable bit for bit, rosbag2 MCAP, sane content."""
import io
import math

import numpy as np
import pytest

from gerotor_twin.bench_emulator import BENCH_TOPICS, EMULATOR_METADATA, BenchSpec, get_profile, synthesize
from gerotor_twin.bench_emulator.emulator import emulated_config
from gerotor_twin.bench_emulator.profiles import Profile, Segment
from gerotor_twin.bench_emulator.sensors import Encoder, FirstOrderLag
from gerotor_twin.cli import main
from gerotor_twin.config import parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.io import metadata, read_topics, scalar_series


@pytest.fixture(scope="module")
def test_bag():
    buf = io.BytesIO()
    res = synthesize(get_profile("test"), buf, progress=None)
    return buf.getvalue(), res


def test_same_seed_same_bytes(test_bag):
    data, _ = test_bag
    again = io.BytesIO()
    synthesize(get_profile("test"), again, progress=None)
    assert again.getvalue() == data
    other = io.BytesIO()
    synthesize(get_profile("test"), other, BenchSpec(seed=7), progress=None)
    assert other.getvalue() != data


def test_topics_types_and_rates(test_bag):
    data, res = test_bag
    series = read_topics(data)
    assert {k: v.msgtype for k, v in series.items()} == BENCH_TOPICS
    counts = {k: len(v) for k, v in series.items()}
    assert counts == res["message_counts"]
    assert counts["/bench/shaft_speed"] == 40 and counts["/bench/delivery_flow"] == 8
    meta = metadata(data)[EMULATOR_METADATA]
    assert meta["synthetic"] == "true" and meta["seed"] == str(BenchSpec().seed)
    # receive (log) time is after the sample stamp by the recorder latency
    s = series["/bench/delivery_pressure"]
    lat = (s.log_time_ns - s.publish_time_ns) * 1e-9
    assert np.all(lat >= 0.3e-3) and np.all(lat < 0.05)


def test_rosbags_reads_bench_bag(tmp_path, test_bag):
    from rosbags.highlevel import AnyReader
    path = tmp_path / "bench.mcap"
    path.write_bytes(test_bag[0])
    with AnyReader([path]) as reader:
        conns = {c.topic: c for c in reader.connections}
        assert {t: c.msgtype for t, c in conns.items()} == BENCH_TOPICS
        for conn, _, raw in reader.messages(connections=[conns["/bench/shaft_speed"]]):
            msg = reader.deserialize(raw, conn.msgtype)
            assert msg.name == ["pump_shaft"] and len(msg.velocity) == 1
        assert conns["/bench/shaft_speed"].ext.offered_qos_profiles[0].reliability.name == "BEST_EFFORT"


def test_content_follows_profile(test_bag):
    series = read_topics(test_bag[0])
    _, w = scalar_series(series["/bench/shaft_speed"], "velocity[0]")
    assert np.all(np.abs(w * 30 / math.pi - 1000) < 1.0)          # encoder quantization ~0.4 rpm
    t, p = scalar_series(series["/bench/delivery_pressure"], "fluid_pressure",
                         t0_ns=int(series["/bench/delivery_pressure"].publish_time_ns[0]))
    gauge = (p - 101325) / 1e5
    assert abs(np.mean(gauge[t < 0.19]) - 10) < 0.1
    assert abs(gauge[-1] - 15) < 0.5                                 # valve tau 80 ms after the step
    _, q = scalar_series(series["/bench/delivery_flow"], "data")
    qth = 22.78e-6 * 1000 / 60
    assert np.all((q > 0.6 * qth) & (q < qth))                       # leaky pump: below theoretical


def test_emulated_pump_is_leakier(cfg):
    c2 = emulated_config(cfg, 1.1)
    assert c2.clearances.tooth_tip_m == pytest.approx(1.1 * cfg.clearances.tooth_tip_m)
    assert c2.clearances.lateral_m == pytest.approx(1.1 * cfg.clearances.lateral_m)
    assert c2.gears.tip_clearance == pytest.approx(c2.clearances.tooth_tip_m)
    with pytest.raises(InputError, match="clearance_factor"):
        emulated_config(cfg, float("nan"))


def test_profiles():
    p = get_profile("map")
    plateaus = p.plateaus()
    assert len(plateaus) == 12
    assert {r for _, _, r, _ in plateaus} == {1000, 2000, 2950}
    assert {b for _, _, _, b in plateaus} == {5, 12.5, 20, 27}
    w, g = p.setpoints([0.0, 11.0, p.duration_s])
    assert w[0] == pytest.approx(1000 * math.pi / 30) and g[0] == pytest.approx(5e5)
    assert 5e5 < g[1] < 12.5e5                                       # half way up the first ramp
    t = get_profile("transient")
    assert 20 < t.duration_s < 40
    with pytest.raises(InputError, match="--profile"):
        get_profile("nope")
    with pytest.raises(InputError, match="rpm"):
        Profile("bad", (Segment(1.0, 4000, 5),))


def test_sensor_elements():
    lag = FirstOrderLag(0.1, 0.001, 0.0)
    for _ in range(100):
        y = lag(1.0)
    assert y == pytest.approx(1 - math.exp(-1.0), rel=1e-9)
    w = 2 * math.pi * 1000 / 60
    enc = Encoder(16384, 10, 1e-3, 0.0, w)
    speeds = [enc(w * 1e-3 * (k + 1))[0] for k in range(50)]
    assert max(abs(s - w) for s in speeds) <= 2 * math.pi / 16384 / 0.01 + 1e-9


def test_bad_rate_and_cli_errors(tmp_path, capsys):
    with pytest.raises(InputError, match="pressure_rate_hz"):
        synthesize(get_profile("test"), io.BytesIO(), BenchSpec(pressure_rate_hz=300), progress=None)
    assert main(["synth-bench", "--profile", "nope", "-o", str(tmp_path / "x.mcap")]) == 2
    assert "--profile" in capsys.readouterr().err
    existing = tmp_path / "e.mcap"
    existing.write_bytes(b"x")
    assert main(["synth-bench", "--profile", "test", "-o", str(existing)]) == 2
    assert "--overwrite" in capsys.readouterr().err


@pytest.mark.parametrize("name", ["bench_map.mcap", "bench_transient.mcap"])
def test_bundled_bags_match_the_current_pump_config(cfg, name):
    """The shipped recordings were made from today's config/pump.yaml (clearances × the
    recorded factor), their recorded config read as today's parser reads it (a key added since takes its
    default): a recalibration or geometry change makes them stale — regenerate
    them with the command stored in their metadata (bags/README.md)."""
    import json
    from pathlib import Path

    import yaml

    meta = metadata(Path(__file__).resolve().parent.parent / "bags" / name)[EMULATOR_METADATA]
    factor = json.loads(meta["spec"])["clearance_factor"]
    recorded = parse_config(yaml.safe_load(meta["emulated_pump_config"])).to_dict()   # a key added since: its default
    expected = emulated_config(cfg, factor).to_dict()
    def flat(d, prefix=""):
        out = {}
        for k, v in d.items():
            out.update(flat(v, f"{prefix}{k}.") if isinstance(v, dict) else {prefix + k: v})
        return out

    got, want = flat(recorded), flat(expected)
    physics = ("gears", "clearances", "ports", "fluid", "leakage", "orifice", "oil", "mixture", "fluid_model",
               "micro_motion")
    for key in [k for k in want if k.split(".")[0] in physics]:
        if isinstance(want[key], (str, bool)) or want[key] is None:
            assert got.get(key) == want[key], (name, key, meta["command"])
        else:
            assert key in got, (name, key, meta["command"])
            np.testing.assert_allclose(np.asarray(got[key], float), np.asarray(want[key], float), rtol=1e-9,
                                       err_msg=f"{name} {key}: {meta['command']}")


@pytest.mark.parametrize("args,needle", [(("--speed-rate", "0"), "speed_rate_hz = 0.0"),
                                         (("--seed", "-5"), "seed = -5"),
                                         (("--flow-rate", "nan"), "flow_rate_hz = nan")])
def test_unusable_settings_one_line(tmp_path, capsys, args, needle):
    """Behaviour: settings synth-bench cannot use give one line and exit 2 (0 Hz was a ZeroDivisionError)."""
    from gerotor_twin.cli import main
    assert main(["synth-bench", "--profile", "test", "-o", str(tmp_path / "x.mcap"), "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0]


def test_bundled_transient_bag_is_what_todays_code_writes():
    """Golden: the first second of ``bags/bench_transient.mcap`` (1000 rpm / 10 bar) is written again with
    the settings and seed stored in it; every sample of every topic agrees to 1e-9 relative.  The config
    check above cannot see a file written by other code: the bags of 43b803e had been (their own commit
    gave η 96.35 % where the file said 95.63 %, bags/README.md).  Values, not bytes, so that a machine whose
    floating point differs in the last bits still passes; a model change fails here — regenerate the bags."""
    import json
    from pathlib import Path

    from gerotor_twin.io import read_topics

    bag = Path(__file__).resolve().parent.parent / "bags" / "bench_transient.mcap"
    meta = metadata(bag)[EMULATOR_METADATA]
    spec = BenchSpec(**json.loads(meta["spec"]))
    first = json.loads(meta["segments"])[0]
    assert (first["rpm"], first["bar"]) == (1000, 10) and first["duration_s"] >= 1.0
    buf = io.BytesIO()
    synthesize(Profile("transient", (Segment(1.0, first["rpm"], first["bar"]),)), buf, spec, progress=None)
    fields = {"/bench/shaft_speed": "velocity[0]", "/bench/delivery_pressure": "fluid_pressure",
              "/bench/suction_pressure": "fluid_pressure", "/bench/delivery_flow": "data",
              "/bench/oil_temperature": "temperature"}
    t_end = spec.start_time_ns + int(0.95e9)
    new, old = read_topics(buf.getvalue(), fields), read_topics(bag, fields)
    for topic, field in fields.items():
        t_new, v_new = scalar_series(new[topic], field, stamp="publish")
        t_old, v_old = scalar_series(old[topic], field, stamp="publish")
        keep = t_new < t_end
        n = int(keep.sum())
        assert n > 0 and np.array_equal(t_old[:n], t_new[keep]), topic
        np.testing.assert_allclose(v_new[keep], v_old[:n], rtol=1e-9, err_msg=topic)
