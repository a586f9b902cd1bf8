"""Session-wide DDS isolation for every test that touches ROS (in-process or subprocess).

One ROS_DOMAIN_ID per pytest session (from the pid, and locked, so parallel sessions differ) and
localhost-only discovery, set in ``os.environ`` when pytest imports this file, before any
test calls ``rclpy.init`` or starts a subprocess.
"""

import fcntl
import os
import tempfile


def _claim_domain_id() -> int:
    """A domain id no other test session of this project on the machine holds (a lock file each).

    Several developers' suites run at once on a shared machine; two in one domain would see
    each other's nodes. The lock is released when this process exits.
    """
    start = os.getpid() % 100
    for offset in range(100):
        domain = (start + offset) % 100 + 1  # 1..100: clear of the default 0, below the 101 port limit
        handle = open(os.path.join(tempfile.gettempdir(), f"rigid_rot_sim_ros_domain_{domain}.lock"), "w")
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError:
            handle.close()
            continue
        _DOMAIN_LOCKS.append(handle)  # held for the whole session
        return domain
    return start + 1  # all taken: share one (as before)


_DOMAIN_LOCKS: list = []
ROS_DOMAIN_ID = _claim_domain_id()
os.environ["ROS_DOMAIN_ID"] = str(ROS_DOMAIN_ID)
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"
os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="rigid_rot_ros_log_"))
os.environ["PYTHONUNBUFFERED"] = "1"  # a subprocess's prints reach its log even if it is killed
