"""A reset sends sim time back: the node publishes the backward /clock (and /tf) at once.

docs/sim_time.md says what tf2 listeners and RViz do with it; they can only act on a /clock
that actually goes back, so that is what is pinned here (over DDS, in-process).
"""

from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_srvs.srv import SetBool, Trigger
from test_node import Harness, context  # noqa: F401 (the fixture)


def _seconds(stamp) -> float:
    return stamp.sec + stamp.nanosec * 1e-9


def test_reset_publishes_the_backward_clock(context):  # noqa: F811
    h = Harness(context, "free_tumble", real_time_factor=0.0)
    try:
        clocks = []
        # a best-effort subscriber, as rclpy's TimeSource and tf2 listeners' nodes use
        h.client.create_subscription(
            Clock,
            "/clock",
            lambda m: clocks.append(_seconds(m.clock)),
            QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT),
        )
        assert h.spin_until(lambda: clocks and clocks[-1] > 0.5)
        assert h.call(SetBool, "pause", SetBool.Request(data=True)).success  # so that t = 0 is the last /clock
        before = h.node.run.sim.clock.t
        assert before > 0.5
        count = len(clocks)
        assert h.call(Trigger, "reset", Trigger.Request()).success
        # the reset itself publishes /clock at t = 0 (paused: nothing after it)
        assert h.spin_until(lambda: 0.0 in clocks[count:], timeout=10.0)
        assert max(clocks[:count]) > 0.5 and clocks[-1] == 0.0
    finally:
        h.close()
