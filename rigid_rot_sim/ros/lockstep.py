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

from rclpy.node import Node

from rigid_rot_sim.ros import parameters as params
from rigid_rot_sim.run.lockstep import TURN_OUTPUTS, Lockstep
from rigid_rot_sim.run.pacing import RunDriver
from rigid_rot_sim.scene.scene import LockstepSpec, Scene, lockstep_spec
from rigid_rot_sim.scene.spacecraft import ROD_COMMAND_TOPIC

#: The ``lockstep.*`` parameters' names (their entries are in the parameter table, ros/parameters.py).
LOCKSTEP_PARAMETERS = tuple(spec.name for spec in params.LOCKSTEP)


def declare_lockstep_parameters(node: Node, scene: Scene) -> None:
    """Declare the read-only ``lockstep.*`` parameters of the table, the scene's section (or off) as defaults."""
    params.declare_parameters(node, scene, params.LOCKSTEP)


def lockstep_from_parameters(node: Node, scene: Scene, dt: float) -> LockstepSpec | None:
    """The lockstep the parameters ask for (None: off); ValueError as the scene loader words it."""

    def value(spec: params.ParamSpec[Any]) -> Any:
        return node.get_parameter(spec.name).value

    period = float(value(params.LOCKSTEP_PERIOD))
    if period <= 0.0:
        return None
    on_timeout = value(params.LOCKSTEP_ON_TIMEOUT_PARAM)
    params.LOCKSTEP_ON_TIMEOUT_PARAM.check_choice(on_timeout)
    section = {
        "period": period,
        "inputs": list(value(params.LOCKSTEP_INPUTS)),
        "timeout": float(value(params.LOCKSTEP_TIMEOUT)),
        "on_timeout": on_timeout,
    }
    commands = value(params.JOINT_STATE_COMMANDS)  # the wheels' JointState door may be a turn input too
    actuators = ((commands,) if commands else ()) + ((ROD_COMMAND_TOPIC,) if scene.spacecraft.rods else ())
    return lockstep_spec(section, scene.topic_inputs, dt, actuators)


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

    def describe(self) -> tuple[list[str], list[str]]:
        """For the start-up line (:class:`~rigid_rot_sim.ros.parts.Part`): the turns and what they wait for."""
        spec = self.turns.spec
        return [
            f"LOCKSTEP on: a turn every {spec.period:g} s of sim time ({self.turns.period_steps} steps), "
            f"waits for {', '.join(spec.inputs)} (commands stamped t_k), timeout {spec.timeout:g} s -> "
            f"{spec.on_timeout}; {', '.join(self.turn_outputs)} once per turn"
        ], []

    def close(self) -> None:
        """Nothing to close (the turns end with the simulator)."""


__all__ = [
    "LOCKSTEP_PARAMETERS",
    "NodeLockstep",
    "declare_lockstep_parameters",
    "lockstep_from_parameters",
]
