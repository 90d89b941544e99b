"""Launch twin_node with config/twin.yaml (needs a full ROS 2 Jazzy install with `launch_ros`).

Untested in this repository's CI (no launch wheels on PyPI); kept minimal:
    ros2 launch gerotor_twin twin.launch.py [params_file:=/path/twin.yaml] [use_sim_time:=true]
"""
import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def generate_launch_description():
    default_params = os.path.join(get_package_share_directory("gerotor_twin"), "config", "twin.yaml")
    return LaunchDescription([
        DeclareLaunchArgument("params_file", default_value=default_params),
        DeclareLaunchArgument("use_sim_time", default_value="false"),
        Node(package="gerotor_twin", executable="twin_node", name="twin_node", output="screen",
             parameters=[LaunchConfiguration("params_file"),
                         {"use_sim_time": LaunchConfiguration("use_sim_time")}]),
    ])
