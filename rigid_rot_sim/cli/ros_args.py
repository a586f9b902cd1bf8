"""``--ros-args`` for every subcommand that creates a ROS node, as ``ros2 run`` accepts it.

Everything after ``--ros-args`` goes to ROS unchanged (``-r old:=new``, ``-r __ns:=/ns``,
``-p name:=value``, ``--params-file FILE``, ``--log-level``), so a tool can be remapped
or put in a namespace like any ROS executable.
"""

from __future__ import annotations

import argparse


def add_ros_args(parser: argparse.ArgumentParser) -> None:
    """Accept ``--ros-args ...`` as the last option of ``parser``."""
    parser.add_argument(
        "--ros-args",
        nargs=argparse.REMAINDER,
        dest="ros_args",
        metavar="ARG",
        help="everything after it goes to ROS as with ros2 run (e.g. -r __ns:=/robot, -p name:=value)",
    )


def rclpy_args(args: argparse.Namespace, program: str = "rigid-rot") -> list[str]:
    """The argv for ``rclpy.init(args=...)``: the program name, then ``--ros-args ...`` if given."""
    ros_args = getattr(args, "ros_args", None)
    return [program] if ros_args is None else [program, "--ros-args", *ros_args]
