"""Bench pumps (``synth-bench --bench-pump F``): an emulated pump and sensors that differ from the twin in form.

Behaviour tier: what a deviation does to the emulated pump and to the recorded samples, in the direction
physics says; every bad field refused with one line naming it; the description recorded in the bag and
read back; every shipped bench pump loads.  Runs are short (the 0.4 s ``test`` profile, 1000 rpm,
10 → 15 bar at 0.2 s) so the file stays within the suite's time.
"""
import io
import math
from pathlib import Path

import numpy as np
import pytest
import yaml

from gerotor_twin.bench_emulator import EMULATOR_METADATA, BenchSpec, get_profile, synthesize
from gerotor_twin.bench_emulator.bench_pump import (PUMP_FIELDS, SENSOR_FIELDS, BenchPump, load_bench_pump,
                                                    parse_bench_pump)
from gerotor_twin.bench_emulator.emulator import emulated_config
from gerotor_twin.cli import main
from gerotor_twin.errors import InputError
from gerotor_twin.io import metadata, read_topics, scalar_series

ROOT = Path(__file__).resolve().parent.parent
SHIPPED = sorted((ROOT / "config" / "bench_pumps").glob("*.yaml"))
FIELDS = {"/bench/shaft_speed": "velocity[0]", "/bench/delivery_pressure": "fluid_pressure",
          "/bench/delivery_flow": "data", "/bench/oil_temperature": "temperature"}
BIASES = {"speed": ("bias_rad_s", 0.3), "delivery_pressure": ("bias_pa", 2.0e4),
          "delivery_flow": ("bias_m3s", -1.0e-6), "oil_temperature": ("bias_c", 1.5)}


def _run(bench_pump: BenchPump, base: BenchSpec = BenchSpec()) -> tuple[bytes, dict]:
    buf = io.BytesIO()
    res = synthesize(get_profile("test"), buf, bench_pump.bench_spec(base), bench_pump=bench_pump, progress=None)
    return buf.getvalue(), res


def _samples(data: bytes) -> dict[str, tuple[np.ndarray, np.ndarray]]:
    """Every recorded sample of the four sensors: time since the start of the recording [s], value (SI)."""
    series = read_topics(data, FIELDS)
    t0 = BenchSpec().start_time_ns
    return {topic: scalar_series(series[topic], f, stamp="publish", t0_ns=t0) for topic, f in FIELDS.items()}


@pytest.fixture(scope="module")
def nominal_run():
    """The nominal pump with the emulator's default sensors, seen as a bench pump."""
    return _run(BenchPump(name="nominal"))


def test_larger_clearances_lower_the_delivered_flow(nominal_run):
    """Behaviour: a bench pump with the tooth-tip clearance ×1.3 (and one with the lateral ×1.3) leaks more,
    so every flow-meter sample it records lies below the nominal pump's (same seed, same noise draws;
    the meter starts at each pump's own run-in flow).  Mean recorded flow on the 0.4 s test profile
    (2026-12-04): nominal 20.78, tip ×1.3 20.69, lateral ×1.3 18.58 L/min — the lateral gaps carry most
    of this pump's leakage."""
    flows = {}
    for label, bp in (("nominal", None), ("tip", BenchPump(tooth_tip_factor=1.3)),
                      ("lateral", BenchPump(lateral_factor=1.3))):
        data = nominal_run[0] if bp is None else _run(bp)[0]
        flows[label] = _samples(data)["/bench/delivery_flow"][1]
    q0 = flows["nominal"]
    for label in ("tip", "lateral"):
        assert np.all(flows[label] < q0 * (1 - 1e-3)), {k: float(v.mean()) for k, v in flows.items()}


def test_port_timing_offset_changes_the_waveform_not_the_leakage(cfg):
    """Behaviour: a valve plate turned 1.5° late (every kidney edge reached later) keeps the chamber
    trapped and compressed longer before the delivery port opens, so the chamber's pressure peak rises
    (measured 11.8 → 13.1 bar absolute at 1000 rpm / 10 bar, fixed-centre model) and the delivery flow's
    ripple changes shape (≈ 4 % of its peak-to-peak), while the mean flow stays within 0.1 % (timing is
    not a leakage path)."""
    from gerotor_twin.model.pump import Inputs, PumpModel

    w = 1000 * math.pi / 30
    inp = Inputs(w, 101325.0, 101325.0 + 10e5, 313.15)
    outs = {}
    for off in (0.0, 1.5):
        model = PumpModel(emulated_config(cfg, 1.0, BenchPump(port_timing_offset_deg=off)), "fixed")
        state, _ = model.advance(model.initial_state(inp), 2 * 2 * math.pi / w, inp)
        outs[off] = model.advance(state, 2 * math.pi / w, inp)[1]
    a, b = outs[0.0], outs[1.5]
    assert b.chamber_pressures.max() > a.chamber_pressures.max() + 0.5e5
    n = min(len(a), len(b))
    diff = np.sqrt(np.mean((a.delivery_flow[:n] - b.delivery_flow[:n]) ** 2))
    assert diff > 0.01 * np.ptp(a.delivery_flow)
    assert b.delivery_flow.mean() == pytest.approx(a.delivery_flow.mean(), rel=1e-3)


def test_sensor_bias_shows_in_the_samples(nominal_run):
    """Behaviour: with the same seed (same noise), a bias on each of the four sensors moves every
    recorded sample of that sensor by the bias and nothing else: the mean offset equals the bias
    far inside the sensor's noise."""
    sensors = {s: {key: value} for s, (key, value) in BIASES.items()}
    biased = _samples(_run(parse_bench_pump({"sensors": sensors}))[0])
    plain = _samples(nominal_run[0])
    for (sensor, (_, bias)), topic in zip(BIASES.items(), FIELDS):
        d = biased[topic][1] - plain[topic][1]
        assert np.array_equal(biased[topic][0], plain[topic][0]), topic
        np.testing.assert_allclose(d, bias, rtol=1e-6, atol=1e-9 * max(1.0, np.abs(plain[topic][1]).max()),
                                   err_msg=sensor)


def test_pressure_sensor_lag_is_its_time_constant():
    """Behaviour: a delivery-pressure transducer with τ = 50 ms, behind a valve that follows its set-point
    within 1 ms, records the 10 → 15 bar step at 0.2 s with its 63 % point ≈ τ later (within 5 ms at
    1 kHz sampling; measured 52 ms, the valve's 1 ms and one sample included)."""
    tau = 0.05
    base = BenchSpec(valve_tau_s=1e-3, pressure_rate_hz=1000.0)
    data, _ = _run(parse_bench_pump({"sensors": {"delivery_pressure": {"tau_s": tau}}}), base)
    t, p = _samples(data)["/bench/delivery_pressure"]
    gauge = (p - 101325.0) / 1e5
    before, after = np.mean(gauge[(t > 0.15) & (t < 0.2)]), 15.0
    assert before == pytest.approx(10.0, abs=0.1)
    crossing = t[(t > 0.2) & (gauge >= before + 0.632 * (after - before))][0]
    assert crossing - 0.2 == pytest.approx(tau, abs=5e-3)


def test_metadata_holds_the_resolved_description(tmp_path, cfg):
    """Behaviour: ``synth-bench --bench-pump F`` records the resolved bench pump (every value used, the
    nominal config's where the file is silent, every sensor setting), the file's text and the emulated
    pump's config in the bag; read back, the description parses to the same bench pump; the command is
    stored with ``--bench-pump`` and ``rosbags`` still reads the file."""
    from rosbags.highlevel import AnyReader

    src = tmp_path / "tip.yaml"
    src.write_text("# tips worn\nname: tips\npump:\n  clearance_factors: {tooth_tip: 1.2}\n"
                   "sensors:\n  delivery_flow: {bias_m3s: 1.0e-6}\n")
    out = tmp_path / "b.mcap"
    assert main(["synth-bench", "--profile", "test", "--bench-pump", str(src), "-o", str(out), "--quiet"]) == 0
    meta = metadata(out)[EMULATOR_METADATA]
    described = parse_bench_pump(yaml.safe_load(meta["bench_pump"]))
    bp = load_bench_pump(src)
    assert described == bp.resolved(cfg, bp.bench_spec())
    assert described.tooth_tip_factor == 1.2 and described.orifice_law == cfg.orifice.law
    assert described.sensors["flow_bias_m3s"] == 1.0e-6 and described.sensors["pressure_noise_pa"] == 2000.0
    assert meta["bench_pump_file_text"] == src.read_text()
    emulated = yaml.safe_load(meta["emulated_pump_config"])
    assert emulated["clearances"]["tooth_tip_m"] == pytest.approx(1.2 * cfg.clearances.tooth_tip_m)
    assert emulated["clearances"]["lateral_m"] == pytest.approx(cfg.clearances.lateral_m)
    assert "--bench-pump" in meta["command"] and "--clearance-factor" not in meta["command"]
    with AnyReader([out]) as reader:
        assert len(list(reader.messages())) > 0


def _bad_values() -> list[tuple[str, str, object]]:
    """(section, dotted key, a value outside its range) for every field of both tables."""
    out = []
    for section, table in (("pump", PUMP_FIELDS), ("sensors", SENSOR_FIELDS)):
        for path, (_, allowed) in table.items():
            out.append((section, path, "nope" if isinstance(allowed[0], str) else allowed[1] * 2 + 1))
    return out


@pytest.mark.parametrize("section,path,value", _bad_values())
def test_every_bad_field_is_refused_naming_it(section, path, value):
    """Bad input: every field outside its allowed range is one InputError naming the field, the value and
    the range."""
    group, key = path.split(".")
    with pytest.raises(InputError) as e:
        parse_bench_pump({section: {group: {key: value}}}, where="f.yaml: ")
    text = str(e.value)
    assert f"f.yaml: {section}.{path} = " in text and "allowed:" in text and "\n" not in text


@pytest.mark.parametrize("raw,needle", [
    ({"pump": {"clearance_factors": {"tip": 1.2}}}, "pump.clearance_factors.tip"),
    ({"pump": {"valves": {}}}, "pump.valves"),
    ({"sensors": {"speed": {"bias_rad_s": True}}}, "sensors.speed.bias_rad_s"),
    ({"sensors": {"speed": {"bias_rad_s": float("nan")}}}, "sensors.speed.bias_rad_s"),
    ({"sensors": {"speed": "fast"}}, "sensors.speed"),
    ({"name": "a b"}, "name"),
    ({"faults": 1}, "faults"),
    ([1, 2], "(document)")])
def test_unknown_keys_and_types_are_refused(raw, needle):
    """Bad input: unknown keys, non-numbers, bad names: one InputError naming the field."""
    with pytest.raises(InputError) as e:
        parse_bench_pump(raw)
    assert str(e.value).startswith(needle)


def test_cli_errors_are_one_line(tmp_path, capsys):
    """Bad input: a bad bench pump file, a missing file, a directory, an alias bomb, and --clearance-factor
    together with --bench-pump each give one line on stderr and exit 2."""
    bad = tmp_path / "bad.yaml"
    bad.write_text("pump:\n  ports: {timing_offset_deg: 9}\n")
    bomb = tmp_path / "bomb.yaml"
    bomb.write_text('a0: &a0 ["x"]\n' + "".join(f"a{i}: &a{i} [" + ", ".join([f"*a{i - 1}"] * 10) + "]\n"
                                                for i in range(1, 12)))
    good = SHIPPED[0]
    for args, needle in ((["--bench-pump", str(bad)], "pump.ports.timing_offset_deg = 9"),
                         (["--bench-pump", str(tmp_path / "none.yaml")], "--bench-pump"),
                         (["--bench-pump", str(tmp_path)], "--bench-pump"),
                         (["--bench-pump", str(bomb)], "--bench-pump"),
                         (["--bench-pump", str(good), "--clearance-factor", "1.2"], "--clearance-factor = 1.2")):
        assert main(["synth-bench", "--profile", "test", "-o", str(tmp_path / "x.mcap"), "--quiet", *args]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and needle in err[0], err


def test_shipped_bench_pumps_load_and_differ_in_kind(cfg):
    """The bench pumps under config/bench_pumps/ load, give a valid emulated pump, each has a header
    comment and a description, and no two deviate in the same fields."""
    assert len(SHIPPED) >= 3
    kinds = []
    for path in SHIPPED:
        bp = load_bench_pump(path)
        assert path.read_text().startswith("# ") and bp.description and bp.name == path.stem
        emulated_config(cfg, 1.0, bp)
        set_fields = {a for a, v in vars(bp).items() if a not in ("name", "description", "source", "sensors")
                      and v not in (None, 1.0, 0.0)} | {f"sensor {k}" for k in bp.sensors}
        kinds.append(frozenset(set_fields))
    assert len(set(kinds)) == len(kinds)


@pytest.mark.parametrize("path", SHIPPED, ids=lambda p: p.stem)
def test_each_shipped_bench_pump_runs(path):
    """Each shipped bench pump runs through the emulator (0.4 s test profile), records all bench topics
    and its own name in the metadata, and delivers less than the theoretical flow."""
    bp = load_bench_pump(path)
    data, res = _run(bp)
    assert all(n > 0 for n in res["message_counts"].values())
    assert yaml.safe_load(metadata(data)[EMULATOR_METADATA]["bench_pump"])["name"] == bp.name
    q = _samples(data)["/bench/delivery_flow"][1]
    assert np.all((q > 0.5 * 22.78e-6 * 1000 / 60) & (q < 22.78e-6 * 1000 / 60))


def test_a_return_line_flow_meter_reads_the_expanded_volume(cfg):
    """Closed form: with the paper's oil law (ln ρ/ρ₀ = (p − p_atm)/β above its switch band) at a constant 40 °C, a
    flow meter in the return line (``delivery_flow.at: atmospheric``) reads the delivered flow × exp((p_d −
    p_atm)/β): with the same seed and no meter noise or lag, the readings over 10 bar and over 15 bar (the test
    profile's step at 0.2 s, a 1 ms valve) are those at the delivery pressure times exp(10e5/β) and exp(15e5/β)
    (to 1e-6, the law's switch band at p_atm)."""
    paper = cfg.with_fluid_model("paper")
    base = BenchSpec(valve_tau_s=1e-3, temperature_start_c=40.0, temperature_end_c=40.0, flow_rate_hz=1000.0)
    flows = {}
    for at in ("delivery", "atmospheric"):
        bp = parse_bench_pump({"sensors": {"delivery_flow": {"tau_s": 0.0, "noise_rel": 0.0, "noise_m3s": 0.0,
                                                             "at": at}}})
        buf = io.BytesIO()
        synthesize(get_profile("test"), buf, bp.bench_spec(base), config=paper, bench_pump=bp, progress=None)
        flows[at] = _samples(buf.getvalue())["/bench/delivery_flow"]
    t, ratio = flows["delivery"][0], flows["atmospheric"][1] / flows["delivery"][1]
    beta = paper.oil.bulk_modulus(313.15)
    for (t0, t1), bar in (((0.1, 0.19), 10.0), ((0.3, 0.4), 15.0)):
        sel = (t > t0) & (t < t1)
        assert sel.sum() >= 5 and ratio[sel] == pytest.approx(math.exp(bar * 1e5 / beta), rel=1e-6), bar
