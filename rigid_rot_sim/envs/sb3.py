"""Stable-Baselines3 on the native vector environment: SB3's ``VecEnv`` interface over one batch.

SB3 trains on a ``VecEnv``: ``reset()`` returns the observations only (the reset infos go to
``reset_infos``); ``step(actions)`` returns ``(obs, rewards, dones, infos)`` with ``dones =
terminated | truncated``, one info dict per slot, ``info["TimeLimit.truncated"]`` (truncated and
not terminated) and, for a slot that ended, the slot already reset and its last observation under
``info["terminal_observation"]``: Gymnasium's ``SAME_STEP`` autoreset, the mode the native vector
environment runs in here. ``seed(s)`` and ``set_options`` apply at the next ``reset()``, slot i
seeded ``s + i``, as SB3's own ``DummyVecEnv`` seeds its environments::

    from stable_baselines3 import SAC
    from stable_baselines3.common.vec_env import VecMonitor
    from rigid_rot_sim.envs.sb3 import sb3_vec_env

    venv = VecMonitor(sb3_vec_env("rigid_rot_sim.envs:RigidRot/AttitudeControl-v0", num_envs=64))
    SAC("MlpPolicy", venv).learn(100_000)

SB3 is no dependency of this package (it needs torch): :class:`NativeVecEnv` implements SB3's
interface by itself (SB3 2.x, ``stable_baselines3/common/vec_env/base_vec_env.py``), and
:func:`sb3_vec_env` makes it a subclass of SB3's ``VecEnv`` when SB3 is importable, so that SB3's
algorithms take it as a vector environment instead of wrapping it as a single one.
"""

from __future__ import annotations

import functools
import importlib
from copy import deepcopy
from typing import Any

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode

from rigid_rot_sim.envs.vector import AttitudeControlVectorEnv

__all__ = ["NativeVecEnv", "sb3_vec_env", "unbatch_infos"]


def unbatch_infos(infos: dict[str, Any], num_envs: int) -> list[dict[str, Any]]:
    """Gymnasium's batched infos (value arrays with ``_key`` masks) as one dict per slot, as SB3 keeps them."""
    slots: list[dict[str, Any]] = [{} for _ in range(num_envs)]
    for key, values in infos.items():
        if key.startswith("_") or f"_{key}" not in infos:
            continue
        per_slot = unbatch_infos(values, num_envs) if isinstance(values, dict) else None
        for i in np.flatnonzero(infos[f"_{key}"]).tolist():
            slots[i][key] = per_slot[i] if per_slot is not None else values[i]
    return slots


class NativeVecEnv:
    """SB3's ``VecEnv`` interface over a native vector environment in ``SAME_STEP`` autoreset mode.

    ``observation_space`` and ``action_space`` are the single environment's (SB3's convention);
    rewards come as float32, as SB3's DummyVecEnv returns them. The slots are one batch: there is
    no per-slot method to call (``env_method`` refuses) and an attribute is set on all of them.
    """

    def __init__(self, envs: AttitudeControlVectorEnv) -> None:
        mode = envs.metadata.get("autoreset_mode")
        if mode is not AutoresetMode.SAME_STEP:
            raise ValueError(
                "SB3 resets a slot in the step that ends it: build the vector environment with "
                f"autoreset_mode=AutoresetMode.SAME_STEP (got {mode})"
            )
        self.envs = envs
        self.num_envs = envs.num_envs
        self.observation_space = envs.single_observation_space
        self.action_space = envs.single_action_space
        self.render_mode = None
        self.metadata: dict[str, Any] = {"render_modes": []}
        self.reset_infos: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        self._seeds: list[int | None] = [None] * self.num_envs
        self._options: list[dict[str, Any]] = [{} for _ in range(self.num_envs)]
        self._actions: np.ndarray | None = None

    def reset(self) -> np.ndarray:
        """Every slot restarts (with the seeds of :meth:`seed`, once); returns the observations."""
        if any(self._options):
            raise ValueError(f"the environments take no reset options, got {self._options[0]!r}")
        seeds = None if all(s is None for s in self._seeds) else list(self._seeds)
        obs, infos = self.envs.reset(seed=seeds)
        self.reset_infos = unbatch_infos(infos, self.num_envs)
        self._seeds = [None] * self.num_envs
        self._options = [{} for _ in range(self.num_envs)]
        return obs

    def step_async(self, actions: np.ndarray) -> None:
        """Hold the actions (num_envs, 3) for :meth:`step_wait`."""
        self._actions = np.asarray(actions)

    def step_wait(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """One step of every slot: ``(obs, rewards float32, dones, infos)``; ended slots come back reset."""
        if self._actions is None:
            raise RuntimeError("call step_async(actions) before step_wait()")
        obs, rewards, terminated, truncated, infos = self.envs.step(self._actions)
        self._actions = None
        dones = terminated | truncated
        slots = unbatch_infos(infos, self.num_envs)
        step_infos: list[dict[str, Any]] = []
        for i, info in enumerate(slots):
            step_info: dict[str, Any] = {"TimeLimit.truncated": bool(truncated[i] and not terminated[i])}
            if dones[i]:
                step_info["terminal_observation"] = info.pop("final_obs")
                info.pop("final_info")
                self.reset_infos[i] = info
            step_infos.append(step_info)
        return obs, rewards.astype(np.float32), dones, step_infos

    def step(self, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[dict[str, Any]]]:
        """:meth:`step_async` then :meth:`step_wait`."""
        self.step_async(actions)
        return self.step_wait()

    def seed(self, seed: int | None = None) -> list[int | None]:
        """Slot i gets ``seed + i`` at the next reset (``None``: a random 32-bit base, as SB3 draws it)."""
        if seed is None:
            seed = int(np.random.randint(0, np.iinfo(np.uint32).max, dtype=np.uint32))
        self._seeds = [seed + i for i in range(self.num_envs)]
        return list(self._seeds)

    def set_options(self, options: list[dict[str, Any]] | dict[str, Any] | None = None) -> None:
        """Options for the next reset (the environments take none: a non-empty one is refused there)."""
        if options is None:
            options = {}
        self._options = deepcopy([options] * self.num_envs if isinstance(options, dict) else list(options))

    def close(self) -> None:
        """Close the vector environment."""
        self.envs.close()

    def _indices(self, indices: None | int | Any) -> list[int]:
        if indices is None:
            return list(range(self.num_envs))
        return [indices] if isinstance(indices, int) else list(indices)

    def has_attr(self, attr_name: str) -> bool:
        """Whether the vector environment has ``attr_name``."""
        return hasattr(self.envs, attr_name)

    def get_attr(self, attr_name: str, indices: None | int | Any = None) -> list[Any]:
        """The vector environment's ``attr_name``, once per slot asked for (the slots share it)."""
        value = getattr(self.envs, attr_name)
        return [value for _ in self._indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices: None | int | Any = None) -> None:
        """Set ``attr_name`` on the vector environment: all slots at once or none."""
        if sorted(self._indices(indices)) != list(range(self.num_envs)):
            raise ValueError(f"the slots share one environment: set {attr_name!r} on all of them (indices=None)")
        setattr(self.envs, attr_name, value)

    def env_method(self, method_name: str, *method_args: Any, indices: None | int | Any = None, **kwargs: Any) -> Any:
        """Refused: the slots are one batch, with no environment object per slot to call."""
        raise AttributeError(
            f"env_method({method_name!r}): the slots are one batch with no per-slot environment; "
            "call the vector environment (.envs) instead"
        )

    def env_is_wrapped(self, wrapper_class: type, indices: None | int | Any = None) -> list[bool]:
        """No slot is wrapped (wrap the whole in SB3's ``VecMonitor`` for episode statistics)."""
        return [False for _ in self._indices(indices)]

    def get_images(self) -> list[None]:
        """No rendering."""
        return [None for _ in range(self.num_envs)]

    def render(self, mode: str | None = None) -> None:
        """No rendering."""
        return None

    @property
    def unwrapped(self) -> NativeVecEnv:
        """This adapter (SB3 unwraps its VecEnvWrappers down to it)."""
        return self

    def getattr_depth_check(self, name: str, already_found: bool) -> str | None:
        """SB3's check that a wrapper's attribute does not hide one of ours."""
        if hasattr(self, name) and already_found:
            return f"{type(self).__module__}.{type(self).__name__}"
        return None


@functools.cache
def _sb3_class() -> type:
    try:
        vec_env = importlib.import_module("stable_baselines3.common.vec_env")  # optional: no stubs, no dependency
    except ImportError as error:
        raise ImportError(
            f"sb3_vec_env needs Stable-Baselines3 (pip install stable-baselines3), which failed to import: {error}"
        ) from error
    return type("SB3NativeVecEnv", (NativeVecEnv, vec_env.VecEnv), {"__module__": __name__})


def sb3_vec_env(env: str | AttitudeControlVectorEnv, num_envs: int = 1, **kwargs: Any) -> NativeVecEnv:
    """An SB3 ``VecEnv`` over the native vector environment of ``env`` (an id, with ``make``'s keyword
    arguments) or over ``env`` itself (a vector environment in ``SAME_STEP`` mode)."""
    cls = _sb3_class()
    if isinstance(env, str):
        vector = gym.make_vec(
            env,
            num_envs=num_envs,
            vectorization_mode="vector_entry_point",
            autoreset_mode=AutoresetMode.SAME_STEP,
            **kwargs,
        )
        if not isinstance(vector, AttitudeControlVectorEnv):
            raise ValueError(f"{env!r} is not an id of rigid_rot_sim.envs (its native vector environment is needed)")
        env = vector
    adapter: NativeVecEnv = cls(env)
    return adapter
