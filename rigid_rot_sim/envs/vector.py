"""The native vector environments: N slew episodes stepped together on the compiled batch kernels.

``gymnasium.make_vec("rigid_rot_sim.envs:RigidRot/AttitudeControl-v0", num_envs=N,
vectorization_mode="vector_entry_point")`` builds :class:`AttitudeControlVectorEnv` (and the
``WheelAttitudeControl`` id :class:`WheelAttitudeControlVectorEnv`); its spaces are the single
environment's for the same arguments. Autoreset (``autoreset_mode=``, declared in
``metadata["autoreset_mode"]``), as Gymnasium's ``SyncVectorEnv`` does it over the single
environment: ``NEXT_STEP`` (the default) - the step after a slot's episode ends resets that slot,
ignores its action and returns its first observation with reward 0 and neither flag set;
``SAME_STEP`` - the step that ends an episode resets the slot and returns its first observation,
the last one under ``info["final_obs"]``; ``DISABLED`` - no autoreset: reset ended slots with
``reset(options={"reset_mask": mask})``. Either way the reset's info comes masked (``_key``).
``reset(options={"reset_mask": mask})`` resets only the slots of ``mask``; the others keep their
state, step count and generator.

Seeding: every slot has its own generator, exactly the single environment's
(``gymnasium.utils.seeding.np_random``). ``reset(seed=[s0, s1, ...])`` seeds slot i with s_i, so
that slot i runs, bit for bit, the episodes of the single environment reset with ``seed=s_i`` and
driven by the same actions (later episodes included: both continue the slot's generator).
``reset(seed=s)`` seeds slot i with :func:`slot_seeds` ``(s, N)[i]``; a slot reset without a
seed continues its generator, as the single environment does.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from rigid_rot_sim.envs.attitude import action_space, make_task, observation_space
from rigid_rot_sim.envs.task import ObservationSensors, SlewBodies

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
        autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP,
        **kwargs: Any,
    ) -> None:
        if int(num_envs) != num_envs or num_envs < 1:
            raise ValueError(f"num_envs must be an integer >= 1, got {num_envs!r}")
        if render_mode is not None:
            raise ValueError(f"render_mode must be None (no rendering), got {render_mode!r}")
        try:
            self.autoreset_mode = AutoresetMode(autoreset_mode)
        except ValueError:
            modes = ", ".join(f"AutoresetMode.{mode.name}" for mode in AutoresetMode)
            raise ValueError(f"autoreset_mode must be one of {modes}, got {autoreset_mode!r}") from None
        self.metadata = {**type(self).metadata, "autoreset_mode": self.autoreset_mode}
        self.num_envs = int(num_envs)
        self.render_mode = None
        own = ("num_envs", "render_mode", "sensors", "autoreset_mode")
        self.task = make_task(type(self).__name__, own, sensors, **kwargs)
        self.single_observation_space = observation_space(self.task, self.with_wheels)
        self.single_action_space = action_space()
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.bodies = SlewBodies(self.task, self.num_envs, self.with_wheels)
        self._generators: list[np.random.Generator | None] = [None] * self.num_envs
        self._started = False
        self._ended = np.zeros(self.num_envs, dtype=np.bool_)  # slots whose episode ended on the last step

    def reset(
        self, *, seed: int | list[int | None] | None = None, options: dict[str, Any] | None = None
    ) -> tuple[np.ndarray, dict[str, Any]]:
        """A new episode in every slot, or in those of ``options["reset_mask"]`` (a bool array (num_envs,)).

        ``seed``: one int (spawned by :func:`slot_seeds`) or one per slot (a slot outside the mask
        ignores its seed); ``None`` continues each slot's generator. ``options`` is not modified.
        """
        if seed is None:
            seeds: list[int | None] = [None] * self.num_envs
        elif isinstance(seed, (int, np.integer)):
            seeds = list(slot_seeds(int(seed), self.num_envs))
        else:
            seeds = list(seed)
            if len(seeds) != self.num_envs:
                raise ValueError(f"reset: {len(seeds)} seeds for {self.num_envs} slots")
        mask = self._reset_mask(options)
        slots = np.flatnonzero(mask)
        for slot in slots.tolist():
            if seeds[slot] is not None or self._generators[slot] is None:
                self._generators[slot] = seeding.np_random(seeds[slot])[0]
        infos = self._reset_slots(slots)
        self._ended[slots] = False
        self._started = True
        return self.bodies.observation.copy(), infos

    def _reset_mask(self, options: dict[str, Any] | None) -> np.ndarray:
        """The slots to reset: ``options["reset_mask"]``, checked as Gymnasium's SyncVectorEnv checks it, or all."""
        if options is None or "reset_mask" not in options:
            return np.ones(self.num_envs, dtype=np.bool_)
        mask = options["reset_mask"]
        if not isinstance(mask, np.ndarray):
            raise TypeError(f"`options['reset_mask']` must be a numpy array, got {type(mask)}")
        if mask.shape != (self.num_envs,):
            raise ValueError(f"`options['reset_mask']` must have shape `({self.num_envs},)`, got {mask.shape}")
        if mask.dtype != np.bool_:
            raise TypeError(f"`options['reset_mask']` must have `dtype=np.bool_`, got {mask.dtype}")
        if not np.any(mask):
            raise ValueError(
                "`options['reset_mask']` must contain a boolean array with at least one True value, "
                f"got reset_mask={mask}"
            )
        if not self._started and not mask.all():
            raise RuntimeError("the first reset() resets every slot: call it without a reset_mask")
        return mask

    def step(self, actions: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, dict[str, Any]]:
        """One control period of every slot (actions (num_envs, 3) in [-1, 1]); ended slots restart per the mode."""
        if not self._started:
            raise RuntimeError("call reset() before step()")
        mode = self.autoreset_mode
        if mode is AutoresetMode.DISABLED and self._ended.any():
            raise RuntimeError(
                f"slots {np.flatnonzero(self._ended).tolist()} ended and autoreset_mode is DISABLED: reset them with "
                "reset(options={'reset_mask': mask}) before the next step"
            )
        restarting = np.flatnonzero(self._ended) if mode is AutoresetMode.NEXT_STEP else np.zeros(0, dtype=np.int64)
        reward, terminated, truncated = self.bodies.step(actions)
        infos: dict[str, Any] = {}
        if restarting.size:
            infos = self._reset_slots(restarting)
            reward[restarting] = 0.0
            terminated[restarting] = False
            truncated[restarting] = False
        ended = terminated | truncated
        if mode is AutoresetMode.SAME_STEP and ended.any():
            slots = np.flatnonzero(ended)
            final_obs = np.full(self.num_envs, None, dtype=object)
            for slot in slots.tolist():
                final_obs[slot] = self.bodies.observation[slot].copy()
            infos = {"final_obs": final_obs, "_final_obs": ended.copy(), "final_info": {}, "_final_info": ended.copy()}
            infos.update(self._reset_slots(slots))
            self._ended[:] = False
        else:
            self._ended = ended
        return self.bodies.observation.copy(), reward, terminated, truncated, infos

    def _reset_slots(self, slots: np.ndarray) -> dict[str, Any]:
        """New episodes in ``slots`` from their generators; their infos batched as ``VectorEnv._add_info`` does."""
        generators = [self._generators[slot] for slot in slots.tolist()]
        episodes = self.bodies.reset(slots, [g for g in generators if g is not None])
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
