"""Gymnasium environments: slew a rigid body to a target attitude, by body torque or by reaction wheels.

``RigidRot/AttitudeControl-v0`` (:class:`AttitudeControlEnv`): the action ``a`` (3,) in [-1, 1]
(clipped) is the body torque ``a * max_torque`` (N*m, body axes), held for ``control_period`` s
over fixed RK4 steps of ``dt``. ``RigidRot/WheelAttitudeControl-v0`` (:class:`WheelAttitudeControlEnv`):
``a * max_torque`` are the motor torques of three reaction wheels on the body axes (the body feels
their reaction; a wheel's torque fades to zero at its maximum speed, as the engine models it).

Observation (float64): the attitude quaternion (x, y, z, w, body -> world), the body rate (rad/s,
body axes), the attitude error to the target as a rotation vector (rad) and, with wheels, the three
wheel speeds (rad/s, relative to the body), and with ``field_observation=True`` the Earth's magnetic
field in the body axes (T; :func:`~rigid_rot_sim.envs.task.world_field`, docs/gym.md); ``sensors=``
replaces the first two by the seeded gyro and star-tracker readings
(:class:`~rigid_rot_sim.envs.task.ObservationSensors`). Reward, hold test and draws:
:mod:`rigid_rot_sim.core.slew` and :class:`~rigid_rot_sim.envs.task.SlewTask`.
``terminated``: held within tolerance for ``hold_periods`` periods; ``truncated``: after
``max_episode_steps`` periods. ``reset(seed=s)`` fixes every random number of the episode
(inertia, target, initial state, sensor noise): the same seed and actions give the same
observations bit for bit, in any process.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium import spaces

from rigid_rot_sim.envs.task import DEFAULT_SENSORS, ObservationSensors, SlewBodies, SlewTask, world_field

__all__ = [
    "AttitudeControlEnv",
    "WheelAttitudeControlEnv",
    "make_task",
    "observation_space",
    "action_space",
    "TASK_ARGUMENTS",
]

#: The keyword arguments of the environments beside ``render_mode`` and ``sensors``: the task's fields.
TASK_ARGUMENTS = tuple(f.name for f in dataclasses.fields(SlewTask) if f.name != "sensors")


def make_task(
    owner: str, own: tuple[str, ...], sensors: ObservationSensors | bool | None = None, **kwargs: Any
) -> SlewTask:
    """A :class:`SlewTask` from ``owner``'s keyword arguments (``sensors=True``: :data:`DEFAULT_SENSORS`).

    An argument that is no field of the task is refused by name, with the arguments ``owner``
    takes: its ``own`` ones and the task's.
    """
    unknown = sorted(set(kwargs) - set(TASK_ARGUMENTS))
    if unknown:
        hint = (
            " (a vector environment's argument: gymnasium.make_vec(..., vector_kwargs={'autoreset_mode': ...}) "
            "for the sync and async modes)"
            if "autoreset_mode" in unknown
            else ""
        )
        raise TypeError(
            f"{owner}: unexpected argument {unknown[0]!r}{hint}; its arguments are {', '.join(own + TASK_ARGUMENTS)}"
        )
    if sensors is True:
        sensors = DEFAULT_SENSORS
    elif sensors is False:
        sensors = None
    return SlewTask(sensors=sensors, **kwargs)


def observation_space(task: SlewTask, with_wheels: bool) -> spaces.Box:
    """The observation's Box: finite bounds from :meth:`SlewTask.rate_bound` (or the gyro's saturation)."""
    rate = task.sensors.gyro.saturation if task.sensors is not None else task.rate_bound(with_wheels)
    high = [1.0] * 4 + [rate] * 3 + [math.pi] * 3
    if with_wheels:
        high += [task.wheel_speed_bound()] * 3
    if task.field_observation:
        high += [1.01 * math.hypot(*world_field())] * 3  # each body-axis component is at most |B|
    bound = np.array(high)
    return spaces.Box(-bound, bound, dtype=np.float64)


def action_space() -> spaces.Box:
    """Three normalised torques in [-1, 1] (float32, as learning libraries emit them)."""
    return spaces.Box(-1.0, 1.0, shape=(3,), dtype=np.float32)


class AttitudeControlEnv(gym.Env[np.ndarray, np.ndarray]):
    """Slew to a target attitude by body torque (keyword arguments: the fields of :class:`SlewTask`)."""

    metadata: dict[str, Any] = {"render_modes": []}
    with_wheels = False

    def __init__(self, render_mode: str | None = None, sensors: ObservationSensors | bool | None = None, **kwargs: Any):
        if render_mode is not None:
            raise ValueError(f"render_mode must be None (no rendering), got {render_mode!r}")
        self.task = make_task(type(self).__name__, ("render_mode", "sensors"), sensors, **kwargs)
        self.observation_space = observation_space(self.task, self.with_wheels)
        self.action_space = action_space()
        self.bodies = SlewBodies(self.task, 1, self.with_wheels)
        self._started = False

    def reset(self, *, seed: int | None = None, options: dict[str, Any] | None = None) -> tuple[np.ndarray, dict]:
        """A new episode drawn from the environment's generator (seeded by ``seed`` when given; no options)."""
        super().reset(seed=seed)
        (episode,) = self.bodies.reset([0], [self.np_random])
        self._started = True
        return self.bodies.observation[0].copy(), episode.info()

    def step(self, action: Any) -> tuple[np.ndarray, float, bool, bool, dict]:
        """One control period under ``action`` (3,) in [-1, 1]."""
        if not self._started:
            raise RuntimeError("call reset() before step()")
        reward, terminated, truncated = self.bodies.step(np.asarray(action).reshape(1, 3))
        return self.bodies.observation[0].copy(), float(reward[0]), bool(terminated[0]), bool(truncated[0]), {}


class WheelAttitudeControlEnv(AttitudeControlEnv):
    """Slew to a target attitude with three reaction wheels (the action: their motor torques)."""

    with_wheels = True
