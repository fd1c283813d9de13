"""stable-baselines3 adapter of the batched environments: :class:`TowSB3VecEnv`.

SB3 does not consume Gymnasium ``VectorEnv`` objects; its own ``VecEnv`` API differs (``reset()`` returns
observations only, ``step`` returns ``(obs, rewards, dones, infos)`` with one info dict per copy, the
last observation of a finished episode is in ``infos[i]["terminal_observation"]``, time-limit
truncation is flagged by ``infos[i]["TimeLimit.truncated"]``, seeding goes through ``seed()``).
This adapter drives a :class:`~towenv.envs.vector.TowVectorEnv` in ``SAME_STEP`` autoreset mode, so a
whole SB3 rollout step is one compiled physics call for all copies::

    from towenv.envs.sb3 import TowSB3VecEnv
    venv = TowSB3VecEnv("towenv/WinchPayout-v0", num_envs=16, seed=0)
    model = PPO("MlpPolicy", VecNormalize(venv), device="cpu").learn(100_000)

Each info dict is the single environment's info (``t``, ``reward_components``, ``fish_heave``, …,
``failure``/``solver_failure``/``termination`` when they apply). A numerical failure truncates the
copy (``TimeLimit.truncated = True``: SB3 bootstraps the value of the last good state).
Requires stable-baselines3 (the ``rl`` extra).
"""
from __future__ import annotations

from typing import Any, Sequence

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from stable_baselines3.common.vec_env.base_vec_env import VecEnv

__all__ = ["TowSB3VecEnv"]


class TowSB3VecEnv(VecEnv):
    """SB3 ``VecEnv`` over ``num_envs`` copies of a towenv environment stepped in one compiled call.

    ``env_id`` is a registered id (``towenv/WinchPayout-v0``, ``towenv/CompensatorGains-v0``) or a
    :class:`~towenv.envs.vector.TowVectorEnv` subclass; ``seed`` seeds copy i with ``seed + i`` at the first
    reset; ``parallel`` steps the copies with ``numba.prange``; other keywords go to every copy."""

    def __init__(self, env_id: str | type = "towenv/WinchPayout-v0", num_envs: int = 1, *, seed: int | None = None,
                 parallel: bool = False, **env_kwargs: Any):
        if isinstance(env_id, str):
            spec = gym.spec(env_id)
            vep = spec.vector_entry_point
            if vep is None:
                raise ValueError(f"{env_id!r} has no vector_entry_point")
            if isinstance(vep, str):
                mod, name = vep.split(":")
                import importlib
                vep = getattr(importlib.import_module(mod), name)
            cls = vep
        else:
            cls = env_id
        self.venv = cls(num_envs, autoreset_mode=AutoresetMode.SAME_STEP, batch_infos=False, parallel=parallel,
                        **env_kwargs)
        self.envs = self.venv.envs
        super().__init__(int(num_envs), self.venv.single_observation_space, self.venv.single_action_space)
        if seed is not None:
            self.seed(seed)
        self._actions = None

    # ------------------------------------------------------------------ VecEnv API
    def reset(self):
        seeds = [s for s in self._seeds]
        for i, env in enumerate(self.envs):
            obs, info = env.reset(seed=seeds[i], options=self._options[i] or None)
            self.venv._obs[i] = obs
            self.reset_infos[i] = info
        self.venv._started[:] = True
        self.venv._autoreset[:] = False
        self._reset_seeds()
        self._reset_options()
        return self.venv._obs.copy()

    def step_async(self, actions: np.ndarray) -> None:
        self._actions = actions

    def step_wait(self):
        venv = self.venv
        res, idx, _, final = venv._step_arrays(self._actions)
        obs = venv._obs.copy()
        rewards = venv._rew.astype(np.float32)
        term, trunc = venv._term, venv._trunc
        dones = term | trunc
        infos: list[dict] = []
        for k in range(self.num_envs):
            info = final[k][1] if k in final else res.info(k)
            if dones[k]:
                info["TimeLimit.truncated"] = bool(trunc[k] and not term[k])
                info["terminal_observation"] = final[k][0]
            infos.append(info)
        return obs, rewards, dones.copy(), infos

    def close(self) -> None:
        self.venv.close()

    def get_attr(self, attr_name: str, indices=None) -> list[Any]:
        return [getattr(self.envs[i], attr_name) for i in self._get_indices(indices)]

    def set_attr(self, attr_name: str, value: Any, indices=None) -> None:
        for i in self._get_indices(indices):
            setattr(self.envs[i], attr_name, value)

    def env_method(self, method_name: str, *method_args, indices=None, **method_kwargs) -> list[Any]:
        return [getattr(self.envs[i], method_name)(*method_args, **method_kwargs) for i in self._get_indices(indices)]

    def env_is_wrapped(self, wrapper_class, indices=None) -> list[bool]:
        return [False for _ in self._get_indices(indices)]

    def get_images(self) -> Sequence[np.ndarray | None]:
        return [None for _ in range(self.num_envs)]
