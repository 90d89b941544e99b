"""Launch twin_node with config/twin.yaml; every node parameter can be set as a launch argument.

    ros2 launch gerotor_twin twin.launch.py                      # packaged config/twin.yaml
    ros2 launch gerotor_twin twin.launch.py bearing_model:=fdm log_dir:=/data/twin
    ros2 launch gerotor_twin twin.launch.py params_file:=/path/twin.yaml use_sim_time:=true
    ros2 launch gerotor_twin twin.launch.py --show-args          # all arguments with descriptions

One launch argument per parameter of :data:`gerotor_twin.ros.params.PARAMETERS`
(description with unit and range); an argument left at its default
``(params_file)`` keeps the value of ``params_file``, a given one overrides it
(converted to the parameter's type; a value that does not convert stops the
launch with a message naming the argument).  The packaged params file logs to
``~/.ros/gerotor_twin`` (not the colcon workspace's ``log/``).
Needs a full ROS 2 Jazzy install (``launch``, ``launch_ros``);
test/test_launch.py checks the arguments with stand-ins for those packages.
"""
import os
from types import SimpleNamespace

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from gerotor_twin.ros.params import PARAMETERS

#: Default of a parameter argument: keep the params file's value.
KEEP = "(params_file)"


def _typed(p, text: str):
    """A launch argument's text as the parameter's type (bool, int, float or str)."""
    if isinstance(p.default, bool):
        if text.lower() not in ("true", "false"):
            raise ValueError(f"launch argument {p.name}:={text!r} is invalid; allowed: true | false")
        return text.lower() == "true"
    try:
        if isinstance(p.default, int):
            return int(text)
        if isinstance(p.default, float):
            return float(text)
    except ValueError:
        kind = "an integer" if isinstance(p.default, int) else "a number"
        raise ValueError(f"launch argument {p.name}:={text!r} is invalid; allowed: {kind}"
                         + (f" in [{p.lo:g}, {p.hi:g}]" if p.lo is not None else "")) from None
    return text


def _describe(p) -> str:
    text = p.description
    if p.choices:
        text += " (one of: " + ", ".join(p.choices) + ")"
    elif p.lo is not None:
        text += f" (range {p.lo:g} .. {p.hi:g})"
    return text + f"; node default {p.default!r}"


def _node(context, *args, **kwargs):
    overrides = {}
    for p in PARAMETERS:
        text = LaunchConfiguration(p.name).perform(context)
        if text != KEEP:
            overrides[p.name] = _typed(p, text)
    sim = _typed(_SIM, LaunchConfiguration("use_sim_time").perform(context))
    return [Node(package="gerotor_twin", executable="twin_node", name="twin_node", output="screen",
                 parameters=[LaunchConfiguration("params_file").perform(context), overrides,
                             {"use_sim_time": sim}])]


_SIM = SimpleNamespace(name="use_sim_time", default=False, lo=None, hi=None)


def generate_launch_description():
    default_params = os.path.join(get_package_share_directory("gerotor_twin"), "config", "twin.yaml")
    args = [DeclareLaunchArgument("params_file", default_value=default_params,
                                  description="YAML file with twin_node's ros__parameters"),
            DeclareLaunchArgument("use_sim_time", default_value="false",
                                  description="follow /clock (replay, simulation): true | false")]
    args += [DeclareLaunchArgument(p.name, default_value=KEEP, description=_describe(p)) for p in PARAMETERS]
    return LaunchDescription([*args, OpaqueFunction(function=_node)])
