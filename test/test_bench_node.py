"""``gerotor-twin bench node`` bookkeeping without starting a node (behaviour tier)."""
from __future__ import annotations

import pytest

from gerotor_twin.cli import main
from gerotor_twin.ros.bench_node import median_row


def _row(cpu, p99, logged, lost, skips=0):
    return {"rpm": 3000, "repeat": 0, "node_cpu_fraction": cpu, "core_rtf": 4.0, "node_rtf": 1.6,
            "latency_p50_ms": 5.0, "latency_p99_ms": p99, "skips": skips, "published": logged + lost,
            "logged": logged, "lost": lost, "unaccounted": 0,
            "thread_cpu_fraction": {"executor": 0.1, "model": cpu - 0.2, "dds": 0.05, "other": 0.05}}


def test_median_row_takes_medians_of_rates_and_sums_of_counts():
    rows = [_row(0.64, 10.5, 19000, 0), _row(0.56, 7.8, 18990, 10, skips=None), _row(0.60, 8.8, 19000, 0, 2)]
    m = median_row(rows)
    assert m["repeat"] == "median" and m["runs"] == 3 and m["rpm"] == 3000
    assert m["node_cpu_fraction"] == 0.60 and m["latency_p99_ms"] == 8.8
    assert (m["published"], m["logged"], m["lost"], m["skips"], m["unaccounted"]) == (57000, 56990, 10, 2, 0)
    assert m["thread_cpu_fraction"]["model"] == pytest.approx(0.40)


@pytest.mark.parametrize("value", ["0", "101"])
def test_node_repeats_out_of_range_is_refused_with_one_line(value, capsys):
    assert main(["bench", "node", "--node-repeats", value]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--node-repeats" in err and value in err and "1 to 100" in err
