"""The node's lockstep wiring: read-only ``lockstep.*`` parameters, the turn engine, the wake-up.

The turns themselves (state machine, stamp matching, timeout decision) are
:class:`rigid_rot_sim.run.lockstep.Lockstep`, without ROS. Here:

* :func:`declare_lockstep_parameters`: ``lockstep.period`` (s; 0 = off), ``lockstep.inputs``,
  ``lockstep.timeout`` (s of wall time), ``lockstep.on_timeout`` (pause | hold), read-only,
  the scene's ``lockstep`` section as defaults; :func:`lockstep_from_parameters` checks them
  as the scene loader does;
* :class:`NodeLockstep`: builds the turns and gates the simulator's commands through them. The
  run loop (:mod:`.run_loop`) waits on the command topics themselves: the turn that takes the last
  answer of a lockstep turn steps on at once, so a turn costs one DDS round trip, not a timer
  period. Nothing waits in a callback.
"""

from __future__ import annotations

from typing import Any

from rcl_interfaces.msg import FloatingPointRange, ParameterDescriptor
from rclpy.node import Node

from rigid_rot_sim.core import limits
from rigid_rot_sim.ros.parameters import JOINT_STATE_COMMANDS
from rigid_rot_sim.run.lockstep import TURN_OUTPUTS, Lockstep
from rigid_rot_sim.run.pacing import RunDriver
from rigid_rot_sim.scene.scene import LockstepSpec, Scene, lockstep_spec
from rigid_rot_sim.scene.scene_schema import LOCKSTEP_ON_TIMEOUT

#: name -> (description, read from the scene); the block to move into the parameter table.
LOCKSTEP_PARAMETERS = {
    "lockstep.period": "Lockstep: s of sim time between controller turns, a whole number of steps; 0 = off",
    "lockstep.inputs": "Lockstep: the torque topic inputs (or joint_state_topics.commands) waited for at every turn",
    "lockstep.timeout": "Lockstep: s of wall time to wait for a turn's commands",
    "lockstep.on_timeout": "Lockstep: pause | hold, what a turn that timed out does",
}


def declare_lockstep_parameters(node: Node, scene: Scene) -> None:
    """Declare the read-only ``lockstep.*`` parameters, the scene's section (or off) as defaults."""
    spec = scene.lockstep
    topics = [t.topic for t in scene.topic_inputs] or ["~/torque"]
    defaults = {
        "lockstep.period": spec.period if spec else 0.0,
        "lockstep.inputs": list(spec.inputs) if spec else topics,
        "lockstep.timeout": spec.timeout if spec else LockstepSpec.timeout,
        "lockstep.on_timeout": spec.on_timeout if spec else LockstepSpec.on_timeout,
    }
    ranges = {"lockstep.period": (0.0, limits.DURATION_RANGE[1]), "lockstep.timeout": (1e-3, limits.DURATION_RANGE[1])}
    for name, description in LOCKSTEP_PARAMETERS.items():
        extra: dict[str, Any] = {}
        if name in ranges:
            extra["floating_point_range"] = [FloatingPointRange(from_value=ranges[name][0], to_value=ranges[name][1])]
        if name == "lockstep.on_timeout":
            extra["additional_constraints"] = " | ".join(LOCKSTEP_ON_TIMEOUT)
        descriptor = ParameterDescriptor(description=description, read_only=True, **extra)
        node.declare_parameter(name, defaults[name], descriptor)


def lockstep_from_parameters(node: Node, scene: Scene, dt: float) -> LockstepSpec | None:
    """The lockstep the parameters ask for (None: off); ValueError as the scene loader words it."""
    value = lambda name: node.get_parameter(name).value  # noqa: E731
    period = float(value("lockstep.period"))
    if period <= 0.0:
        return None
    on_timeout = value("lockstep.on_timeout")
    if on_timeout not in LOCKSTEP_ON_TIMEOUT:
        raise ValueError(f"lockstep.on_timeout must be one of {', '.join(LOCKSTEP_ON_TIMEOUT)}, got {on_timeout!r}")
    section = {
        "period": period,
        "inputs": list(value("lockstep.inputs")),
        "timeout": float(value("lockstep.timeout")),
        "on_timeout": on_timeout,
    }
    commands = value(JOINT_STATE_COMMANDS.name)  # the wheels' JointState door may be a turn input too
    return lockstep_spec(section, scene.topic_inputs, dt, (commands,) if commands else ())


class NodeLockstep:
    """Lockstep turns for the node's ``run``: the gate and the turn outputs' periods."""

    def __init__(self, node: Node, spec: LockstepSpec, run: RunDriver) -> None:
        sim = run.sim
        self.run = run
        self.turns = Lockstep(spec, sim, clock=run.clock)
        n = self.turns.period_steps
        built = [name for name in TURN_OUTPUTS if name in run.schedule.periods]
        if not built:
            raise ValueError("lockstep needs a state output (rates.state, rates.orientation, ... > 0) to answer")
        for name in built:  # the state outputs: exactly once per turn, at t_k
            run.schedule.periods[name] = n
        self.turn_outputs = built
        sim.add_observer(self.turns)
        sim.command_gate = self.turns.admit

    def describe(self) -> str:
        spec = self.turns.spec
        return (
            f"LOCKSTEP on: a turn every {spec.period:g} s of sim time ({self.turns.period_steps} steps), "
            f"waits for {', '.join(spec.inputs)} (commands stamped t_k), timeout {spec.timeout:g} s -> "
            f"{spec.on_timeout}; {', '.join(self.turn_outputs)} once per turn"
        )


__all__ = [
    "LOCKSTEP_PARAMETERS",
    "NodeLockstep",
    "declare_lockstep_parameters",
    "lockstep_from_parameters",
]
