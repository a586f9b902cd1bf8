"""Gymnasium environments on the compiled batch core (docs/gym.md).

Importing this package registers, under the ``RigidRot`` namespace::

    gymnasium.make("rigid_rot_sim.envs:RigidRot/AttitudeControl-v0")
    gymnasium.make("rigid_rot_sim.envs:RigidRot/WheelAttitudeControl-v0")
    gymnasium.make_vec("rigid_rot_sim.envs:RigidRot/AttitudeControl-v0", num_envs=1024,
                       vectorization_mode="vector_entry_point")

(the ``module:`` prefix imports this package first). Keyword arguments of ``make`` and
``make_vec`` are the fields of :class:`~rigid_rot_sim.envs.task.SlewTask` and ``sensors``.

Modules: :mod:`.task` - the slew task (dispersions, reward, bounds); :mod:`.attitude` - the single
environments; :mod:`.vector` - the native vector environment on the batch kernels; :mod:`.sb3` -
Stable-Baselines3's ``VecEnv`` interface over the native vector environment.
"""

from __future__ import annotations

from gymnasium.envs.registration import register, registry

from rigid_rot_sim.envs.task import DEFAULT_SENSORS, ObservationSensors, SlewTask

__all__ = ["DEFAULT_SENSORS", "ObservationSensors", "SlewTask", "MAX_EPISODE_STEPS", "ENV_IDS"]

#: The registered episode length (control periods): ``make`` applies it with TimeLimit, ``make_vec``
#: passes it to the vector environment; both environments also truncate there themselves.
MAX_EPISODE_STEPS = SlewTask.max_episode_steps

#: The registered ids and their single and vector entry points.
ENV_IDS = {
    "RigidRot/AttitudeControl-v0": ("AttitudeControlEnv", "AttitudeControlVectorEnv"),
    "RigidRot/WheelAttitudeControl-v0": ("WheelAttitudeControlEnv", "WheelAttitudeControlVectorEnv"),
}

for _id, (_single, _vector) in ENV_IDS.items():
    if _id not in registry:
        register(
            id=_id,
            entry_point=f"rigid_rot_sim.envs.attitude:{_single}",
            vector_entry_point=f"rigid_rot_sim.envs.vector:{_vector}",
            max_episode_steps=MAX_EPISODE_STEPS,
        )
