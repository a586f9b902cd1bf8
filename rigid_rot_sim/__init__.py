"""rigid_rot_sim: a ROS 2 rigid-body rotation simulator with a pure numerical core."""

__version__ = "0.1.0"
