"""Pure numerical core of rigid_rot_sim (numpy, scipy and numba; never imports rclpy).

Scene files are read with PyYAML (:mod:`.bounded_yaml`) and checked with jsonschema
(:mod:`.schema`, :mod:`.scene_schema`); nothing here needs ROS.

Conventions everywhere: SI units; quaternions scalar-last ``(x, y, z, w)`` rotating
body -> world (as ``scipy.spatial.transform.Rotation`` and geometry_msgs do);
angular velocity and torque in the body frame unless a name says ``_world``.
"""
