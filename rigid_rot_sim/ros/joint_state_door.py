"""The reaction wheels' JointState door, for ros2_control's topic hardware interface (docs/ros2_control.md).

Built when the ``joint_state_topics.commands`` / ``joint_state_topics.states`` parameters (read-only;
the scene's ``joint_state_topics`` section gives their defaults) name topics, in a scene with
``actuators.reaction_wheels``:

* **commands** (sensor_msgs/JointState in): the motor torque of each named wheel in ``effort`` (N*m),
  under the rule of :mod:`rigid_rot_sim.run.joint_commands` (any subset of the wheels, in any order;
  held until the next command for that wheel, no timeout; velocity or position only, unknown names,
  mismatched lengths, non-finite values rejected on ``~/rejected`` with the reason; beyond max_torque
  clamped and said once per wheel, as on ``~/wheel_torque``). The subscription is reliable and
  volatile, keep-last ``commands.qos_depth``: it matches the interface's ``QoS(1)`` publisher (reliable,
  volatile) and loses no command of a burst. A command takes effect at its header stamp when that is
  non-zero and not in the past, else on receipt (the interface stamps with its node's clock, the sim
  time under ``use_sim_time``, so on receipt; a stamp more than a minute ahead, wall time without
  ``use_sim_time``, is rejected with that reason); it goes to the simulator as a wheel command from the
  commands topic (the name as given), recorded with the run and replayed by ``rigid-rot resim``.
  In lockstep, listing the commands topic (as given) in ``lockstep.inputs`` makes it a turn input:
  each turn waits for one command stamped with the turn's time, as for a torque topic.
* **states** (sensor_msgs/JointState out): what ``~/wheels`` publishes, at the same steps (``rates.wheels``,
  sim-time stamps): position = wheel angle (rad, relative to the body, unwrapped), velocity = speed
  relative to the body (rad/s), effort = the motor torque acting (N*m). Reliable, volatile, depth 10:
  it matches the interface's ``SensorDataQoS`` (best-effort) subscriber and reliable ones alike.

How it hooks into the node (a wire, no physics): :class:`JointStateDoor` is built beside
:class:`~rigid_rot_sim.ros.wheel_inputs.WheelTorqueInput`; ``subscriptions`` go to the recording like
the wheel topic's, ``listeners`` receive every command message as received (the recording; the
run loop's intake wakes a lockstep turn), and the door is an observer of the run driver
(:meth:`outputs_due`) for the states.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState

from rigid_rot_sim import conversions
from rigid_rot_sim.ros.inputs import Rejections
from rigid_rot_sim.ros.intake import CommandIntake
from rigid_rot_sim.run.joint_commands import effective_time, merged_torques, wheel_efforts
from rigid_rot_sim.run.observables import StateSnapshot
from rigid_rot_sim.run.observer import SimulationObserver
from rigid_rot_sim.run.simulator import CommandRejected, Simulator
from rigid_rot_sim.scene.scene import Scene

#: QoS of the states publisher: reliable (matches best-effort SensorDataQoS subscribers too), volatile.
STATES_QOS = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)


class JointStateDoor(SimulationObserver):
    """The commands subscription and the states publisher of a scene with wheels (either may be absent)."""

    def __init__(
        self,
        intake: CommandIntake,
        sim: Simulator,
        scene: Scene,
        topics: tuple[str, str],
        wheels_rate: float,
        depth: int,
        rejections: Rejections,
    ) -> None:
        """``topics``: (commands, states), empty for none; ``wheels_rate``: rates.wheels (Hz of sim time).

        The commands subscription is the run loop's (``intake``): taken in arrival order with every other
        command topic, losses counted and reported (:mod:`rigid_rot_sim.ros.intake`)."""
        node = intake.node
        commands, states = topics
        self.sim = sim
        self.rejections = rejections
        self.logger = node.get_logger()
        self.names = scene.spacecraft.wheel_names
        self.body_frame = scene.frames.body
        self.listeners: list[Any] = []
        self.subscriptions: list[Any] = []
        self.publisher: Any = None
        self.source = commands  # the name as given: the command source, as lockstep.inputs lists it
        self.commands_topic = self.states_topic = ""
        self._clamped_said: set[int] = set()
        if (commands or states) and not self.names:
            raise ValueError("joint_state_topics: the scene has no reaction wheels (actuators.reaction_wheels)")
        if states and not wheels_rate > 0.0:
            raise ValueError("joint_state_topics.states needs rates.wheels > 0: the states are published at its steps")
        if commands:
            qos = QoSProfile(depth=depth, reliability=ReliabilityPolicy.RELIABLE, durability=DurabilityPolicy.VOLATILE)
            self.subscriptions.append(intake.subscribe(JointState, commands, self.callback, qos))
            self.commands_topic = self.subscriptions[0].topic_name
        if states:
            self.publisher = node.create_publisher(JointState, states, STATES_QOS)
            self.states_topic = self.publisher.topic_name

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line: (what was built, what was left out and why)."""
        if not self.names:
            return [], []
        if not (self.subscriptions or self.publisher):
            return [], ["JointState door (joint_state_topics not set)"]
        parts = [f"commands on {self.commands_topic} (effort, N*m)"] if self.subscriptions else []
        parts += [f"states on {self.states_topic} (at rates.wheels)"] if self.publisher else []
        return [f"JointState door for ros2_control: {', '.join(parts)}"], []

    # ------------------------------------------------------------------ commands

    def callback(self, msg: Any, received_ns: int | None = None) -> None:
        """A JointState command (from the run loop's intake, in arrival order): to the simulator, or rejected."""
        received_ns = time.time_ns() if received_ns is None else received_ns
        try:
            self._command(msg)
        except CommandRejected as exc:
            self.rejections.reject(self.commands_topic, exc.reason, msg.header.frame_id, (0.0, 0.0, 0.0))
        except Exception as exc:  # never out of a callback: rejected with the reason
            self.rejections.reject(
                self.commands_topic, f"internal error: {exc!r}", msg.header.frame_id, (0.0, 0.0, 0.0)
            )
        for listener in self.listeners:
            listener.received(self.commands_topic, msg, received_ns)

    def _command(self, msg: Any) -> None:
        names, position, velocity, effort, stamp = conversions.joint_command_from_msg(msg)
        efforts = wheel_efforts(self.source, self.names, names, position, velocity, effort)
        sim = self.sim
        effective = effective_time(self.source, stamp, sim.clock.t)
        sim.command_gate(self.source, stamp if stamp > 0.0 else None)  # lockstep: a turn input, or it passes
        torques = merged_torques(sim.commands.wheel_torques, efforts)
        _, _, clamped = sim.submit_wheel_torques(self.source, torques, effective)
        for i in clamped:
            if i not in self._clamped_said and i in efforts:
                self._clamped_said.add(i)
                self.logger.warning(
                    f"{self.commands_topic}: wheel {self.names[i]!r} effort clamped to its max_torque "
                    "(said once per wheel; every clamp is in the recorded events)"
                )

    # ------------------------------------------------------------------ states

    def outputs_due(self, step: int, snapshot: StateSnapshot, names: Sequence[str]) -> None:
        """With ``~/wheels`` due: the same JointState on the states topic."""
        if self.publisher is not None and "wheels" in names:
            self.publisher.publish(conversions.snapshot_to_joint_state(snapshot, self.body_frame))
