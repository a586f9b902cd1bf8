"""The rule of the wheels' JointState door: which wheel commands a sensor_msgs/JointState carries.

ros2_control's topic hardware interface (``joint_state_topic_hardware_interface/JointStateTopicSystem``)
publishes, at every controller-manager cycle whose commands changed, one JointState with every joint
of its ``<ros2_control>`` block in ``name`` and, per joint, the value of each of its command interfaces
in ``position``, ``velocity`` or ``effort``. A reaction wheel is driven by its motor torque, so the
door reads ``effort`` (N*m) and nothing else:

* ``name`` names any subset of the scene's wheels, in any order, each at most once;
* ``effort`` has one finite value per name; ``position`` and ``velocity`` are ignored when
  ``effort`` is given (a joint may have more command interfaces than this door reads);
* a command with velocity or position only, no names, an unknown or repeated name, an ``effort``
  whose length differs from ``name``'s, or a non-finite effort is rejected as a whole, with the
  reason: nothing of it acts.

A wheel keeps its command until the next command that names it (no timeout): the interface's
changed-value threshold may suppress repetitions for as long as the value stays the same, and the
wheel must still be driven. :func:`merged_torques` builds the full set of motor torques (scene
order) the simulator then holds: the named wheels' new efforts, the others as they act now.
No ROS here: the door (:mod:`rigid_rot_sim.ros.joint_state_door`) passes the message's arrays. The torque
rods' command (``~/magnetorquer_command``) follows the same rule with their dipoles (A*m^2) in ``effort``
(:func:`joint_efforts` with :data:`RODS`).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

from rigid_rot_sim.run.commands import STAMP_HORIZON, CommandRejected

__all__ = ["Actuators", "WHEELS", "RODS", "wheel_efforts", "joint_efforts", "merged_torques", "effective_time"]


@dataclass(frozen=True)
class Actuators:
    """The words a door's reasons use for its joints: plural, short and singular names, quantity, unit."""

    plural: str
    short: str
    singular: str
    quantity: str
    unit: str


WHEELS = Actuators("reaction wheels", "wheels", "wheel", "motor torques", "N*m")
RODS = Actuators("torque rods", "rods", "rod", "dipoles", "A*m^2")


def wheel_efforts(
    source: str,
    wheel_names: Sequence[str],
    names: Sequence[str],
    position: Sequence[float],
    velocity: Sequence[float],
    effort: Sequence[float],
) -> dict[int, float]:
    """The efforts (N*m) of a JointState command by wheel index (scene order); CommandRejected with the reason."""
    return joint_efforts(WHEELS, source, wheel_names, names, position, velocity, effort)


def joint_efforts(
    actuators: Actuators,
    source: str,
    joint_names: Sequence[str],
    names: Sequence[str],
    position: Sequence[float],
    velocity: Sequence[float],
    effort: Sequence[float],
) -> dict[int, float]:
    """The efforts of a JointState command by joint index (scene order) under the rule above (the rods' door
    reads their dipoles, A*m^2, by the same rule); CommandRejected with the reason."""
    if not joint_names:
        raise CommandRejected(source, f"this scene has no {actuators.plural}")
    if not names:
        raise CommandRejected(source, "the command names no joint")
    if not effort:
        given = " and ".join(field for field, values in (("position", position), ("velocity", velocity)) if values)
        what = f"{given} only" if given else "no value"
        raise CommandRejected(
            source,
            f"{what}: this door takes the {actuators.short}' {actuators.quantity} in effort ({actuators.unit}); "
            "give the joints an effort command interface",
        )
    if len(effort) != len(names):
        raise CommandRejected(source, f"mismatched array lengths: {len(names)} name(s), {len(effort)} effort value(s)")
    index = {name: i for i, name in enumerate(joint_names)}
    efforts: dict[int, float] = {}
    for name, value in zip(names, effort, strict=True):
        if name not in index:
            raise CommandRejected(source, f"unknown joint {name!r} (the {actuators.short}: {', '.join(joint_names)})")
        if index[name] in efforts:
            raise CommandRejected(source, f"joint {name!r} is named twice")
        value = float(value)
        if not math.isfinite(value):
            raise CommandRejected(source, f"non-finite effort for {actuators.singular} {name!r}: {value}")
        efforts[index[name]] = value
    return efforts


def effective_time(source: str, stamp: float, now: float) -> float | None:
    """When a command stamped ``stamp`` (s; 0: none) acts: at the stamp when it is not in the past, else on
    receipt (None). CommandRejected for a stamp more than ``STAMP_HORIZON`` s ahead of sim time ``now``: the
    interface's node stamps with its clock, which is wall time without ``use_sim_time`` (the rule of the
    torque topics, :meth:`~rigid_rot_sim.run.commands.CommandSchedule.admit`)."""
    if not math.isfinite(stamp) or stamp == 0.0:
        return None
    if stamp > now + STAMP_HORIZON:
        raise CommandRejected(
            source,
            f"header stamp {stamp:.9g} s is {stamp - now:.3g} s ahead of sim time {now:.9g} s (limit "
            f"{STAMP_HORIZON:g} s): run the controller manager with use_sim_time true (our /clock)",
        )
    return stamp if stamp >= now else None


def merged_torques(acting: Sequence[float], efforts: dict[int, float]) -> list[float]:
    """The motor torques of every wheel (scene order): ``efforts`` where given, else what acts now."""
    return [efforts.get(i, float(value)) for i, value in enumerate(acting)]
