"""The fault classifier on short emulated bags, one per kind (behaviour tier).

Each bag: ``synth-bench`` of the default pump (clearance factor 1.0, against the twin of the same config) along the
four operating points of the ``diagnosis`` profile seen once, 2.5 s each (10 s), with one fault kind as a step from the
start at a severity that costs about 8 pt at the monitor's reference point (the bench's high severities on this
pump, docs/calibration_health.md, "Fault diagnosis"); then ``run-bag`` with the monitor's windows of 0.5 s after
0.5 s of settling (:func:`gerotor_twin.offline.diagnosis_bench.run_case`).  The full confusion tables over ramps,
steps, seeds and severities are the benchmark (``python -m gerotor_twin.offline.diagnosis_bench``), not a test.
"""
import math

import pytest
import yaml

from gerotor_twin.cli import main as cli_main
from gerotor_twin.config import load_config
from gerotor_twin.hydraulics.meter import lag_step
from gerotor_twin.offline.diagnosis_bench import health_args, run_case
from gerotor_twin.offline.health_log import load_health

#: kind → step severity (``--fault-to``): the default pump's high severities (8 pt at the reference point for the
#: flow kinds; −5 bar is the offset range's end, 6.8 pt)
STEPS = {"healthy": None, "tip_wear": 2.27, "lateral_wear": 1.096, "air_ingress": 0.0776,
         "pressure_offset": -5e5, "flowmeter_drift": -0.11, "speed_dropout": 0.3, "suction_restriction": 6e4}


@pytest.fixture(scope="module")
def short_profile(tmp_path_factory):
    """The diagnosis profile's four points once, 2.5 s each, oil 50 °C."""
    path = tmp_path_factory.mktemp("profile") / "diagnosis_once.yaml"
    points = ((1000, 5), (1000, 25), (2500, 25), (2500, 5))
    segments = [{"duration_s": 2.5, "rpm": rpm, "bar": bar} for rpm, bar in points]
    segments[0]["oil_temperature_c"] = 50.0
    path.write_text(yaml.safe_dump({"name": "diagnosis_once", "segments": segments}))
    return path


@pytest.mark.parametrize("kind", list(STEPS))
def test_short_bag_names_its_fault(kind, short_profile, tmp_path):
    """Behaviour: on a short bag with one fault from the start, the kind named at the last health update is that
    fault (healthy: no fault); the healthy bag, the suction restriction and the speed dropout (whose flow stays
    as predicted) raise no WARN or ERROR, and every flow fault raises one."""
    r = run_case(load_config(), kind, STEPS[kind], 3, tmp_path, 0.0, profile_file=str(short_profile))
    assert r["named"] == kind, (r["named"], r["confidence"], r["alarms"])
    flow_fault = kind not in ("healthy", "speed_dropout", "suction_restriction")
    assert bool(r["alarms"]) == flow_fault, r["alarms"]


def test_lag_step_closed_form():
    """Closed form: a first-order sensor after one time constant of a unit step reads 1 − 1/e; two half steps are
    one whole (the exact solution, not an Euler step); no lag (τ = 0) reads the input."""
    assert lag_step(0.0, 1.0, 0.2, 0.2) == pytest.approx(1.0 - math.exp(-1.0), rel=1e-15)
    assert lag_step(lag_step(0.0, 1.0, 0.1, 0.2), 1.0, 0.1, 0.2) == pytest.approx(lag_step(0.0, 1.0, 0.2, 0.2),
                                                                                   rel=1e-14)
    assert lag_step(3.0, 1.0, 0.5, 0.0) == 1.0


def test_meter_lag_read_alike_right_after_a_step(short_profile, tmp_path):
    """Behaviour: on a healthy bag whose flow meter lags 0.2 s (the emulator's default), windows counted right
    after each step (``settle_s`` = 0) see the meter still settling: the residuals carry part of the flow's step
    (0.4 L/min at seed 3); with the monitor told the meter's time constant (``flow_sensor_tau_s``) the model's
    flows are read through the same lag and the largest residual falls to the noise's size (below a third)."""
    run_case(load_config(), "healthy", None, 3, tmp_path, 0.0, profile_file=str(short_profile),
             health=health_args(settle_s=0.0, flow_sensor_tau_s=0.0))
    lagged = tmp_path / "healthy_3_lagged.mcap"          # the same bag, the monitor told the meter's lag
    assert cli_main(["run-bag", str(tmp_path / "healthy_3.mcap"), "-o", str(lagged), "--quiet",
                     *health_args(settle_s=0.0, flow_sensor_tau_s=0.2)]) == 0
    worst = []
    for twin in (tmp_path / "healthy_3_twin.mcap", lagged):
        _, rows = load_health(twin)
        worst.append(max(abs(float(row["residual_m3s"])) for row in rows))
    assert worst[1] < worst[0] / 3, worst
