"""launch/twin.launch.py with stand-ins for ``launch``/``launch_ros`` (not on PyPI) (behaviour).

The stand-ins record what the launch file builds: the declared arguments must be
exactly the node's parameters (plus ``params_file`` and ``use_sim_time``), each
with a description; arguments left at their default must not override the
params file, given ones must arrive typed; a bad value stops the launch naming it.
"""
from __future__ import annotations

import importlib.util
import sys
import types
from pathlib import Path

import pytest
import yaml

from gerotor_twin.ros.params import PARAMETERS

ROOT = Path(__file__).resolve().parent.parent


class _Rec:
    def __init__(self, *args, **kwargs):
        self.args, self.kwargs = args, kwargs


class Configuration:
    def __init__(self, name):
        self.name = name

    def perform(self, context):
        return context.launch_configurations[self.name]


class Context:
    def __init__(self, declared, given):
        self.launch_configurations = {a.args[0]: a.kwargs["default_value"] for a in declared}
        self.launch_configurations.update(given)


@pytest.fixture
def launch_file(monkeypatch):
    mods = {name: types.ModuleType(name) for name in
            ("launch", "launch.actions", "launch.substitutions", "launch_ros", "launch_ros.actions",
             "ament_index_python", "ament_index_python.packages")}
    mods["launch"].LaunchDescription = lambda entities: list(entities)
    mods["launch.actions"].DeclareLaunchArgument = type("DeclareLaunchArgument", (_Rec,), {})
    mods["launch.actions"].OpaqueFunction = type("OpaqueFunction", (_Rec,), {})
    mods["launch.substitutions"].LaunchConfiguration = Configuration
    mods["launch_ros.actions"].Node = type("Node", (_Rec,), {})
    mods["ament_index_python.packages"].get_package_share_directory = lambda pkg: f"/opt/share/{pkg}"
    for name, mod in mods.items():
        monkeypatch.setitem(sys.modules, name, mod)
    spec = importlib.util.spec_from_file_location("twin_launch", ROOT / "launch" / "twin.launch.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    entities = module.generate_launch_description()
    declared = [e for e in entities if type(e).__name__ == "DeclareLaunchArgument"]
    (opaque,) = [e for e in entities if type(e).__name__ == "OpaqueFunction"]

    def run(**given):
        (node,) = opaque.kwargs["function"](Context(declared, given))
        return node.kwargs["parameters"]
    return declared, run


def test_every_node_parameter_is_a_described_launch_argument(launch_file):
    declared, _ = launch_file
    names = [a.args[0] for a in declared]
    assert len(names) == len(set(names))
    assert set(names) == {p.name for p in PARAMETERS} | {"params_file", "use_sim_time"}
    by_name = {a.args[0]: a.kwargs for a in declared}
    for p in PARAMETERS:
        assert by_name[p.name]["description"].startswith(p.description)
    assert by_name["params_file"]["default_value"] == "/opt/share/gerotor_twin/config/twin.yaml"


def test_defaults_keep_params_file_and_given_values_are_typed(launch_file):
    _, run = launch_file
    params_file, overrides, sim = run()
    assert params_file == "/opt/share/gerotor_twin/config/twin.yaml"
    assert overrides == {} and sim == {"use_sim_time": False}
    _, overrides, sim = run(bearing_model="fdm", log_dir="/x", tick_rate_hz="200", log_queue="500",
                            log_waveforms="False", suction_pressure_topic="", use_sim_time="true")
    assert overrides == {"bearing_model": "fdm", "log_dir": "/x", "tick_rate_hz": 200.0, "log_queue": 500,
                         "log_waveforms": False, "suction_pressure_topic": ""}
    assert type(overrides["tick_rate_hz"]) is float and type(overrides["log_queue"]) is int
    assert sim == {"use_sim_time": True}


def test_bad_value_names_the_argument(launch_file):
    _, run = launch_file
    with pytest.raises(ValueError, match=r"tick_rate_hz:='fast' is invalid; allowed: a number in \[1, 1000\]"):
        run(tick_rate_hz="fast")
    with pytest.raises(ValueError, match=r"log_fsync:='yes' is invalid; allowed: true \| false"):
        run(log_fsync="yes")


def test_packaged_params_log_outside_the_workspace():
    """twin.yaml's log_dir is under ~/.ros, not a relative path (colcon's log/ in a workspace)."""
    prm = yaml.safe_load((ROOT / "config" / "twin.yaml").read_text())["/**"]["ros__parameters"]
    assert prm["log_dir"].startswith("~/.ros/")
    assert set(prm) <= {p.name for p in PARAMETERS}
