"""The B-dot detumble controller as an outside ROS node: ``python -m rigid_rot_sim.ros.detumble_controller``.

It closes the magnetic loop around the simulation node of a scene with torque rods and a magnetometer
(``cubesat_detumble``): it subscribes to the node's ``~/magnetometer`` (sensor_msgs/MagneticField, T, body axes)
and answers each reading with the rods' dipoles on ``~/magnetorquer_command`` (sensor_msgs/JointState, ``effort``
in A*m^2 by rod name), **stamped with the reading's stamp**, as ``rigid-rot-controller`` answers states: in
lockstep (``lockstep.inputs: ["~/magnetorquer_command"]``, period = the magnetometer's) each turn waits for that
answer, so the closed loop repeats bit for bit.

Each sample is answered once. A reading published before this node was matched (the node's first, at start-up) is
lost to it, so it also listens to the node's ``~/state`` (a lockstep turn output, sent again while a turn waits):
a state whose sample falls before the settle sample of a cycle is answered at once with the rods off, which is
what the law commands there whatever the reading (its difference starts afresh at the settle sample), so either
path gives the same bits.

The law is :func:`rigid_rot_sim.core.magnetic_control.bdot_step` (duty-cycled B-dot: ``sensing`` of every
``cycle`` readings with the rods off, the difference across them, the dipole held for the rest), the sample index
the reading's stamp times the magnetometer's ``rate`` (so a lost reading shifts nothing), the body dipole split on
the rods by :func:`rigid_rot_sim.core.magnetorquer.allocate` (scaled, never turned, to the limits).

Parameters: ``gain`` (A*m^2*s/T), ``rate`` (Hz, the magnetometer's), ``cycle``, ``sensing``, ``rod_names``,
``rod_axes`` (3 per rod, body frame), ``max_dipoles`` (A*m^2), ``magnetometer_topic``, ``state_topic``,
``command_topic``; the defaults are ``cubesat_detumble``'s.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.node import Node
from sensor_msgs.msg import JointState, MagneticField

from rigid_rot_msgs.msg import RigidBodyState
from rigid_rot_sim.core import magnetic_control, magnetorquer
from rigid_rot_sim.ros.controller import CONTROL_QOS, run_node
from rigid_rot_sim.run.detumble import BDOT_GAIN

NODE_NAME = "detumble_controller"


class DetumbleController(Node):
    """Answers each ``~/magnetometer`` reading with the rods' B-dot dipoles, stamped with the reading's stamp."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)

        def declare(name: str, value: Any, text: str) -> Any:
            return self.declare_parameter(name, value, ParameterDescriptor(description=text)).value

        gain = float(declare("gain", BDOT_GAIN, "B-dot gain k, A*m^2*s/T"))
        rate = float(declare("rate", 10.0, "The magnetometer's rate, Hz of sim time"))
        cycle = int(declare("cycle", 10, "Readings per control cycle"))
        sensing = int(declare("sensing", 4, "Readings at the start of each cycle with the rods off (0: always on)"))
        names = list(declare("rod_names", ["mtq_x", "mtq_y", "mtq_z"], "The rods' names (JointState names)"))
        axes = list(declare("rod_axes", [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0], "3 per rod, body frame"))
        limits = list(declare("max_dipoles", [0.2, 0.2, 0.2], "Each rod's limit, A*m^2"))
        magnetometer_topic = declare("magnetometer_topic", "/rigid_rot_sim/magnetometer", "The node's magnetometer")
        state_topic = declare("state_topic", "/rigid_rot_sim/state", "The node's state (answered before settling)")
        command_topic = declare("command_topic", "/rigid_rot_sim/magnetorquer_command", "The node's rod commands")
        if not (rate > 0.0 and math.isfinite(rate)) or len(axes) != 3 * len(names):
            raise ValueError(f"need rate > 0 and 3 rod_axes per rod name, got rate {rate}, {len(axes)} for {names}")
        self.rods = magnetorquer.Magnetorquers(np.reshape(axes, (-1, 3)).T, np.array(limits, dtype=float), tuple(names))
        self.schedule = magnetic_control.BDotSchedule(gain, 1.0 / rate, cycle, sensing)
        self.state = magnetic_control.BDotState.initial()
        self.answered = -1  # the last sample answered
        self.publisher = self.create_publisher(JointState, command_topic, CONTROL_QOS)
        self.subscription = self.create_subscription(
            MagneticField, magnetometer_topic, self.reading_callback, CONTROL_QOS
        )
        self.state_subscription = self.create_subscription(
            RigidBodyState, state_topic, self.state_callback, CONTROL_QOS
        )
        self.get_logger().info(
            f"B-dot: {magnetometer_topic} -> {command_topic}, k {gain:g} A*m^2*s/T, rods off {sensing} of every "
            f"{cycle} readings at {rate:g} Hz, rods {list(names)}"
        )

    def reading_callback(self, msg: MagneticField) -> None:
        field = msg.magnetic_field
        self._answer(msg.header.stamp, (field.x, field.y, field.z))

    def state_callback(self, msg: RigidBodyState) -> None:
        schedule = self.schedule
        index = self._index(msg.header.stamp)
        if schedule.sensing_samples and index % schedule.cycle_samples < schedule.settle_samples:
            self._answer(msg.header.stamp, (0.0, 0.0, 0.0))  # the law ignores the reading there

    def _index(self, stamp: Any) -> int:
        return round((stamp.sec + 1e-9 * stamp.nanosec) / self.schedule.sample_period)

    def _answer(self, stamp: Any, b: tuple[float, float, float]) -> None:
        index = self._index(stamp)
        if index <= self.answered:
            return
        self.answered = index
        self.state, m_body = magnetic_control.bdot_step(self.schedule, self.state, index, b)
        command = JointState()
        command.header.stamp = stamp  # the stamp of the sample answered: the lockstep contract
        command.name = list(self.rods.names)
        command.effort = magnetorquer.allocate(self.rods.axes, m_body, self.rods.max_dipoles).tolist()
        self.publisher.publish(command)


def main(args: list[str] | None = None) -> int:
    """Run the controller until Ctrl-C / SIGTERM (exit 0); a bad parameter: one line on stderr, exit 2."""
    return run_node(DetumbleController, NODE_NAME, args)


if __name__ == "__main__":
    raise SystemExit(main())
