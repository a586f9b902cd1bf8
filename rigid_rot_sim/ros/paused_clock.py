"""``/clock`` while the run is paused: the frozen sim time, at the clock's rate in wall time.

The run publishes ``/clock`` at its steps (``rates.clock``, Hz of sim time); a paused run takes
no step, so without this a ``use_sim_time`` node started during a pause would have no time at
all (its clock reads 0 until the first message). Gazebo keeps publishing the frozen time while
paused; so does this node: a steady-clock timer at ``rates.clock`` Hz of wall time (at most
:data:`MAX_RATE`) publishes ``sim.clock.t`` while the simulator is paused, nothing while it runs. These
messages carry no new time, so the recording does not hold them (they go to the publisher only).
"""

from __future__ import annotations

from typing import Any

from rclpy.callback_groups import MutuallyExclusiveCallbackGroup
from rclpy.clock import Clock as SteadyClock
from rclpy.clock_type import ClockType
from rclpy.node import Node

from rigid_rot_sim import conversions
from rigid_rot_sim.run.simulator import Simulator

#: Most /clock messages per second of wall time while paused: the time is frozen, so ten a second serve a
#: late ``use_sim_time`` node as well as a thousand would, and a paused node stays near idle (a 50 Hz timer
#: cost a paused node ~4 % of a core here).
MAX_RATE = 10.0


class PausedClock:
    """The timer of ``node`` that republishes the frozen time on ``publisher`` (the /clock output) while paused."""

    def __init__(self, node: Node, sim: Simulator, publisher: Any, rate: float) -> None:
        self.sim = sim
        self.publisher = publisher
        period = 1.0 / min(rate, MAX_RATE)
        # a group of its own: the tick reads one float and needs neither the run lock of the node's default
        # group nor a wake-up of the run loop after it (ros/run_loop.py)
        self.timer = node.create_timer(
            period,
            self.tick,
            callback_group=MutuallyExclusiveCallbackGroup(),
            clock=SteadyClock(clock_type=ClockType.STEADY_TIME),
        )

    def tick(self) -> None:
        if self.sim.paused:
            self.publisher.publish(conversions.clock_message(self.sim.clock.t))
        else:
            # playing: no tick until the run is paused again (the run loop re-arms it then:
            # SceneRun._paused_clock_follows). Cancelled here, on the executor's thread, never from the run
            # loop's: rclpy raises when an executor calls a timer cancelled after it found it ready.
            self.timer.cancel()


def start(node: Node, sim: Simulator, publishers: dict[str, Any], rates: dict[str, float]) -> PausedClock | None:
    """The paused clock of a node whose /clock output is built (None without one)."""
    if "clock" not in publishers or not rates.get("clock", 0.0) > 0.0:
        return None
    return PausedClock(node, sim, publishers["clock"], rates["clock"])
