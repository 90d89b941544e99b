"""Sweeps on a real Dask cluster on loopback (issue 15): same results as in-process, a worker killed mid-run.

Tier: behaviour.  ``dask scheduler`` + two ``dask worker`` processes (no nanny) on 127.0.0.1,
started and stopped by PID by :mod:`dask_cluster`; the sweep runs as a separate
``gerotor-twin sweep --scheduler`` process.  The workers get a private, empty table cache so that
each geometry point costs a table build (about 1-3 s): long enough to kill a worker while it
computes.  Same results: compared bit-for-bit with the in-process evaluation of every point.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from dask_cluster import loopback_cluster, stop
from gerotor_twin.offline.sweep_point import evaluate_point
from gerotor_twin.offline.sweep_spec import parse_spec
from test_sweep import COMPARED, TINY

pytestmark = pytest.mark.slow

CLI = str(Path(sys.executable).parent / "gerotor-twin")
KILL_STUDY = {
    "title": "kill study", "model": "fixed", "revolutions": 6,
    "set": {"numerics.table_points": 512, "numerics.max_step_deg": 4.0},
    "operating": {"speed_rpm": 1500, "delivery_bar": 10},
    "parameters": {"gears.lobe_radius_m": [8.6e-3, 8.8e-3, 9.2e-3, 9.4e-3, 9.6e-3, 9.8e-3]},
}


def _write(path: Path, body: dict) -> Path:
    path.write_text(yaml.safe_dump(body, sort_keys=False))
    return path


def _lines(path: Path) -> list[dict]:
    return [json.loads(x) for x in path.read_text().splitlines()] if path.exists() else []


def _in_process(body: dict) -> dict:
    spec = parse_spec(dict(body))
    return {p["id"]: {k: v for k, v in evaluate_point(spec.task(), p).items() if k in COMPARED}
            for p in spec.points()}


@pytest.fixture(scope="module")
def cluster(tmp_path_factory):
    tmp = tmp_path_factory.mktemp("cluster")
    cache = tmp / "cache"
    with loopback_cluster(tmp, 2, env={"GEROTOR_TWIN_CACHE": str(cache)}) as (address, workers):
        yield address, workers, cache


def _sweep(spec: Path, out: Path, address: str, *extra) -> subprocess.Popen:
    return subprocess.Popen([CLI, "sweep", str(spec), "-o", str(out), "--scheduler", address, *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def test_cluster_gives_the_in_process_results_bit_for_bit(tmp_path, cluster):
    """Behaviour: the tiny study on the loopback cluster equals its in-process evaluation (hence the local one)."""
    address, _, _ = cluster
    proc = _sweep(_write(tmp_path / "s.yaml", TINY), tmp_path / "r", address)
    try:
        out, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 0, err
    assert "on 2 worker(s)" in out
    recs = _lines(tmp_path / "r" / "points.jsonl")
    assert {r["id"]: {k: r[k] for k in COMPARED} for r in recs} == _in_process(TINY)
    assert {r["worker"] for r in recs if r["status"] == "ok"} <= set(_worker_addresses(address))


def test_cheap_points_share_tasks_with_the_same_results(tmp_path, cluster):
    """Behaviour: 32 operating points on 2 workers go 2 per task (chunk_size); every point once, equal to
    in-process bit-for-bit."""
    from gerotor_twin.offline.engine import chunk_size
    body = {"title": "operating map", "model": "fixed", "revolutions": 6, "set": TINY["set"],
            "parameters": {"operating.speed_rpm": [600, 1000, 1400, 1800, 2200, 2600, 2800, 3000],
                           "operating.delivery_bar": [2, 9, 16, 23]}}
    assert chunk_size(32, 2) == 2 and chunk_size(15, 2) == 1 and chunk_size(10**6, 2) == 32
    address, _, _ = cluster
    proc = _sweep(_write(tmp_path / "op.yaml", body), tmp_path / "r", address, "--quiet")
    try:
        _, err = proc.communicate(timeout=120)
    finally:
        stop(proc)
    assert proc.returncode == 0, err
    recs = _lines(tmp_path / "r" / "points.jsonl")
    assert sorted(r["id"] for r in recs) == [f"p{i:06d}" for i in range(32)]
    assert {r["id"]: {k: r[k] for k in COMPARED} for r in recs} == _in_process(body)


def _worker_addresses(address: str) -> dict:
    from distributed import Client
    with Client(address, timeout=10) as c:
        return {a: w["name"] for a, w in c.scheduler_info()["workers"].items()}


def _kill_a_busy_worker(address: str, workers: dict, points: Path, proc: subprocess.Popen, timeout: float = 90):
    """Once a point is stored, SIGKILL a worker that is computing one; return (its address, the keys it had)."""
    from distributed import Client
    t0 = time.monotonic()
    with Client(address, timeout=10) as c:
        while time.monotonic() - t0 < timeout and proc.poll() is None:
            if _lines(points):
                busy = {a: keys for a, keys in c.processing().items() if keys}
                info = c.scheduler_info()["workers"]
                if busy:
                    addr, keys = next(iter(busy.items()))
                    os.kill(workers[info[addr]["name"]].pid, signal.SIGKILL)
                    return addr, [str(k) for k in keys]
            time.sleep(0.05)
    raise AssertionError("the sweep finished (or timed out) before a worker could be killed while computing")


def test_a_worker_killed_mid_run_loses_no_point_and_duplicates_none(tmp_path, cluster, monkeypatch):
    """Behaviour: SIGKILL one of two workers while it computes; every point ends up exactly once in the
    results, the killed worker's points recomputed by the survivor, values equal to in-process."""
    address, workers, cache = cluster
    out = tmp_path / "r"
    proc = _sweep(_write(tmp_path / "k.yaml", KILL_STUDY), out, address)
    try:
        killed, keys = _kill_a_busy_worker(address, workers, out / "points.jsonl", proc)
        stored_at_kill = len(_lines(out / "points.jsonl"))
        _, err = proc.communicate(timeout=180)
    finally:
        stop(proc)
    assert proc.returncode == 0, err
    recs = _lines(out / "points.jsonl")
    ids = [r["id"] for r in recs]
    assert len(ids) == len(set(ids)) == len(KILL_STUDY["parameters"]["gears.lobe_radius_m"])
    assert stored_at_kill < len(ids)
    assert all(r["status"] == "ok" for r in recs), [r["reason"] for r in recs]
    lost = [k.rsplit("-", 1)[1] for k in keys]
    assert lost and all(next(r for r in recs if r["id"] == i)["worker"] != killed for i in lost)
    monkeypatch.setenv("GEROTOR_TWIN_CACHE", str(cache))  # the workers' tables (bit-identical when reloaded)
    assert {r["id"]: {k: r[k] for k in COMPARED} for r in recs} == _in_process(KILL_STUDY)
