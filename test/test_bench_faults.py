"""Fault scenarios of the bench emulator (``synth-bench --fault KIND[,KIND] --fault-to X --fault-start S``).

Behaviour tier unless a test says closed form or bad input: each fault kind, applied to a short emulated
run, leaves the signature physics (or the sensor's definition) says it must, relative to the healthy run
with the same seed (same noise draws); the truth is recorded in the bag's metadata and read back; every
bad option is one line naming it.  Runs last 0.4–0.8 s at 1000–2000 rpm with the flow meter at 100 Hz
and τ = 10 ms so a plateau's flow is seen within it.
"""
import io
import json

import numpy as np
import pytest
import yaml

from gerotor_twin.bench_emulator import EMULATOR_METADATA, BenchSpec, get_profile, synthesize
from gerotor_twin.bench_emulator.faults import FAULT_KINDS, Fault, FaultScenario, parse_faults
from gerotor_twin.bench_emulator.profiles import Profile, Segment
from gerotor_twin.cli import main
from gerotor_twin.errors import InputError
from gerotor_twin.io import metadata, read_topics, scalar_series

FIELDS = {"/bench/shaft_speed": "velocity[0]", "/bench/delivery_pressure": "fluid_pressure",
          "/bench/suction_pressure": "fluid_pressure", "/bench/delivery_flow": "data"}
SPEC = BenchSpec(flow_tau_s=0.01, flow_rate_hz=100.0)
#: one speed, two delivery pressures: a leakage fault shows more at the higher one
PRESSURES = Profile("pressures", (Segment(0.4, 1000, 5), Segment(0.4, 1000, 25)))
#: one pressure, two speeds: the suction restriction shows more at the higher flow
SPEEDS = Profile("speeds", (Segment(0.4, 1000, 10), Segment(0.4, 2000, 10)))
LOW, HIGH = (0.25, 0.4), (0.65, 0.8)     # second half of each plateau [s]


def _run(profile: Profile, faults=(), spec: BenchSpec = SPEC):
    """Samples of the four sensors (time since the start [s], value SI) and the result of ``synthesize``."""
    buf = io.BytesIO()
    res = synthesize(profile, buf, spec, progress=None, faults=faults)
    series = read_topics(buf.getvalue(), FIELDS)
    return {k: scalar_series(series[k], f, stamp="publish", t0_ns=spec.start_time_ns) for k, f in FIELDS.items()}, res


@pytest.fixture(scope="module")
def healthy_pressures():
    return _run(PRESSURES)[0]


@pytest.fixture(scope="module")
def healthy_speeds():
    return _run(SPEEDS)[0]


def _flow_deficit(healthy: dict, faulty: dict, window: tuple[float, float]) -> float:
    """(healthy − faulty) / healthy recorded delivery flow, mean over ``window`` [s]."""
    t, q0 = healthy["/bench/delivery_flow"]
    q1 = faulty["/bench/delivery_flow"][1]
    sel = (t > window[0]) & (t < window[1])
    return float((q0[sel] - q1[sel]).mean() / q0[sel].mean())


@pytest.mark.parametrize("kind,to,low_min,high_min", [("tip_wear", 2.0, 0.005, 0.03),
                                                       ("lateral_wear", 1.3, 0.03, 0.2),
                                                       ("housing_wear", 3.0, 1e-5, 1e-3)])
def test_wear_lowers_the_flow_more_at_high_pressure(healthy_pressures, kind, to, low_min, high_min):
    """Behaviour: worn tooth tips, side plates or housing (a step to the severity at the start) leak more,
    so the recorded flow lies below the healthy pump's, by more at 25 bar than at 5 bar (leakage grows with
    the pressure difference).  Measured at 1000 rpm (2026-12-05, ``gear_coupling: constrained``): tip ×2
    1.44 % / 5.79 %, lateral ×1.3 6.47 % / 41.1 %, housing ×3 0.0034 % / 0.21 %.  The housing clearance does
    not move the outer gear here: it rests on the inner gear (the tooth contact), so its eccentricity stays
    where it was (32–37 µm at these points); the flow loss comes through the kernel's housing clearance.
    (Without the tooth constraint, ``stages``, housing ×3 lost 0.10 % / 0.57 %: the freer gear ran further
    into the teeth within each step before the check pulled it back, and that squeeze went with the flow.)"""
    faulty, res = _run(PRESSURES, (Fault(kind, to, 0.0, 0.0),))
    low, high = (_flow_deficit(healthy_pressures, faulty, w) for w in (LOW, HIGH))
    assert low > low_min and high > high_min and high > 3 * low, (low, high)
    assert res["fault_truth"][kind] == [to] * len(res["fault_truth"]["t_s"])


def test_housing_wear_reaches_the_kernel_and_the_outer_gear_film(cfg):
    """Behaviour: the worn housing clearance replaces the kernel's and rebuilds the short-bearing film of a
    running model (its state stays valid); the tip and lateral clearances stay."""
    from gerotor_twin.model.clearance_scale import scaled_config, take_config
    from gerotor_twin.model.pump import PumpModel

    model = PumpModel(cfg, "short")
    c = cfg.clearances
    take_config(model, scaled_config(cfg, housing=2.0))
    assert model.bearing_geometry.clearance_m == model.kernel.pc.housing_clearance == 2.0 * c.housing_radial_m
    assert model.config.clearances.tooth_tip_m == c.tooth_tip_m and model.config.clearances.lateral_m == c.lateral_m


def test_air_ingress_lowers_the_flow_and_raises_the_free_air(healthy_pressures, cfg):
    """Behaviour: free air rising from the pump's 0.1 % to 5 % (ramp over the run) fills each chamber with
    more gas at suction pressure, compressed away on delivery: the recorded flow falls, by more at the end
    (25 bar, 5 % air) than at the start (5 bar, little air); the truth's free air rises linearly.  Measured
    (step to 5 %, 2026-12-04): 6.1 % at 5 bar, 7.9 % at 25 bar."""
    faulty, res = _run(PRESSURES, (Fault("air_ingress", 0.05),))
    truth = res["fault_truth"]
    air = np.array(truth["air_ingress"])
    np.testing.assert_allclose(air, cfg.air.air_fraction + (0.05 - cfg.air.air_fraction) * np.array(truth["t_s"]) / 0.8,
                               rtol=1e-12)
    early, late = _flow_deficit(healthy_pressures, faulty, (0.05, 0.2)), _flow_deficit(healthy_pressures, faulty, HIGH)
    assert 0.0 < early < 0.02 < late, (early, late)


def test_air_ingress_lowers_the_flow_more_at_low_suction_pressure():
    """Behaviour: the same 5 % of free air (at atmospheric pressure) takes twice the volume at half of it, so
    with the suction line's drop raised to put the suction at ≈ 51 kPa (1000 rpm / 10 bar) the flow lost to
    the air is about twice that at ≈ 101 kPa.  Measured (2026-12-04): 6.7 % and 14.3 %."""
    from dataclasses import replace

    one = Profile("one", (Segment(0.4, 1000, 10),))
    deficits = []
    for drop in (5.0e3, 4.5e5):                  # suction-line drop at the top speed [Pa]; 1/9 of it at 1000 rpm
        spec = replace(SPEC, suction_drop_pa=drop)
        healthy, faulty = (_run(one, faults, spec)[0] for faults in ((), (Fault("air_ingress", 0.05, 0.0, 0.0),)))
        deficits.append(_flow_deficit(healthy, faulty, LOW))
    assert 0.03 < deficits[0] and deficits[1] > 1.7 * deficits[0], deficits


def test_suction_restriction_lowers_the_suction_pressure_with_the_flow(healthy_speeds, cfg):
    """Behaviour and closed form: a restriction of 6e4 Pa at rated flow (a step at the start) lowers the
    recorded suction pressure by to·(Q/Q_rated)², Q the pump's intake flow (here within 10 % of the healthy
    run's delivered flow, leakage and compression apart), so by about 4× as much at 2000 rpm as at 1000."""
    import math

    to = 6.0e4
    faulty, _ = _run(SPEEDS, (Fault("suction_restriction", to, 0.0, 0.0),))
    t, ps0 = healthy_speeds["/bench/suction_pressure"]
    ps1 = faulty["/bench/suction_pressure"][1]
    tq, q0 = healthy_speeds["/bench/delivery_flow"]
    q_rated = cfg.gears.displacement_closed_form() * cfg.range.max_speed_rpm / 60.0
    drops = []
    for lo, hi in (LOW, HIGH):
        sel, selq = (t > lo) & (t < hi), (tq > lo) & (tq < hi)
        drop, expected = float((ps0[sel] - ps1[sel]).mean()), to * (q0[selq].mean() / q_rated) ** 2
        assert drop == pytest.approx(expected, rel=0.2), (lo, drop, expected)
        drops.append(drop)
    assert drops[1] > 3.0 * drops[0] and math.isfinite(drops[1])


@pytest.fixture(scope="module")
def sensor_faults_run():
    """Offset (ramped), dropout (a step at 0.105 s) and drift on the 0.4 s test profile, and the healthy run."""
    faults = (Fault("pressure_offset", 3.0e4, 0.1, 0.2), Fault("speed_dropout", 0.25, 0.105),
              Fault("flowmeter_drift", 0.1, 0.05))
    return _run(get_profile("test"), faults)[0], _run(get_profile("test"))[0], faults


def test_pressure_offset_shifts_the_delivery_pressure_by_the_offset(sensor_faults_run):
    """Closed form: with the same noise, every recorded delivery pressure moves by exactly the offset at its
    time (0 before 0.1 s, linear to 3e4 Pa at 0.3 s, then held); the suction pressure does not move."""
    faulty, healthy, faults = sensor_faults_run
    t, p1 = faulty["/bench/delivery_pressure"]
    t0, p0 = healthy["/bench/delivery_pressure"]
    assert np.array_equal(t, t0)
    np.testing.assert_allclose(p1 - p0, 3.0e4 * np.clip((t - 0.1) / 0.2, 0.0, 1.0), atol=1e-6)
    assert np.array_equal(faulty["/bench/suction_pressure"][1], healthy["/bench/suction_pressure"][1])


def test_speed_dropout_drops_the_stated_count(sensor_faults_run):
    """Closed form: a quarter of the shaft-speed samples after 0.105 s are missing, ⌊n/4⌋ of the n there
    (100 Hz: n = 30, 7 missing), none before; every sample left is the healthy run's."""
    faulty, healthy, _ = sensor_faults_run
    t1, w1 = faulty["/bench/shaft_speed"]
    t0, w0 = healthy["/bench/shaft_speed"]
    n_after = int(np.sum(t0 > 0.105))
    assert len(t0) - len(t1) == n_after // 4 == 7
    assert np.array_equal(t1[t1 < 0.105], t0[t0 < 0.105])
    kept = np.isin(t0, t1)
    assert np.array_equal(w0[kept], w1)


def test_flowmeter_drift_grows_the_recorded_to_true_ratio(sensor_faults_run):
    """Closed form: the flow meter's gain error grows linearly from 0 at 0.05 s to 0.1 at the end (0.4 s), so
    every recorded flow sample is the healthy one × (1 + 0.1·(t − 0.05)/0.35)."""
    faulty, healthy, _ = sensor_faults_run
    t, q1 = faulty["/bench/delivery_flow"]
    q0 = healthy["/bench/delivery_flow"][1]
    np.testing.assert_allclose(q1 / q0, 1.0 + 0.1 * np.clip((t - 0.05) / 0.35, 0.0, 1.0), rtol=1e-12)


def test_metadata_holds_the_fault_truth(tmp_path, capsys):
    """Behaviour: ``synth-bench --fault`` records each fault resolved (kind, severity, unit, start, ramp, end),
    its values every 0.1 s and the count of missing speed samples in the bag's metadata; read back with the
    project's reader they are the faults of the command line; the command is stored with every fault setting."""
    out, truth = tmp_path / "f.mcap", tmp_path / "truth.json"
    assert main(["synth-bench", "--profile", "test", "-o", str(out), "--quiet", "--fault", "tip_wear,speed_dropout",
                 "--fault-to", "1.4,0.5", "--fault-start", "0.1", "--json", str(truth)]) == 0
    assert "fault tip_wear: 1.4 (x tooth-tip clearance) from 0.1 s, reached at 0.4 s" in capsys.readouterr().out
    assert json.loads(truth.read_text())["fault_truth"]["tip_wear"][-1] == 1.4
    meta = metadata(out)[EMULATOR_METADATA]
    recorded = yaml.safe_load(meta["faults"])
    assert recorded == [Fault("tip_wear", 1.4, 0.1).resolved(0.4).as_dict(),
                        Fault("speed_dropout", 0.5, 0.1, 0.0).as_dict()]
    assert recorded[0]["unit"] == FAULT_KINDS["tip_wear"].unit and recorded[0]["end_s"] == pytest.approx(0.4)
    series = json.loads(meta["fault_series"])
    np.testing.assert_allclose(series["t_s"], np.arange(5) * 0.1)
    np.testing.assert_allclose(series["tip_wear"], [1.0, 1.0, 1.0 + 0.4 / 3, 1.0 + 0.8 / 3, 1.4], rtol=1e-12)
    assert series["speed_dropout"] == [0.0, 0.5, 0.5, 0.5, 0.5]
    assert meta["speed_samples_dropped"] == "15"           # 30 samples from 0.1 s on (the one at 0.1 s included)
    assert meta["command"].endswith("--fault tip_wear,speed_dropout --fault-to 1.4,0.5 --fault-start 0.1,0.1 "
                                    "--fault-ramp 0.3,0")


def test_no_fault_writes_no_fault_metadata():
    """Behaviour: a healthy run records no fault keys and its result has no fault truth."""
    buf = io.BytesIO()
    res = synthesize(get_profile("test"), buf, BenchSpec(), progress=None)
    assert "fault_truth" not in res
    assert not {"faults", "fault_series", "speed_samples_dropped"} & set(metadata(buf.getvalue())[EMULATOR_METADATA])


@pytest.mark.parametrize("args,needle", [
    (("--fault", "rust"), "--fault = 'rust' is invalid; allowed: tip_wear | lateral_wear"),
    (("--fault", "tip_wear", "--fault-to", "0.5"), "--fault-to (tip_wear) = 0.5 is invalid; allowed: [1, 3] x tooth"),
    (("--fault", "pressure_offset", "--fault-to", "1e6"), "--fault-to (pressure_offset) = 1000000.0 is invalid; "
                                                         "allowed: [-500000, 500000] Pa"),
    (("--fault", "speed_dropout", "--fault-to", "1.5"), "--fault-to (speed_dropout) = 1.5 is invalid; allowed: [0, 1]"),
    (("--fault", "tip_wear,air_ingress", "--fault-to", "1.2"), "--fault-to = '1.2' is invalid; allowed: 2 values"),
    (("--fault", "tip_wear,air_ingress", "--fault-start", "0,0,0"), "--fault-start = '0,0,0' is invalid; allowed: "
                                                                     "one value, or 2"),
    (("--fault", "tip_wear", "--fault-to", "lots"), "--fault-to = 'lots' is invalid; allowed: a number"),
    (("--fault", "tip_wear", "--fault-start", "0.5"), "--fault-start (tip_wear) = 0.5 is invalid; allowed: [0, 0.4) s"),
    (("--fault", "tip_wear", "--fault-start", "-1"), "--fault-start (tip_wear) = -1.0 is invalid; allowed:"),
    (("--fault", "tip_wear", "--fault-ramp", "nan"), "--fault-ramp (tip_wear) = nan is invalid"),
    (("--fault", "tip_wear,tip_wear"), "--fault = 'tip_wear,tip_wear' is invalid; allowed: each kind once"),
    (("--fault", "tip_wear,"), "allowed: a comma-separated list without empty items"),
    (("--fault-to", "2"), "--fault-to = '2' is invalid; allowed: only with --fault KIND[,KIND]"),
])
def test_bad_fault_options_one_line(tmp_path, capsys, args, needle):
    """Bad input: every bad fault option is one line naming the option (and kind), the value and the allowed
    range, exit 2, and nothing is written."""
    out = tmp_path / "x.mcap"
    assert main(["synth-bench", "--profile", "test", "-o", str(out), "--quiet", *args]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and needle in err[0], err
    assert not out.exists()


def test_faults_the_pump_cannot_take_are_refused_before_work(cfg):
    """Bad input: air ingress on a pump without free air in its state equation (``fluid_model: paper``) and a
    wear that takes a clearance outside the config's range (with ``--wear-to``) are refused by name."""
    from dataclasses import replace

    with pytest.raises(InputError, match="air_ingress.*fluid_model: mixture"):
        synthesize(get_profile("test"), io.BytesIO(), BenchSpec(), config=replace(cfg, fluid_model="paper"),
                   progress=None, faults=(Fault("air_ingress", 0.01),))
    with pytest.raises(InputError, match=r"--fault-to \(lateral_wear\): emulated pump clearances.tooth_tip_m = .*"
                                         r"at full severity, with --wear-to"):
        FaultScenario((Fault("lateral_wear", 3.0),), 1.0).check(cfg, wear_end=100.0)
    assert parse_faults(None) == ()
    assert [f.to for f in parse_faults("tip_wear,flowmeter_drift")] == [1.5, 0.05]
