"""Session-wide DDS isolation for every test that touches ROS (in-process or subprocess).

One ROS_DOMAIN_ID per pytest session (from the pid, locked, and probed for other nodes, so
parallel sessions differ) and localhost-only discovery, set in ``os.environ`` when pytest
imports this file, before any test calls ``rclpy.init`` or starts a subprocess.
"""

import fcntl
import os
import tempfile

PROBE_SECONDS = 1.0  # s of listening for other ROS nodes on a candidate domain


def _domain_is_quiet(domain: int) -> bool:
    """No other ROS node on ``domain`` (localhost): no /rosout publisher besides the probe's own."""
    import time

    import rclpy

    context = rclpy.Context()
    rclpy.init(context=context, domain_id=domain)
    try:
        node = rclpy.create_node("rigid_rot_sim_domain_probe", context=context)
        deadline = time.monotonic() + PROBE_SECONDS
        while time.monotonic() < deadline:
            if node.count_publishers("/rosout") > 1:
                return False
            time.sleep(0.05)
        node.destroy_node()
        return True
    finally:
        rclpy.try_shutdown(context=context)


def _claim_domain_id() -> int:
    """A domain id that no other test session on the machine uses.

    Several developers' suites run at once on a shared machine; two in one domain would see
    each other's nodes. A lock file per domain keeps this project's sessions apart; a short
    probe skips a domain where other ROS nodes already run (sessions that take no lock). The
    lock is released when this process exits.
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
        if not _domain_is_quiet(domain):
            handle.close()
            continue
        _DOMAIN_LOCKS.append(handle)  # held for the whole session
        return domain
    return start + 1  # all taken: share one (as before)


_DOMAIN_LOCKS: list = []
os.environ["ROS_AUTOMATIC_DISCOVERY_RANGE"] = "LOCALHOST"  # before the probe: it listens on localhost only
ROS_DOMAIN_ID = _claim_domain_id()
os.environ["ROS_DOMAIN_ID"] = str(ROS_DOMAIN_ID)
# A second domain of this session for the in-process node tests (test/ros/test_node.py's context):
# they ask the graph for the node by name, and a node of an e2e test in this session's domain (a
# subprocess just stopped, whose participant the graph still lists) has that name too.
os.environ["RIGID_ROT_SIM_IN_PROCESS_DOMAIN_ID"] = str(_claim_domain_id())
os.environ.setdefault("ROS_LOG_DIR", tempfile.mkdtemp(prefix="rigid_rot_ros_log_"))
os.environ["PYTHONUNBUFFERED"] = "1"  # a subprocess's prints reach its log even if it is killed


def pytest_collection_modifyitems(config, items):
    """Every test under test/e2e/ is marked ``e2e`` (setup.cfg registers the markers)."""
    import pytest

    for item in items:
        if "e2e" in item.path.parent.parts:
            item.add_marker(pytest.mark.e2e)
