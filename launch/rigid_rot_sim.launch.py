"""Launch the rigid_rot_sim node on a scene (for a ROS 2 install: ``launch`` is not on PyPI).

    ros2 launch rigid_rot_sim rigid_rot_sim.launch.py scene:=heavy_top
    ros2 launch rigid_rot_sim rigid_rot_sim.launch.py scene:=/path/to/my_scene.yaml namespace:=sat1 \
        params_file:=/path/to/params.yaml remappings:="/tf:=tf /tf_static:=tf_static"

Arguments
---------
scene        a shipped scene's name (found in the package's share directory) or a path
params_file  a ROS 2 parameters file (keys under ``rigid_rot_sim:`` or ``/**:``); its values win
             over the scene's and over ``scene`` / ``record_path`` given here
namespace    push the node, its topics and services into a namespace (e.g. ``sat1``)
node_name    the node's name (default rigid_rot_sim)
remappings   space-separated ``FROM:=TO`` pairs, e.g. ``/tf:=tf`` to keep /tf per namespace
record_path  an MCAP file to record the run to (default: none)

Neither the package nor its tests import this file (launch is not importable in the PyPI
venv); the test suite compiles it and checks its arguments.
"""

from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from launch import LaunchDescription

ARGUMENTS = {
    "scene": ("free_tumble", "a shipped scene's name or a scene YAML path"),
    "params_file": ("", "a ROS 2 parameters file; empty for none"),
    "namespace": ("", "namespace of the node, its topics and services"),
    "node_name": ("rigid_rot_sim", "name of the node"),
    "remappings": ("", "space-separated FROM:=TO topic remappings"),
    "record_path": ("", "MCAP file to record the run to; empty for none"),
}


def _remappings(text: str) -> list[tuple[str, str]]:
    pairs = []
    for item in text.split():
        source, separator, target = item.partition(":=")
        if not (source and separator and target):
            raise ValueError(f"remappings: {item!r} is not FROM:=TO")
        pairs.append((source, target))
    return pairs


def _node(context):
    value = {name: LaunchConfiguration(name).perform(context) for name in ARGUMENTS}
    parameters = [{"scene": value["scene"]}]
    if value["record_path"]:
        parameters[0]["record_path"] = value["record_path"]
    if value["params_file"]:
        parameters.append(value["params_file"])  # applied after the values above: it wins
    return [
        Node(
            package="rigid_rot_sim",
            executable="rigid_rot_sim_node",
            name=value["node_name"],
            namespace=value["namespace"],
            parameters=parameters,
            remappings=_remappings(value["remappings"]),
            output="screen",
        )
    ]


def generate_launch_description() -> LaunchDescription:
    return LaunchDescription(
        [
            DeclareLaunchArgument(name, default_value=default, description=text)
            for name, (default, text) in ARGUMENTS.items()
        ]
        + [OpaqueFunction(function=_node)]
    )
