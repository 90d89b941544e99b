"""Health monitoring over the shipped bags with run-bag (the node's core): wear detection, tracking, no false alarm.

The twin runs the config calibrated on bags/bench_map.mcap (bags/pump_fitted_bench_map.yaml).
Truth comes from the emulated pump itself (short-bearing model, emulator numerics) at the
set-point and clearance factor of each instant: k_true = its flow loss / the twin's.
"""
import json
import math
from pathlib import Path

import numpy as np
import pytest

from gerotor_twin.bench_emulator import BenchSpec, get_profile
from gerotor_twin.bench_emulator.emulator import EMULATOR_METADATA, emulated_config, wear_factor
from gerotor_twin.config import load_config
from gerotor_twin.io import open_mcap, read_topics
from gerotor_twin.io.reader import multiarray_series
from gerotor_twin.model.clearance_scale import scale_clearances
from gerotor_twin.model.pump import PumpModel
from gerotor_twin.model.steady import run_steady
from gerotor_twin.offline.run_bag import run_bag
from gerotor_twin.twin.health import HEALTH_FIELDS, HEALTH_STATUS, HealthSettings

BAGS = Path(__file__).resolve().parent.parent / "bags"
FITTED = BAGS / "pump_fitted_bench_map.yaml"
WARN_DELAY_S = 6.0      #: stated in README: WARN at most this long after the emulated loss crosses warn_pt


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


@pytest.fixture(scope="module")
def wear_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("health") / "wear_twin.mcap"
    run_bag(BAGS / "bench_wear.mcap", out, config_path=FITTED, progress=None)
    return out


@pytest.fixture(scope="module")
def emulated():
    """The emulated pump of the wear bag, its spec and profile (from the bag's metadata)."""
    meta = open_mcap(BAGS / "bench_wear.mcap").metadata[EMULATOR_METADATA]
    spec = BenchSpec(**json.loads(meta["spec"]))
    cfg = emulated_config(load_config(), spec.clearance_factor)
    return spec, get_profile(meta["profile"]), cfg, PumpModel(cfg, spec.bearing)


def _loss(model, rpm, bar):
    r = run_steady(model, rpm, bar)
    return r.theoretical_flow_m3s - r.mean_delivery_flow_m3s, r.theoretical_flow_m3s


def test_wear_warn_after_crossing(wear_run, emulated):
    """Behaviour (known truth): WARN comes at most WARN_DELAY_S after the emulated pump's efficiency at the
    reference point has fallen warn_pt below its healthy (calibrated) value, and not before it; ERROR
    likewise after error_pt."""
    spec, prof, cfg, emu = emulated
    hs = HealthSettings()

    def drop_pt(t):
        scale_clearances(emu, cfg, wear_factor(spec, t, prof.duration_s) / spec.clearance_factor)
        loss, qth = _loss(emu, hs.reference_rpm, hs.reference_bar)
        return 100 * loss / qth
    base = drop_pt(0.0)
    ts = np.linspace(0.0, prof.duration_s, 17)       # the loss is smooth in t (linear wear): 4 s steps
    drops = np.array([drop_pt(t) for t in ts]) - base
    t_warn_true = float(np.interp(hs.warn_pt, drops, ts))
    t_err_true = float(np.interp(hs.error_pt, drops, ts))
    _, rows, t_abs = _health(wear_run)
    t_rel = t_abs - 1_735_689_600.0            # the emulator's fixed start (2025-01-01T00:00:00Z)
    t_warn = next(t for t, r in zip(t_rel, rows) if r["level"] in (1, 2))
    t_err = next(t for t, r in zip(t_rel, rows) if r["level"] == 2)
    print(f"\nemulated loss crosses {hs.warn_pt} pt at {t_warn_true:.1f} s, WARN at {t_warn:.1f} s; "
          f"{hs.error_pt} pt at {t_err_true:.1f} s, ERROR at {t_err:.1f} s")
    assert t_warn_true - 1.0 <= t_warn <= t_warn_true + WARN_DELAY_S
    assert t_err_true - 1.0 <= t_err <= t_err_true + WARN_DELAY_S
    levels = _health_statuses(wear_run)
    assert levels[-1] == 2 and 1 in levels


def test_wear_estimate_follows_emulated_factor(wear_run, emulated):
    """Golden (known truth): every update's leakage factor is within 2 reported standard deviations of the
    emulated pump's (its flow loss over the twin's at the set-point of that instant)."""
    spec, prof, cfg, emu = emulated
    twin = PumpModel(load_config(FITTED), "mobility")
    _, rows, t_abs = _health(wear_run)
    twin_loss = {}
    z = []
    for t, r in zip(t_abs - 1_735_689_600.0, rows):
        w, p = prof.setpoints([t])
        rpm, bar = w[0] * 30 / math.pi, p[0] / 1e5
        scale_clearances(emu, cfg, wear_factor(spec, t, prof.duration_s) / spec.clearance_factor)
        key = (round(rpm, 3), round(bar, 4))
        if key not in twin_loss:
            twin_loss[key] = _loss(twin, rpm, bar)[0]
        k_true = _loss(emu, rpm, bar)[0] / twin_loss[key]
        z.append((r["leakage_factor"] - k_true) / r["leakage_factor_sd"])
    print(f"\n{len(z)} updates, max |k - k_true| / sd = {np.abs(z).max():.2f}")
    assert len(z) >= 30
    assert np.all(np.abs(z) <= 2.0)


def test_no_false_alarm_on_healthy_bag(tmp_path):
    """Behaviour: on the healthy transient bag the health status never leaves OK (after learning)."""
    out = tmp_path / "tr.mcap"
    run_bag(BAGS / "bench_transient.mcap", out, config_path=FITTED, progress=None)
    _, rows, _ = _health(out)
    assert len(rows) >= 5
    assert {r["level"] for r in rows} <= {0.0, 3.0}
    assert set(_health_statuses(out)) <= {0, 3}
    assert max(abs(r["leakage_factor"] - 1) for r in rows) < 0.05


def test_health_command_lists_alarm_intervals(wear_run, tmp_path, capsys):
    """Behaviour: `gerotor-twin health` prints the updates and the WARN then ERROR intervals, JSON alike."""
    from gerotor_twin.cli import main
    js = tmp_path / "h.json"
    assert main(["health", str(wear_run), "--every", "10", "--json", str(js)]) == 0
    out = capsys.readouterr().out
    assert "WARN from" in out and "ERROR from" in out
    alarms = json.loads(js.read_text())["alarms"]
    assert [a[0] for a in alarms] == ["WARN", "ERROR"] and alarms[0][2] < alarms[1][1]


@pytest.mark.parametrize("item", ["bogus=1", "adapt=maybe", "warn_pt=x", "warn_pt=-3"])
def test_run_bag_bad_health_setting(tmp_path, capsys, item):
    """Bad input: a bad --health item is one line naming the setting; nothing is written."""
    from gerotor_twin.cli import main
    out = tmp_path / "o.mcap"
    assert main(["run-bag", str(BAGS / "bench_transient.mcap"), "-o", str(out), "--health", item, "--quiet"]) == 2
    err = capsys.readouterr().err
    assert ("--health" in err or "health_warn_pt" in err) and len(err.strip().splitlines()) == 1
    assert not out.exists()
