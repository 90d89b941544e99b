"""Bench profiles follow the pump: built-in profiles scaled to the config's range, user profile files.

Tiers: behaviour (scaling, profile files into the bag, bad files), golden (the default range gives
the set-points recorded in the bundled bags by the code that wrote them), closed form (the oil
temperature following its set-point, against the analytic step response and a numerical
integration).  Short profiles only (≤ 0.8 s simulated).
"""
import io
import json
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from gerotor_twin.bench_emulator import EMULATOR_METADATA, BenchSpec, get_profile, synthesize
from gerotor_twin.bench_emulator.emulator import oil_bath
from gerotor_twin.bench_emulator.profile_file import load_profile_file
from gerotor_twin.bench_emulator.profiles import PROFILES, REFERENCE_RANGE, Profile, Segment, scale_to_range
from gerotor_twin.bench_emulator.sensors import OilBath, oil_warmup
from gerotor_twin.cli import main
from gerotor_twin.config import OperatingRange, default_config_path, load_config, parse_config
from gerotor_twin.errors import InputError
from gerotor_twin.io import metadata, read_topics, scalar_series

ROOT = Path(__file__).resolve().parent.parent
BAGS = {"map": "bench_map.mcap", "transient": "bench_transient.mcap", "wear": "bench_wear.mcap"}


def _config_with_range(tmp_path, **rng) -> Path:
    raw = yaml.safe_load(default_config_path().read_text())
    raw["range"] = rng
    path = tmp_path / "pump_range.yaml"
    path.write_text(yaml.safe_dump(raw, sort_keys=False))
    return path


@pytest.fixture
def pump_7000(tmp_path):
    """A copy of config/pump.yaml with the range 0-7000 rpm, 0-5 bar."""
    return _config_with_range(tmp_path, max_speed_rpm=7000.0, max_delivery_bar=5.0)


# ---------------------------------------------------------------- built-in profiles and the range

@pytest.mark.parametrize("name", sorted(BAGS))
def test_default_range_gives_the_recorded_setpoints(name):
    """Golden: on config/pump.yaml every built-in profile has exactly the segments recorded in the bundled
    bag (written by the emulator before profiles followed the range), and scaling them to the reference
    range is the identity."""
    meta = metadata(ROOT / "bags" / BAGS[name])[EMULATOR_METADATA]
    prof = get_profile(name, load_config().range)
    assert meta["profile"] == name
    assert json.dumps([s.as_dict() for s in prof.segments]) == meta["segments"]
    for s in prof.segments:
        assert scale_to_range(s.rpm, s.bar, REFERENCE_RANGE) == (s.rpm, s.bar)


def test_default_test_profile_is_todays():
    """Behaviour: the 0.4 s unit-test profile is 1000 rpm, 10 then 15 bar on the default pump."""
    segs = get_profile("test", load_config().range).segments
    assert [(s.duration_s, s.rpm, s.bar, s.ramp) for s in segs] == [(0.2, 1000, 10, False), (0.2, 1000, 15, False)]


def test_map_follows_a_7000_rpm_5_bar_pump(pump_7000):
    """Behaviour: on a 7000 rpm / 5 bar pump the map's 12 plateaus lie inside the range, below its top,
    at the same fractions of it as on the default pump (within the rounding: 10 rpm, 0.01 bar), on
    round numbers."""
    rng = load_config(pump_7000).range
    ref = get_profile("map").plateaus()
    new = get_profile("map", rng).plateaus()
    assert len(new) == len(ref) == 12
    for (t0, t1, w0, p0), (u0, u1, w, p) in zip(ref, new):
        assert (u0, u1) == (t0, t1)
        assert 0 < w < 7000 and 0 < p < 5
        assert abs(w / 7000 - w0 / 3000) <= 5 / 7000 + 1e-12
        assert abs(p / 5 - p0 / 27.5) <= 0.005 / 5 + 1e-12
        assert w == round(w, -1) and p == round(p, 2)
    assert sorted({w for *_, w, _ in new}) == [2330, 4670, 6880]
    assert sorted({p for *_, p in new}) == [0.91, 2.27, 3.64, 4.91]


def test_diagnosis_profile_is_the_file_scaled(pump_7000):
    """Closed form: the built-in ``diagnosis`` profile is config/profiles/diagnosis.yaml on the default range (its
    oil temperature kept; four operating points, each visited twice) and on a 7000 rpm / 5 bar pump the same
    plateaus at the scaled set-points: 1000 → 7000/3 and 2500 → 7000/3 + 1500·(7000 − 7000/3)/2000 rpm, 5 and
    25 bar × 5/27.5, rounded to 10 rpm and 0.01 bar."""
    written = load_profile_file(ROOT / "config" / "profiles" / "diagnosis.yaml").segments
    assert get_profile("diagnosis", load_config().range).segments == written
    plateaus = [(rpm, bar) for *_, rpm, bar in get_profile("diagnosis").plateaus()]
    assert len(plateaus) == 8 and all(plateaus.count(p) == 2 for p in plateaus)     # four points, each seen twice
    scaled = get_profile("diagnosis", load_config(pump_7000).range).segments
    low, high = 7000 / 3, 7000 / 3 + 1500 * (7000 - 7000 / 3) / 2000
    assert [(s.rpm, s.bar) for s in scaled] == 2 * [(round(low, -1), round(5 * 5 / 27.5, 2)),
                                                    (round(low, -1), round(25 * 5 / 27.5, 2)),
                                                    (round(high, -1), round(25 * 5 / 27.5, 2)),
                                                    (round(high, -1), round(5 * 5 / 27.5, 2))]
    assert [(s.duration_s, s.ramp, s.oil_temperature_c) for s in scaled] == \
        [(s.duration_s, s.ramp, s.oil_temperature_c) for s in written]


@pytest.mark.parametrize("name", sorted(PROFILES))
def test_every_profile_inside_another_range(pump_7000, name):
    """Behaviour: every set-point of every built-in profile lies in the 7000 rpm / 5 bar range, and the
    default-range profile is refused there, naming the field, value and the pump's range."""
    cfg = load_config(pump_7000)
    prof = get_profile(name, cfg.range)
    assert all(0 <= s.rpm <= 7000 and 0 <= s.bar <= 5 for s in prof.segments)
    prof.check_within(cfg.range)
    with pytest.raises(InputError, match=r"profile\.segments\[\d+\]\.bar = [\d.]+ is invalid; allowed: \[0, 5\] bar"):
        synthesize(get_profile(name), io.BytesIO(), config=cfg, progress=None)


def test_minimum_speed_sets_the_low_end(tmp_path):
    """Behaviour: with ``range.min_speed_rpm: 300`` the map starts at 300 rpm (not at a third of the
    maximum), keeps three speeds below 3000 rpm, and the config round-trips the key; without it the
    config's dict has none."""
    cfg = load_config(_config_with_range(tmp_path, max_speed_rpm=3000.0, max_delivery_bar=27.5, min_speed_rpm=300.0))
    speeds = sorted({w for *_, w, _ in get_profile("map", cfg.range).plateaus()})
    assert speeds[0] == 300 and len(speeds) == 3 and speeds[-1] < 3000
    assert min(s.rpm for p in PROFILES for s in get_profile(p, cfg.range).segments) == 300
    assert parse_config(cfg.to_dict()).range.min_speed_rpm == 300
    assert "min_speed_rpm" not in load_config().to_dict()["range"]
    with pytest.raises(InputError, match="range.min_speed_rpm"):
        OperatingRange(max_speed_rpm=3000.0, min_speed_rpm=3000.0)


def test_synth_bench_on_a_7000_rpm_pump(tmp_path, pump_7000):
    """Behaviour: ``synth-bench --config`` (7000 rpm / 5 bar) ``--profile test`` records the scaled
    plateau: 2330 rpm, 1.82 bar gauge (the default pump's 1000 rpm / 10 bar)."""
    out = tmp_path / "b.mcap"
    assert main(["synth-bench", "--profile", "test", "--config", str(pump_7000), "-o", str(out), "--quiet"]) == 0
    series = read_topics(out)
    _, w = scalar_series(series["/bench/shaft_speed"], "velocity[0]")
    t, p = scalar_series(series["/bench/delivery_pressure"], "fluid_pressure",
                         t0_ns=int(series["/bench/delivery_pressure"].publish_time_ns[0]))
    assert np.all(np.abs(w * 30 / math.pi - 2330) < 1.0)
    assert abs(np.mean((p[t < 0.19] - 101325) / 1e5) - 1.82) < 0.05
    meta = metadata(out)[EMULATOR_METADATA]
    assert json.loads(meta["segments"])[0]["rpm"] == 2330 and "--config" in meta["command"]


# ---------------------------------------------------------------- profile files

PROFILE_TEXT = """\
name: roundtrip
description: two pressures at 1200 rpm, oil held at 50 °C
segments:
  - {duration_s: 0.3, rpm: 1200, bar: 8, oil_temperature_c: 50}
  - {duration_s: 0.5, rpm: 1200, bar: 14}
"""


def test_profile_file_round_trips_into_the_bag(tmp_path, capsys):
    """Behaviour: a profile file's name, text and segments are in the bag's metadata, the command line
    names the file, and the recorded speed, pressure plateaus and oil temperature follow its set-points
    (oil set on the first segment only: the run starts and stays at 50 °C, not the 30 → 70 °C warm-up)."""
    f = tmp_path / "p.yaml"
    f.write_text(PROFILE_TEXT)
    out = tmp_path / "p.mcap"
    assert main(["synth-bench", "--profile-file", str(f), "-o", str(out), "--quiet"]) == 0
    meta = metadata(out)[EMULATOR_METADATA]
    assert meta["profile"] == "roundtrip" and meta["profile_description"].startswith("two pressures")
    assert meta["profile_file_text"] == PROFILE_TEXT
    assert json.loads(meta["segments"]) == [
        {"duration_s": 0.3, "rpm": 1200, "bar": 8, "ramp": False, "oil_temperature_c": 50},
        {"duration_s": 0.5, "rpm": 1200, "bar": 14, "ramp": False}]
    assert "--profile-file " + str(f) in meta["command"] and "--profile " not in meta["command"]
    series = read_topics(out)
    t0 = int(series["/bench/delivery_pressure"].publish_time_ns[0])
    _, w = scalar_series(series["/bench/shaft_speed"], "velocity[0]")
    t, p = scalar_series(series["/bench/delivery_pressure"], "fluid_pressure", t0_ns=t0)
    gauge = (p - 101325) / 1e5
    assert np.all(np.abs(w * 30 / math.pi - 1200) < 1.0)
    assert abs(np.mean(gauge[t < 0.29]) - 8) < 0.1
    assert abs(np.mean(gauge[t > 0.65]) - 14) < 0.1              # valve τ 80 ms: 0.35 s after the step
    _, temp = scalar_series(series["/bench/oil_temperature"], "temperature")
    assert np.all(np.abs(temp - 50) < 0.3)                        # σ 0.05 K
    assert "wrote" in capsys.readouterr().out


def test_example_profile_file_loads():
    """Behaviour: config/profiles/example.yaml loads against the default pump, and every set-point lies in
    its range and in a 7000 rpm / 27.5 bar one (refused on a 2000 rpm pump: 2500 rpm)."""
    path = ROOT / "config" / "profiles" / "example.yaml"
    prof = load_profile_file(path, load_config().range)
    assert prof.name == "example" and prof.source == path.read_text() and len(prof.plateaus()) >= 4
    assert prof.segments[0].oil_temperature_c is not None
    load_profile_file(path, OperatingRange(7000.0, 27.5))
    with pytest.raises(InputError, match=r"example\.yaml: segments\[2\]\.rpm = 2500"):
        load_profile_file(path, OperatingRange(2000.0, 27.5))
    doc = (ROOT / "docs" / "offline.md").read_text()
    block = doc.split("[`config/profiles/example.yaml`]", 1)[1].split("```yaml\n", 1)[1].split("```", 1)[0]
    assert yaml.safe_load(block) == yaml.safe_load(path.read_text())      # the documented example is the file


BAD = [
    ("segments:\n  - {duration_s: 1, rpm: 1000, bar: 5}\n  - {duration_s: 1, rpm: 4000, bar: 5}\n",
     ("segments[1].rpm = 4000", "[0, 3000] rpm")),
    ("segments:\n  - {duration_s: 1, rpm: 1000, bar: -1}\n", ("segments[0].bar = -1", "[0, 27.5] bar")),
    ("segments:\n  - {duration_s: 1, rpm: 1000, bar: 30}\n", ("segments[0].bar = 30", "[0, 27.5] bar")),
    ("segments:\n  - {duration_s: 0, rpm: 1000, bar: 5}\n", ("segments[0].duration_s = 0", "[0.001, 3600] s")),
    ("segments:\n  - {duration_s: 2000, rpm: 1000, bar: 5}\n  - {duration_s: 2000, rpm: 1000, bar: 5}\n",
     ("segments[1].duration_s = 2000", "at most 3600 s")),
    ("segments:\n  - {duration_s: 1, rpm: 1000, bar: 5, oil_temperature_c: 500}\n",
     ("segments[0].oil_temperature_c = 500", "[-40, 200] °C")),
    ("segments:\n  - {duration_s: 1, rpm: 1000, bar: 5, ramp: 'yes'}\n", ("segments[0].ramp = 'yes'", "true | false")),
    ("segments:\n  - {duration_s: 1, rpm: fast, bar: 5}\n", ("segments[0].rpm = 'fast'", "[0, 3000] rpm")),
    ("segments:\n  - {duration_s: 1, rpm: .nan, bar: 5}\n", ("segments[0].rpm = nan", "[0, 3000] rpm")),
    ("segments:\n  - {duration_s: 1, rpm: 1000}\n", ("segments[0].bar = None", "missing key")),
    ("segments:\n  - {duration_s: 1, speed: 1000, bar: 5}\n", ("segments[0].speed = 1000", "unknown key")),
    ("segments:\n  - [1, 1000, 5]\n", ("segments[0] = [1, 1000, 5]", "a mapping")),
    ("segments: []\n", ("segments = []", "at least one segment")),
    ("name: x\n", ("segments = None", "missing key")),
    ("- {duration_s: 1, rpm: 1000, bar: 5}\n", ("(document) = [", "a mapping")),
    ("name: a/b\nsegments:\n  - {duration_s: 1, rpm: 1000, bar: 5}\n", ("name = 'a/b'", "letters, digits")),
    ("segments: [\n", ("valid YAML",)),
]


@pytest.mark.parametrize("text,needles", BAD)
def test_bad_profile_file_one_line(tmp_path, capsys, text, needles):
    """Behaviour: each bad profile file gives one line naming the file, the segment and field, the value
    and the allowed range; exit 2; nothing written."""
    f = tmp_path / "bad.yaml"
    f.write_text(text)
    out = tmp_path / "o.mcap"
    assert main(["synth-bench", "--profile-file", str(f), "-o", str(out), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(f) in err[0], err
    for needle in needles:
        assert needle in err[0], err
    assert not out.exists()


def test_profile_file_checked_against_the_config_range(tmp_path, capsys, pump_7000):
    """Behaviour: 6000 rpm is fine on the 7000 rpm pump, 8 bar is not (its range is 5 bar); a missing file
    and --profile together with --profile-file are one line each."""
    f = tmp_path / "p.yaml"
    f.write_text("segments:\n  - {duration_s: 1, rpm: 6000, bar: 8}\n")
    assert main(["synth-bench", "--profile-file", str(f), "--config", str(pump_7000), "-o",
                 str(tmp_path / "o.mcap"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "segments[0].bar = 8" in err[0] and "[0, 5] bar" in err[0], err
    assert main(["synth-bench", "--profile-file", str(tmp_path / "none.yaml"), "-o", str(tmp_path / "o.mcap")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--profile-file" in err[0] and "file not found" in err[0], err
    assert main(["synth-bench", "--profile-file", str(f), "--profile", "map", "-o", str(tmp_path / "o.mcap")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "either --profile or --profile-file" in err[0], err


# ---------------------------------------------------------------- the oil temperature set-point

def test_oil_without_profile_temperatures_is_the_warm_up():
    """Closed form: a profile without oil temperatures gives exactly the bench's warm-up
    T = 70 − 40·exp(−t/90 s) °C at every tick (so the bundled bags do not change)."""
    spec = BenchSpec()
    bath = oil_bath(get_profile("transient"), spec)
    for t in np.arange(0, 26001) * 1e-3:
        assert bath(t) == oil_warmup(t, 30.0, 70.0, 90.0)
    assert bath(90.0) == pytest.approx(70 - 40 / math.e, rel=1e-15)


def test_oil_follows_stepped_and_ramped_setpoints():
    """Closed form and numerical reference: T' = (u − T)/τ.  A step from 50 to 80 °C at t = 2 s gives
    T = 80 − (80 − T(2))·exp(−(t − 2)/τ); a ramp 80 → 40 °C over 3 s then a hold agrees with a tight
    numerical integration (scipy, rtol 1e-10).  Segments without a temperature keep the previous one;
    before the first, the warm-up target 70 °C; a first segment without one starts at 30 °C."""
    from scipy.integrate import solve_ivp
    tau = 5.0
    spec = BenchSpec(temperature_warmup_tau_s=tau)
    prof = Profile("oil", (Segment(2.0, 1000, 5, oil_temperature_c=50), Segment(3.0, 1000, 5, oil_temperature_c=80),
                           Segment(3.0, 1000, 5, ramp=True, oil_temperature_c=40), Segment(4.0, 1000, 5)))
    bath = oil_bath(prof, spec)
    assert bath(0.0) == 50 and bath(1.999) == pytest.approx(50, abs=1e-12)
    for t in (2.5, 3.0, 4.99):                  # the step is a 1 µs ramp: its effect is below 1e-5 K
        assert bath(t) == pytest.approx(80 - 30 * math.exp(-(t - 2.0) / tau), abs=1e-5)

    def u(t):
        return np.interp(t, [0, 2, 2 + 1e-6, 5, 8, 12], [50, 50, 80, 80, 40, 40])
    t_a = 2.0 + 1e-6                            # after the step, from the value just checked
    ts = np.linspace(t_a, 12.0, 60)
    ref = solve_ivp(lambda t, y: (u(t) - y) / tau, (t_a, 12.0), [bath(t_a)], t_eval=ts, rtol=1e-10, atol=1e-10,
                    max_step=0.05, method="DOP853")
    np.testing.assert_allclose([bath(t) for t in ts], ref.y[0], atol=1e-7)
    warm = oil_bath(Profile("w", (Segment(1.0, 1000, 5), Segment(1.0, 1000, 5, oil_temperature_c=40))), spec)
    assert warm(0.0) == 30 and warm(1.0) == pytest.approx(oil_warmup(1.0, 30, 70, tau), abs=1e-12)
    assert warm(2.0) == pytest.approx(40 - (40 - oil_warmup(1.0, 30, 70, tau)) * math.exp(-1.0 / tau), abs=1e-5)
    assert OilBath([0.0, 1.0], [40.0, 80.0], 30.0, 0.0)(5.0) == 30.0       # τ ≤ 0: no warm-up
