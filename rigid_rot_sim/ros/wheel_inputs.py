"""What the node receives for its reaction wheels: ``~/wheel_torque`` (rigid_rot_msgs/WheelTorques).

Built only for a scene with ``actuators.reaction_wheels``. A message carries one motor torque
(N*m) per wheel in the scene's order; it takes effect at its header stamp when that is
non-zero and not in the past, else on receipt. A value beyond a wheel's max_torque is clamped
and said once per wheel (a warning, and the recorded event on ``~/sim_events``); a wrong number
of values or a non-finite one is rejected with the reason on ``~/rejected``.
"""

from __future__ import annotations

import math
import time
from typing import Any

from rclpy.qos import QoSProfile

from rigid_rot_msgs.msg import WheelTorques
from rigid_rot_sim import conversions
from rigid_rot_sim.ros.inputs import Rejections
from rigid_rot_sim.ros.intake import CommandIntake
from rigid_rot_sim.ros.qos import COMMAND_QOS
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import Scene

#: The topic of the wheel commands.
WHEEL_TORQUE_TOPIC = "~/wheel_torque"


class WheelTorqueInput:
    """The ``~/wheel_torque`` subscription of a scene with wheels (:attr:`subscriptions` is empty otherwise)."""

    def __init__(self, intake: CommandIntake, sim: Simulator, scene: Scene, depth: int, rejections: Rejections) -> None:
        node = intake.node
        self.sim = sim
        self.rejections = rejections
        self.logger = node.get_logger()
        self.listeners: list[Any] = []
        self.subscriptions: list[Any] = []
        self._clamped_said: set[int] = set()
        self.spacecraft = scene.spacecraft
        self.names = scene.spacecraft.wheel_names
        self.topic = node.resolve_topic_name(WHEEL_TORQUE_TOPIC)
        if self.names:
            qos = QoSProfile(depth=depth, reliability=COMMAND_QOS.reliability, durability=COMMAND_QOS.durability)
            self.subscriptions.append(intake.subscribe(WheelTorques, WHEEL_TORQUE_TOPIC, self.callback, qos))

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line: (what was built, what was left out and why).

        Wheels, their schedule, gravity gradient.
        """
        built: list[str] = []
        left_out: list[str] = []
        if self.names:
            built.append(
                f"{len(self.names)} reaction wheel(s) [{', '.join(self.names)}]: commands on {self.topic} "
                f"(WheelTorques, N*m), speeds on ~/wheels"
            )
        else:
            left_out.append("reaction wheels (none in the scene)")
        if self.spacecraft.wheel_schedule is not None:
            built.append(f"a wheel-torque schedule of {len(self.spacecraft.wheel_schedule.segments)} segment(s)")
        gg = self.spacecraft.gravity_gradient
        if gg is not None and gg.kepler is not None:
            k = gg.kepler
            built.append(
                f"gravity gradient (the scene's orbit: a {k.a:g} m, e {k.e:g}, i {math.degrees(k.i):g} deg, "
                f"J2 {'on' if k.j2 else 'off'})"
            )
        elif gg is not None:
            built.append(
                f"gravity gradient (circular orbit, radius {gg.radius:g} m, inclination {gg.inclination:g} rad)"
            )
        return built, left_out

    def callback(self, msg: Any, received_ns: int | None = None) -> None:
        """A wheel command (from the run loop's intake, in arrival order): to the simulator, or rejected."""
        received_ns = time.time_ns() if received_ns is None else received_ns
        torques, stamp = conversions.wheel_torques_from_msg(msg)
        try:
            effective = stamp if stamp > 0.0 and stamp >= self.sim.clock.t else None
            _, _, clamped = self.sim.submit_wheel_torques(self.topic, torques, effective)
            for i in clamped:
                if i not in self._clamped_said:
                    self._clamped_said.add(i)
                    self.logger.warning(
                        f"{self.topic}: wheel {self.names[i]!r} command clamped to its max_torque "
                        "(said once per wheel; every clamp is in the recorded events)"
                    )
        except CommandRejected as exc:
            self.rejections.reject(self.topic, exc.reason, msg.header.frame_id, (0.0, 0.0, 0.0))
        except Exception as exc:  # never out of a callback: rejected with the reason
            self.rejections.reject(self.topic, f"internal error: {exc!r}", msg.header.frame_id, (0.0, 0.0, 0.0))
        for listener in self.listeners:
            listener.received(self.topic, msg, received_ns)
