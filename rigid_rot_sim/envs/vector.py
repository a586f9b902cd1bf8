"""The native vector environments: N slew episodes stepped together on the compiled batch kernels.

``gymnasium.make_vec("rigid_rot_sim.envs:RigidRot/AttitudeControl-v0", num_envs=N,
vectorization_mode="vector_entry_point")`` builds :class:`AttitudeControlVectorEnv` (and the
``WheelAttitudeControl`` id :class:`WheelAttitudeControlVectorEnv`). Autoreset: Gymnasium's
``AutoresetMode.NEXT_STEP`` (declared in ``metadata["autoreset_mode"]``): the step after a slot's
episode ends resets that slot, ignores its action and returns its first observation with reward 0
and neither flag set (and the reset's info, masked as SyncVectorEnv masks it).

Seeding: every slot has its own generator, exactly the single environment's
(``gymnasium.utils.seeding.np_random``). ``reset(seed=[s0, s1, ...])`` seeds slot i with s_i, so
that slot i runs, bit for bit, the episodes of the single environment reset with ``seed=s_i`` and
driven by the same actions (later episodes included: both continue the slot's generator).
``reset(seed=s)`` seeds slot i with :func:`slot_seeds` ``(s, N)[i]``.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from rigid_rot_sim.envs.attitude import action_space, make_task, observation_space
from rigid_rot_sim.envs.task import Episode, ObservationSensors, SlewBodies

__all__ = ["AttitudeControlVectorEnv", "WheelAttitudeControlVectorEnv", "slot_seeds"]


def slot_seeds(seed: int, num_envs: int) -> list[int]:
    """The slots' seeds spawned from one seed: slot i gets the 64-bit word of ``SeedSequence(seed).spawn(num_envs)[i]``.

    ``int(np.random.SeedSequence(seed, spawn_key=(i,)).generate_state(1, np.uint64)[0])``: independent
    streams by NumPy's rule, and slot i's seed does not depend on the number of slots.
    """
    children = np.random.SeedSequence(seed).spawn(num_envs)
    return [int(child.generate_state(1, np.uint64)[0]) for child in children]


class AttitudeControlVectorEnv(VectorEnv):
    """``num_envs`` slots of :class:`~rigid_rot_sim.envs.attitude.AttitudeControlEnv` in one batch."""

    metadata: dict[str, Any] = {"render_modes": [], "autoreset_mode": AutoresetMode.NEXT_STEP}
    with_wheels = False

    def __init__(
        self,
        num_envs: int = 1,
        render_mode: str | None = None,
        sensors: ObservationSensors | bool | None = None,
        **kwargs: Any,
    ) -> None:
        if int(num_envs) != num_envs or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if render_mode is not None:
            raise ValueError(f"render_mode must be None (no rendering), got {render_mode!r}")
        self.num_envs = int(num_envs)
        self.render_mode = None
        self.task = make_task(sensors, **kwargs)
        self.single_observation_space = observation_space(self.task, self.with_wheels)
        self.single_action_space = action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.bodies = SlewBodies(self.task, self.num_envs, self.with_wheels)
        self._generators: list[np.random.Generator] = []
        self._autoreset = np.zeros(self.num_envs, dtype=np.bool_)

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """A new episode in every slot (``seed``: one int, spawned by :func:`slot_seeds`, or one per slot)."""
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            seeds = list(slot_seeds(int(seed), self.num_envs))
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"reset: {len(seeds)} seeds for {self.num_envs} slots")
        self._generators = [seeding.np_random(s)[0] for s in seeds]
        slots = np.arange(self.num_envs)
        infos = self._reset_infos(slots, self.bodies.reset(slots, self._generators))
        self._autoreset[:] = False
        return self.bodies.observation.copy(), infos

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One control period of every slot (actions (num_envs, 3) in [-1, 1]); slots that ended last step restart."""
        if not self._generators:
            raise RuntimeError("call reset() before step()")
        restarting = np.flatnonzero(self._autoreset)
        reward, terminated, truncated = self.bodies.step(actions)
        infos: dict[str, Any] = {}
        if restarting.size:
            episodes = self.bodies.reset(restarting, [self._generators[slot] for slot in restarting])
            infos = self._reset_infos(restarting, episodes)
        reward[restarting] = 0.0
        terminated[restarting] = False
        truncated[restarting] = False
        self._autoreset = terminated | truncated
        return self.bodies.observation.copy(), reward, terminated, truncated, infos

    def _reset_infos(self, slots: np.ndarray, episodes: list[Episode]) -> dict[str, Any]:
        """The reset infos of ``slots``, batched as ``VectorEnv._add_info`` batches them (value, ``_key`` mask)."""
        infos: dict[str, Any] = {}
        mask = np.zeros(self.num_envs, dtype=np.bool_)
        mask[slots] = True
        moments = np.array([episode.principal_moments for episode in episodes])
        targets = np.array([episode.target for episode in episodes])
        inertias = np.zeros((len(episodes), 3, 3))
        inertias[:, [0, 1, 2], [0, 1, 2]] = moments  # Episode.info's np.diag, for all at once
        for key, values in (("principal_moments", moments), ("inertia", inertias), ("target", targets)):
            array = np.zeros((self.num_envs, *values.shape[1:]), dtype=values.dtype)
            array[slots] = values
            infos[key] = array
            infos["_" + key] = mask.copy()
        return infos


class WheelAttitudeControlVectorEnv(AttitudeControlVectorEnv):
    """``num_envs`` slots of :class:`~rigid_rot_sim.envs.attitude.WheelAttitudeControlEnv` in one batch."""

    with_wheels = True
