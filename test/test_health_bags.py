"""Health monitoring over the shipped bags with run-bag (the node's core): wear detection, tracking, no false alarm.

The twin runs the config calibrated on bags/bench_map.mcap (bags/pump_fitted_bench_map.yaml).
Truth comes from the emulated pump itself (short-bearing model, emulator numerics) at the
set-point, clearance factor and true oil temperature of each instant (the recording's oil warms
from 30 to 50 °C): k_true = its flow loss / the twin's at that temperature.
"""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from gerotor_twin.bench_emulator import BenchSpec, get_profile
from gerotor_twin.bench_emulator.emulator import EMULATOR_METADATA, emulated_config, wear_factor
from gerotor_twin.bench_emulator.sensors import oil_warmup
from gerotor_twin.config import load_config
from gerotor_twin.io import open_mcap, read_topics
from gerotor_twin.io.reader import multiarray_series
from gerotor_twin.model.clearance_scale import scale_clearances
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady
from gerotor_twin.offline.run_bag import run_bag
from gerotor_twin.twin import TwinSettings
from gerotor_twin.twin.diagnosis import KINDS
from gerotor_twin.twin.health import HEALTH_FIELDS, HEALTH_STATUS, HealthSettings
from gerotor_twin.units import celsius_to_kelvin

BAGS = Path(__file__).resolve().parent.parent / "bags"
FITTED = BAGS / "pump_fitted_bench_map.yaml"
ALARM_DELAY_S = 6.0     #: stated in docs/calibration_health.md: WARN / ERROR at most this long after the crossing


def _health(path):
    s = read_topics(path, ["/twin/health"])["/twin/health"]
    t, v, _ = multiarray_series(s)
    return t - t[0] + 0.0, [dict(zip(HEALTH_FIELDS, row)) for row in v], t


def _health_statuses(path):
    rows = read_topics(path, ["/diagnostics"])["/diagnostics"]
    out = []
    for msg in rows.messages:
        for st in msg.status:
            if st.name == HEALTH_STATUS:
                out.append(int.from_bytes(st.level, "little") if isinstance(st.level, bytes) else int(st.level))
    return out


def _twin_settings(bag) -> TwinSettings:
    """run-bag's settings with the thermometer lag compensated: the emulated thermometer's τ is in the
    bag's metadata (a bench engineer takes it from the sensor's data sheet)."""
    spec = json.loads(open_mcap(bag).metadata[EMULATOR_METADATA]["spec"])
    return TwinSettings(max_span_s=math.inf, oil_sensor_tau_s=spec["temperature_tau_s"])


@pytest.fixture(scope="module")
def wear_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("health") / "wear_twin.mcap"
    bag = BAGS / "bench_wear.mcap"
    run_bag(bag, out, config_path=FITTED, progress=None, settings=_twin_settings(bag))
    return out


@pytest.fixture(scope="module")
def emulated():
    """The emulated pump of the wear bag, its spec and profile (from the bag's metadata)."""
    meta = open_mcap(BAGS / "bench_wear.mcap").metadata[EMULATOR_METADATA]
    spec = BenchSpec(**json.loads(meta["spec"]))
    cfg = emulated_config(load_config(), spec.clearance_factor)
    return spec, get_profile(meta["profile"]), cfg, PumpModel(cfg, spec.bearing)


def _oil_k(spec, t):
    """True oil temperature of the emulated pump at time t [s] of the recording [K]."""
    return celsius_to_kelvin(oil_warmup(t, spec.temperature_start_c, spec.temperature_end_c,
                                        spec.temperature_warmup_tau_s))


def _loss(model, rpm, bar, oil_k):
    r = run_steady(model, rpm, bar, oil_temperature=oil_k)
    return r.theoretical_flow_m3s - r.mean_delivery_flow_m3s, r.theoretical_flow_m3s


def test_wear_alarms_agree_with_the_truth(wear_run, emulated):
    """Behaviour (known truth): at every update, when the emulated pump's efficiency drop at the reference
    point (at the monitor's reference oil temperature) is more than 2 reported σ beyond a threshold the
    level has reached that alarm, and when it is more than 2 σ short of it the level has not; both WARN
    and ERROR are reached, in that order, each at most ALARM_DELAY_S after (and not more than 1 s before)
    the emulated drop crosses its threshold. (σ: the published reference-efficiency sd; between the two
    bounds the truth is within the monitor's own stated uncertainty and either level is right.)"""
    spec, prof, cfg, emu = emulated
    hs = HealthSettings()

    def drop_pt(t):
        scale_clearances(emu, cfg, wear_factor(spec, t, prof.duration_s) / spec.clearance_factor)
        loss, qth = _loss(emu, hs.reference_rpm, hs.reference_bar, celsius_to_kelvin(hs.reference_oil_c))
        return 100 * loss / qth
    base = drop_pt(0.0)
    ts = np.linspace(0.0, prof.duration_s, 17)       # the loss is smooth in t (linear wear): 4 s steps
    drops = np.array([drop_pt(t) for t in ts]) - base
    _, rows, t_abs = _health(wear_run)
    t_rel = t_abs - 1_735_689_600.0            # the emulator's fixed start (2025-01-01T00:00:00Z)
    checked = 0
    for t, r in zip(t_rel, rows):
        if r["updates"] < hs.min_updates:
            continue
        true, two_sd = float(np.interp(t - hs.window_s / 2, ts, drops)), 200 * r["reference_efficiency_sd"]
        for level, pt in ((1, hs.warn_pt), (2, hs.error_pt)):
            if true > pt + two_sd:
                assert r["level"] >= level, (t, true, two_sd, r)
                checked += 1
            elif true < pt - two_sd:
                assert r["level"] < level, (t, true, two_sd, r)
                checked += 1
    assert checked >= len(rows)                  # most updates are decisive for both thresholds
    t_warn = next(t for t, r in zip(t_rel, rows) if r["level"] in (1, 2))
    t_err = next(t for t, r in zip(t_rel, rows) if r["level"] == 2)
    print(f"\nemulated drop crosses {hs.warn_pt} pt at {np.interp(hs.warn_pt, drops, ts):.1f} s, WARN at "
          f"{t_warn:.1f} s; {hs.error_pt} pt at {np.interp(hs.error_pt, drops, ts):.1f} s, ERROR at {t_err:.1f} s")
    assert t_warn < t_err
    t_warn_true, t_err_true = (float(np.interp(pt, drops, ts)) for pt in (hs.warn_pt, hs.error_pt))
    assert t_warn_true - 1.0 <= t_warn <= t_warn_true + ALARM_DELAY_S
    assert t_err_true - 1.0 <= t_err <= t_err_true + ALARM_DELAY_S
    levels = _health_statuses(wear_run)
    assert levels[-1] == 2 and 1 in levels


def test_wear_estimate_follows_emulated_factor(wear_run, emulated):
    """Golden (known truth): every update's leakage factor is within 2 reported standard deviations of the
    emulated pump's (its flow loss over the twin's at the set-point, clearance factor and oil temperature of
    the middle of the update's window)."""
    spec, prof, cfg, emu = emulated
    twin = PumpModel(load_config(FITTED), "mobility")
    _, rows, t_abs = _health(wear_run)
    z = []
    half = HealthSettings().window_s / 2              # an update is stamped at the end of its window
    for t_end, r in zip(t_abs - 1_735_689_600.0, rows):
        t = t_end - half
        w, p = prof.setpoints([t])
        rpm, bar = w[0] * 30 / math.pi, p[0] / 1e5
        scale_clearances(emu, cfg, wear_factor(spec, t, prof.duration_s) / spec.clearance_factor)
        oil = _oil_k(spec, t)
        k_true = _loss(emu, rpm, bar, oil)[0] / _loss(twin, rpm, bar, oil)[0]
        z.append((r["leakage_factor"] - k_true) / r["leakage_factor_sd"])
    print(f"\n{len(z)} updates, max |k - k_true| / sd = {np.abs(z).max():.2f}")
    assert len(z) >= 30
    assert np.all(np.abs(z) <= 2.0)


def test_no_false_alarm_on_healthy_bag(tmp_path):
    """Behaviour: on the healthy transient bag the health status never leaves OK (after learning) and the
    classifier names no fault once learnt."""
    out = tmp_path / "tr.mcap"
    bag = BAGS / "bench_transient.mcap"
    run_bag(bag, out, config_path=FITTED, progress=None, settings=_twin_settings(bag))
    _, rows, _ = _health(out)
    assert len(rows) >= 5
    assert {r["level"] for r in rows} <= {0.0, 3.0}
    assert set(_health_statuses(out)) <= {0, 3}
    assert max(abs(r["leakage_factor"] - 1) for r in rows) < 0.05
    assert {KINDS[int(r["fault"])] for r in rows if r["level"] != 3.0} == {"healthy"}


def test_health_command_lists_alarm_intervals(wear_run, tmp_path, capsys):
    """Behaviour: `gerotor-twin health` prints the updates and the WARN then ERROR intervals, JSON alike."""
    from gerotor_twin.cli import main
    js = tmp_path / "h.json"
    assert main(["health", str(wear_run), "--every", "10", "--json", str(js)]) == 0
    out = capsys.readouterr().out
    assert "WARN from" in out and "ERROR from" in out
    alarms = json.loads(js.read_text())["alarms"]
    assert [a[0] for a in alarms] == ["WARN", "ERROR"] and alarms[0][2] < alarms[1][1]


def test_health_command_names_the_fault(wear_run, tmp_path):
    """Behaviour (end to end: emulated bench → run-bag → health): every alarm of the wear bag (tip and lateral
    clearance opening together) is named a wear, with its probability (a tentative naming: the other wear as its
    rival); the printed alarm lines name it."""
    from gerotor_twin.cli import main
    js = tmp_path / "h.json"
    assert main(["health", str(wear_run), "--json", str(js)]) == 0
    records = json.loads(js.read_text())["alarm_records"]
    assert [a["level"] for a in records] == ["WARN", "ERROR"]
    for a in records:
        assert set(a) == {"start_s", "end_s", "level", "fault", "confidence", "rival", "first_fault",
                          "first_confidence", "named_at_s"}
        assert a["start_s"] <= a["named_at_s"] <= a["end_s"]
        assert a["fault"] in ("tip_wear", "lateral_wear") and 0.3 < a["confidence"] <= 1.0, a
        assert a["rival"] in (None, *{"tip_wear", "lateral_wear"} - {a["fault"]}), a


def test_diagnostics_name_the_fault(wear_run):
    """Behaviour: the last /diagnostics health status of the wear run names a wear in its text and values, with
    its closest rival and their separation."""
    rows = read_topics(wear_run, ["/diagnostics"])["/diagnostics"]
    last = [st for msg in rows.messages for st in msg.status if st.name == HEALTH_STATUS][-1]
    values = {kv.key: kv.value for kv in last.values}
    assert values["fault"] in ("tip_wear", "lateral_wear")
    assert f"fault: {values['fault']} (probability" in last.message
    assert KINDS[int(float(values["fault_rival"]))] in KINDS[1:6] and float(values["fault_separation"]) >= 0.0
    assert ("tentative: not yet told apart from" in last.message) == (values["fault_tentative"] == "1")


@pytest.mark.parametrize("item", ["bogus=1", "adapt=maybe", "warn_pt=x", "warn_pt=-3"])
def test_run_bag_bad_health_setting(tmp_path, capsys, item):
    """Bad input: a bad --health item is one line naming the setting; nothing is written."""
    from gerotor_twin.cli import main
    out = tmp_path / "o.mcap"
    assert main(["run-bag", str(BAGS / "bench_transient.mcap"), "-o", str(out), "--health", item, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert ("--health" in err or "health_warn_pt" in err) and len(err.strip().splitlines()) == 1
    assert not out.exists()


def test_report_shows_health_and_alarms(wear_run, tmp_path, monkeypatch):
    """Behaviour: the report of the wear run has the two health plots; the efficiency plot carries the
    estimate with its ±2σ band and the WARN and ERROR intervals the monitor logged, in that order, each
    labelled with the fault named; beside them the fault timeline lists those alarms with the fault and
    probability the health log's alarm records name."""
    from gerotor_twin.offline.health_log import alarm_intervals, load_health
    from gerotor_twin.report import build
    from gerotor_twin.report.acceptance import AcceptanceCriterion
    from gerotor_twin.report.build import build_report, make_context
    from gerotor_twin.report.health_panels import fault_timeline, ts_health_efficiency, ts_health_leakage
    from gerotor_twin.twin.health import alarm_records, fault_text
    loaded = []                          # the recordings as the report read them (read once: the twin log is long)

    def load(*args):
        loaded.append(real_load(*args))
        return loaded[-1]
    real_load = build._load
    monkeypatch.setattr(build, "_load", load)
    html = tmp_path / "wear.html"
    build_report(BAGS / "bench_wear.mcap", [wear_run], html)
    page = html.read_text()
    assert '<div class="ts-panel" id="ts-health-efficiency"></div>' in page
    assert '<div class="ts-panel" id="ts-health-leakage"></div>' in page
    assert len(loaded) == 1
    ctx = make_context(*loaded[0], AcceptanceCriterion(), "wear")
    eff, leak = ts_health_efficiency(ctx), ts_health_leakage(ctx)
    t, rows = load_health(wear_run)
    logged, records = alarm_intervals(t, rows), alarm_records(t, rows)
    assert [r["fault"] for r in records] and all(r["fault"] in ("tip_wear", "lateral_wear") for r in records)
    labels = [f"{r['level']}: {fault_text(r['fault'], r['confidence'], r['rival'])}" for r in records]
    assert [iv.label for iv in eff.intervals] == labels == [iv.label for iv in leak.intervals]
    assert [r["level"] for r in records] == ["WARN", "ERROR"]
    timeline = fault_timeline(ctx)
    assert "id='tab-fault-timeline'" in page and timeline.heading == eff.heading
    assert [(r[0], r[3]) for r in timeline.rows] == [(r["level"], fault_text(r["fault"], None, r["rival"]))
                                                     for r in records]
    assert [r[4] for r in timeline.rows] == pytest.approx([r["confidence"] for r in records])
    assert [iv.t0 for iv in eff.intervals] == pytest.approx([a[1] for a in logged], abs=0.1)     # health_log counts from the first flow input
    est, band = eff.traces[0], eff.bands[0]
    assert np.all(band.lo <= est.y) and np.all(est.y <= band.hi) and np.any(band.hi > band.lo)
