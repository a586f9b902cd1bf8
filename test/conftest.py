"""Session-wide DDS isolation for every test that touches ROS (in-process or subprocess).

One ROS_DOMAIN_ID per pytest session (from the pid, so parallel sessions differ) and
localhost-only discovery, set in ``os.environ`` when pytest imports this file, before any
test calls ``rclpy.init`` or starts a subprocess.
"""

import os
import tempfile

ROS_DOMAIN_ID = os.getpid() % 100 + 1  # 1..100: clear of the default 0, below the 101 port limit
os.environ["ROS_DOMAIN_ID"] = str(ROS_DOMAIN_ID)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="rigid_rot_ros_log_"))
os.environ["PYTHONUNBUFFERED"] = "1"  # a subprocess's prints reach its log even if it is killed
