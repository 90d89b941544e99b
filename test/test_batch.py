"""Fleet batch runs (issue 15): run-bag + report per recording on Dask, resumable, fleet summary.

Tier: behaviour.  Small synthetic bench recordings (bench emulator, 2 x 4 s plateaus each,
fixed-centre emulated pump) and one corrupt file; the batch runs on the embedded cluster and on a
loopback ``dask scheduler`` + 2 ``dask worker`` processes (stopped by PID).  A fleet row must carry
the figures of the ``report`` command run by hand on the same files, bit-for-bit.
"""
from __future__ import annotations

import csv
import json
from pathlib import Path

import pytest

from dask_cluster import loopback_cluster
from gerotor_twin.cli import main

METRICS = ("status", "date_utc", "duration_s", "speed_range_rpm", "delivery_range_bar", "plateaus",
           "flow_bias_m3s", "flow_rmse_m3s", "eta_bias", "eta_rmse")


def _bag(path: Path, i: int, rpm: float, bar: float) -> None:
    from gerotor_twin.bench_emulator import BenchSpec, Profile, Segment, synthesize
    synthesize(Profile(f"fleet{i}", (Segment(4.0, rpm, bar), Segment(4.0, rpm + 400, bar + 5))), path,
               BenchSpec(bearing="fixed", seed=100 + i), progress=None)


@pytest.fixture(scope="module")
def bags(tmp_path_factory):
    d = tmp_path_factory.mktemp("bags")
    for i, (rpm, bar) in enumerate(((1200, 8), (2000, 12))):
        _bag(d / f"bench_{i}.mcap", i, rpm, bar)
    (d / "corrupt.mcap").write_bytes(b"not an mcap file at all")
    return d


@pytest.fixture(scope="module")
def local_fleet(bags, tmp_path_factory):
    out = tmp_path_factory.mktemp("fleet") / "local"
    assert main(["batch", str(bags), "-o", str(out), "--model", "fixed", "--workers", "2", "--quiet"]) == 0
    return out


def _rows(out: Path) -> dict:
    return {r["name"].rsplit("-", 1)[0]: r for r in json.loads((out / "fleet.json").read_text())["recordings"]}


@pytest.mark.slow
def test_fleet_rows_are_the_reports_figures(local_fleet, bags, tmp_path):
    """Behaviour: one row per recording; a good row carries what `run-bag` + `report` by hand give;
    the corrupt file is a failed row with its reason; CSV and HTML hold the same rows."""
    rows = _rows(local_fleet)
    assert sorted(rows) == ["bench_0", "bench_1", "corrupt"]
    assert rows["corrupt"]["status"] == "failed" and "not an MCAP file" in rows["corrupt"]["reason"]
    r = rows["bench_1"]
    assert r["status"] == "ok" and r["plateaus"] == 2 and 7.5 < r["duration_s"] < 8.5
    assert 1990 < r["speed_range_rpm"][0] < 2010 and 2390 < r["speed_range_rpm"][1] < 2410
    twin = tmp_path / "twin.mcap"
    assert main(["run-bag", str(bags / "bench_1.mcap"), "-o", str(twin), "--model", "fixed", "--quiet"]) == 0
    assert main(["report", "--bench", str(bags / "bench_1.mcap"), "--twin", str(twin), "-o",
                 str(tmp_path / "r.html"), "--json", str(tmp_path / "r.json")]) == 0
    o = json.loads((tmp_path / "r.json").read_text())["twins"][0]["overall"]
    assert (r["flow_bias_m3s"], r["flow_rmse_m3s"]) == (o["flow_error_m3s"]["bias"], o["flow_error_m3s"]["rmse"])
    assert (r["eta_bias"], r["eta_rmse"]) == (o["eta_error"]["bias"], o["eta_error"]["rmse"])
    with open(local_fleet / "fleet.csv") as fh:
        table = list(csv.DictReader(fh))
    assert [t["status"] for t in table] == ["ok", "ok", "failed"]
    assert float(table[1]["flow_bias_m3s"]) == r["flow_bias_m3s"]
    page = (local_fleet / "fleet.html").read_text()
    assert page.count("<tr>") == 4 and 'id="fig-fleet-errors"' in page
    assert f"href='bags/{r['name']}/report.html'" in page
    assert Path(r["report"]).is_file() and Path(r["twin"]).is_file()


def test_bad_arguments_are_one_line(tmp_path, bags, capsys):
    """Behaviour: no recording, an unknown model: one line each, exit 2."""
    cases = [(["batch", str(tmp_path / "nothing*.mcap"), "-o", str(tmp_path / "o")],
              "BAG_DIR_OR_GLOB = "),
             (["batch", str(bags), "-o", str(tmp_path / "o"), "--model", "rigid"], "--model = 'rigid' is invalid")]
    for argv, needle in cases:
        assert main(argv) == 2
        err = capsys.readouterr().err.strip()
        assert err.startswith("error: ") and "\n" not in err and needle in err, err
    assert not (tmp_path / "o").exists()


def test_fleet_rows_carry_health(local_fleet):
    """Behaviour: a good row carries the health monitor's last state of its twin log (level, k ± sd, the fault
    named) as `gerotor-twin health` reads it; CSV and HTML show it."""
    from gerotor_twin.offline.health_log import LEVELS, load_health
    from gerotor_twin.twin.diagnosis import KINDS
    r = _rows(local_fleet)["bench_1"]
    t, hist = load_health(r["twin"])
    h = r["health"]
    assert h["level"] == LEVELS[int(hist[-1]["level"])] and h["updates"] == len(hist)
    assert h["leakage_factor"] == hist[-1]["leakage_factor"] and h["leakage_factor_sd"] > 0
    with open(local_fleet / "fleet.csv") as fh:
        table = {row["name"].rsplit("-", 1)[0]: row for row in csv.DictReader(fh)}
    assert table["bench_1"]["health"] == h["level"]
    assert float(table["bench_1"]["health_leakage_factor"]) == h["leakage_factor"]
    assert f"<b>{h['level']}</b>: k = {h['leakage_factor']:.3f}" in (local_fleet / "fleet.html").read_text()
    assert h["fault"] == KINDS[int(hist[-1]["fault"])] and f"fault: {h['fault']}" in (local_fleet / "fleet.html").read_text()


@pytest.mark.slow
def test_fleet_calibrate_recovers_the_emulated_clearances(bags, tmp_path):
    """Golden (known truth): with --calibrate every good recording gets its fitted pump config, and the
    fitted clearance combination's 95 % interval holds the emulated pump's factor (BenchSpec default,
    same fixed-centre model as the twin); the corrupt file stays a failed row; a rerun without
    --calibrate into the same directory is refused."""
    from gerotor_twin.bench_emulator import BenchSpec
    from gerotor_twin.config import load_config
    out = tmp_path / "cal"
    tau = str(BenchSpec().temperature_tau_s)           # the emulated thermometer's lag, undone
    assert main(["batch", str(bags), "-o", str(out), "--model", "fixed", "--workers", "2", "--calibrate",
                 "--oil-sensor-tau", tau, "--quiet"]) == 0
    rows = _rows(out)
    assert rows["corrupt"]["status"] == "failed"
    truth = BenchSpec().clearance_factor
    for name in ("bench_0", "bench_1"):
        cal = rows[name]["calibration"]
        assert "error" not in cal, cal
        assert cal["note"] is None                    # the thermometer lag is undone: no note about it
        lo, hi = cal["combinations"][0]["factor_ci95"]
        assert lo <= truth <= hi, (name, cal)
        assert load_config(cal["config"]).calibration["bags"] == [rows[name]["bag"]]
    with open(out / "fleet.csv") as fh:
        assert all(row["fit_factor"] for row in csv.DictReader(fh) if row["status"] == "ok")
    assert "fitted clearance factor" in (out / "fleet.html").read_text()
    assert main(["batch", str(bags), "-o", str(out), "--model", "fixed", "--oil-sensor-tau", tau]) == 2


@pytest.mark.slow
def test_cluster_fleet_equals_local(local_fleet, bags, tmp_path):
    """Behaviour: the same fleet on a loopback dask scheduler + 2 workers gives the same rows."""
    out = tmp_path / "cluster"
    with loopback_cluster(tmp_path, 2) as (address, _):
        assert main(["batch", str(bags), "-o", str(out), "--model", "fixed", "--scheduler", address,
                     "--quiet"]) == 0
    got, ref = _rows(out), _rows(local_fleet)
    assert sorted(got) == sorted(ref)
    assert all(got[k][m] == ref[k][m] for k in got for m in METRICS if m in ref[k])


@pytest.mark.slow
def test_rerun_processes_only_new_recordings(local_fleet, bags, tmp_path, capsys):
    """Behaviour: a rerun on the same OUTDIR keeps what is done and runs only what is new (the same file
    reached through a link is the same recording); each recording once in the fleet.  Runs last: it adds
    to the module's fleet."""
    sel = tmp_path / "sel"
    sel.mkdir()
    for name in ("bench_0.mcap", "bench_1.mcap"):
        (sel / name).symlink_to(bags / name)
    _bag(sel / "bench_2.mcap", 2, 2500, 18)
    before = _rows(local_fleet)
    assert main(["batch", str(sel), "-o", str(local_fleet), "--model", "fixed", "--workers", "1"]) == 0
    assert "3 recordings, 3 reported, 0 failed (1 processed" in capsys.readouterr().out
    assert len((local_fleet / "bags.jsonl").read_text().splitlines()) == 4      # 3 before + the new one
    rows = _rows(local_fleet)
    assert sorted(rows) == ["bench_0", "bench_1", "bench_2"]
    assert all(rows[k] == before[k] for k in ("bench_0", "bench_1"))
    assert main(["batch", str(sel), "-o", str(local_fleet), "--model", "mobility"]) == 2
    assert "--model = 'mobility' is invalid; allowed: 'fixed'" in capsys.readouterr().err
