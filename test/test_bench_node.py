"""``gerotor-twin bench node`` bookkeeping without starting a node (behaviour tier)."""
from __future__ import annotations

import pytest

from gerotor_twin.cli import main
from gerotor_twin.ros.bench_node import median_row


def _row(cpu, p99, logged, lost, skips=0, startup_rtf=3.0):
    return {"rpm": 3000, "repeat": 0, "node_cpu_fraction": cpu, "startup_rtf": startup_rtf, "core_rtf": 4.0,
            "node_rtf": 1.6,
            "latency_p50_ms": 5.0, "latency_p99_ms": p99, "skips": skips, "published": logged + lost,
            "logged": logged, "lost": lost, "unaccounted": 0,
            "thread_cpu_fraction": {"executor": 0.1, "model": cpu - 0.2, "dds": 0.05, "other": 0.05}}


def test_median_row_takes_medians_of_rates_and_sums_of_counts():
    rows = [_row(0.64, 10.5, 19000, 0, startup_rtf=2.5), _row(0.56, 7.8, 18990, 10, skips=None),
            _row(0.60, 8.8, 19000, 0, 2, startup_rtf=3.5)]
    m = median_row(rows)
    assert m["repeat"] == "median" and m["runs"] == 3 and m["rpm"] == 3000
    assert m["node_cpu_fraction"] == 0.60 and m["latency_p99_ms"] == 8.8 and m["startup_rtf"] == 3.0
    assert (m["published"], m["logged"], m["lost"], m["skips"], m["unaccounted"]) == (57000, 56990, 10, 2, 0)
    assert m["thread_cpu_fraction"]["model"] == pytest.approx(0.40)


@pytest.mark.parametrize("value", ["0", "101"])
def test_node_repeats_out_of_range_is_refused_with_one_line(value, capsys):
    assert main(["bench", "node", "--node-repeats", value]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "--node-repeats" in err and value in err and "1 to 100" in err


def _family_yaml(tmp_path, rpm=4500.0, bar=25.0):
    from pathlib import Path
    text = (Path(__file__).resolve().parent.parent / "config" / "pump.yaml").read_text()
    text = text.replace("max_speed_rpm: 3000.0", f"max_speed_rpm: {rpm}")
    text = text.replace("max_delivery_bar: 27.5", f"max_delivery_bar: {bar}")
    f = tmp_path / "family.yaml"
    f.write_text(text)
    return f


def _plan(*argv):
    from gerotor_twin.cli import build_parser
    from gerotor_twin.ros.bench_node import plan
    return plan(build_parser().parse_args(["bench", "node", *argv]))


def test_config_is_the_nodes_pump_at_its_top_speed_and_pressure(tmp_path):
    """--config F: pump_config:=F (absolute) for the node, speeds and pressure from F's range by default."""
    f = _family_yaml(tmp_path)
    p = _plan("--config", str(f), "--node-param", "tick_rate_hz:=100.0")
    assert p["rpms"] == (4500,) and p["bar"] == 25.0
    assert p["params"] == (f"pump_config:={f.resolve()}", "tick_rate_hz:=100.0")
    given = _plan("--config", str(f), "--node-rpms", "1000,4500", "--bar", "10")
    assert given["rpms"] == (1000, 4500) and given["bar"] == 10.0


def test_without_config_the_packaged_pump_and_no_pump_config():
    p = _plan()
    assert p["rpms"] == (3000,) and p["bar"] == 27.5 and p["config"] is None
    assert not any(q.startswith("pump_config") for q in p["params"])


@pytest.mark.parametrize("argv,needle", [(("--node-rpms", "5000"), "--node-rpms"), (("--bar", "30"), "--bar")])
def test_speed_or_pressure_beyond_the_pumps_range_refused(tmp_path, capsys, argv, needle):
    f = _family_yaml(tmp_path)
    assert main(["bench", "node", "--config", str(f), *argv]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and needle in err and "the pump's range" in err
