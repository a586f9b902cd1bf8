"""What the node receives for its torque rods: ``~/magnetorquer_command`` (sensor_msgs/JointState).

Built only for a scene with ``actuators.magnetorquers``. ``name`` names any subset of the rods, ``effort`` carries
their dipoles (A*m^2), under the wheels' JointState rule (:func:`rigid_rot_sim.run.joint_commands.joint_efforts`
with ``RODS``): a rod keeps its dipole until a command names it again (no timeout), the rods not named keep theirs.
A dipole beyond a rod's max_dipole is clamped and said once per rod (a warning, and the recorded event on
``~/sim_events``); an unknown name, mismatched lengths, velocity or position only or a non-finite value is
rejected as a whole with the reason on ``~/rejected``. The command takes effect at its header stamp when that is
non-zero and not in the past, else on receipt. ``lockstep.inputs`` may list ``~/magnetorquer_command``: each turn
then waits for one command stamped with the turn's time. Why JointState: it names each rod, needs no new
message, and is what ros2_control's topic hardware interface publishes for joints with an ``effort`` command
interface (docs/spacecraft.md).
"""

from __future__ import annotations

import time
from typing import Any

from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState

from rigid_rot_sim import conversions
from rigid_rot_sim.ros.inputs import Rejections
from rigid_rot_sim.ros.intake import CommandIntake
from rigid_rot_sim.ros.qos import COMMAND_QOS
from rigid_rot_sim.run.joint_commands import RODS, effective_time, joint_efforts, merged_torques
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import Scene
from rigid_rot_sim.scene.spacecraft import ROD_COMMAND_TOPIC


class RodCommandInput:
    """The ``~/magnetorquer_command`` subscription of a scene with rods (:attr:`subscriptions` is empty otherwise)."""

    def __init__(self, intake: CommandIntake, sim: Simulator, scene: Scene, depth: int, rejections: Rejections) -> None:
        node = intake.node
        self.sim = sim
        self.rejections = rejections
        self.logger = node.get_logger()
        self.listeners: list[Any] = []
        self.subscriptions: list[Any] = []
        self._clamped_said: set[int] = set()
        self.names = scene.spacecraft.rod_names
        self.topic = node.resolve_topic_name(ROD_COMMAND_TOPIC)
        if self.names:
            qos = QoSProfile(depth=depth, reliability=COMMAND_QOS.reliability, durability=COMMAND_QOS.durability)
            self.subscriptions.append(intake.subscribe(JointState, ROD_COMMAND_TOPIC, self.callback, qos))

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line: (what was built, what was left out and why)."""
        if not self.names:
            return [], []
        return [f"{len(self.names)} torque rod(s) [{', '.join(self.names)}]: dipoles on {self.topic} (JointState)"], []

    def callback(self, msg: Any, received_ns: int | None = None) -> None:
        """A rods' command (from the run loop's intake, in arrival order): to the simulator, or rejected."""
        received_ns = time.time_ns() if received_ns is None else received_ns
        try:
            names, position, velocity, effort, stamp = conversions.joint_command_from_msg(msg)
            efforts = joint_efforts(RODS, self.topic, self.names, names, position, velocity, effort)
            sim = self.sim
            effective = effective_time(self.topic, stamp, sim.clock.t)
            sim.command_gate(ROD_COMMAND_TOPIC, stamp if stamp > 0.0 else None)  # lockstep.inputs names it so
            dipoles = merged_torques(sim.commands.rod_dipoles, efforts)
            for i in sim.submit_rod_dipoles(self.topic, dipoles, effective)[2]:
                if i not in self._clamped_said and i in efforts:
                    self._clamped_said.add(i)
                    self.logger.warning(
                        f"{self.topic}: rod {self.names[i]!r} dipole clamped to its max_dipole "
                        "(said once per rod; every clamp is in the recorded events)"
                    )
        except CommandRejected as exc:
            self.rejections.reject(self.topic, exc.reason, msg.header.frame_id, (0.0, 0.0, 0.0))
        except Exception as exc:  # never out of a callback: rejected with the reason
            self.rejections.reject(self.topic, f"internal error: {exc!r}", msg.header.frame_id, (0.0, 0.0, 0.0))
        for listener in self.listeners:
            listener.received(self.topic, msg, received_ns)
