"""Batched environments: ``N`` TowEnv copies stepped in one ``VectorEnv.step`` call.

First version: the copies' Simulators are looped in Python inside one process (each copy's physics
sub-steps already run in one compiled ``advance_steps`` call). This saves Gymnasium's SyncVectorEnv
bookkeeping but not the per-copy Python overhead; **a single compiled multi-copy kernel (one numba call
stepping all B systems, optionally with ``prange``) is future work** — it needs a batched ``advance`` in
the simulator core.

Registered as the ``vector_entry_point`` of both ids, so
``gymnasium.make_vec("towenv/CompensatorGains-v0", num_envs=8, vectorization_mode="vector_entry_point")``
builds one of these. Autoreset follows Gymnasium 1.x: ``NEXT_STEP`` (default; the step after an
episode ends returns the reset observation with reward 0 and both flags False), ``SAME_STEP`` (the reset
observation is returned at once and the last one is in ``infos["final_obs"]``) or ``DISABLED`` (reset
finished copies yourself with ``reset(options={"reset_mask": mask})``).
"""
from __future__ import annotations

from typing import Any

import numpy as np
from gymnasium.vector import AutoresetMode, VectorEnv
from gymnasium.vector.utils import batch_space

from .compensator import CompensatorGainsEnv
from .winch import WinchPayoutEnv

__all__ = ["TowVectorEnv", "CompensatorGainsVectorEnv", "WinchPayoutVectorEnv"]


class TowVectorEnv(VectorEnv):
    """``num_envs`` copies of ``env_class(**env_kwargs)`` (every copy gets the same keywords).

    ``batch_infos=False`` skips building the per-step info dict (a few µs per copy); episode-level
    keys (``failure``, ``termination``, ``final_obs``/``final_info``) are still reported."""

    metadata = {"render_modes": ["rgb_array"], "render_fps": 10, "autoreset_mode": AutoresetMode.NEXT_STEP}
    env_class: type | None = None

    def __init__(self, num_envs: int = 1, *, env_class: type | None = None,
                 autoreset_mode: AutoresetMode | str = AutoresetMode.NEXT_STEP, render_mode: str | None = None,
                 batch_infos: bool = True, **env_kwargs: Any):
        cls = env_class or self.env_class
        if cls is None:
            raise ValueError("TowVectorEnv: give env_class (or use a subclass)")
        if int(num_envs) < 1:
            raise ValueError(f"num_envs must be >= 1 (got {num_envs!r})")
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"vector environments render only 'rgb_array' (got {render_mode!r})")
        self.autoreset_mode = AutoresetMode(autoreset_mode)
        self.num_envs = int(num_envs)
        self.envs = [cls(render_mode=render_mode, **env_kwargs) for _ in range(self.num_envs)]
        e0 = self.envs[0]
        self.single_observation_space = e0.observation_space
        self.single_action_space = e0.action_space
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        self.metadata = dict(self.metadata, autoreset_mode=self.autoreset_mode,
                             render_fps=e0.metadata["render_fps"])
        self.render_mode = render_mode
        self.batch_infos = bool(batch_infos)
        self.dt = e0.dt
        n = self.num_envs
        self._obs = np.zeros((n,) + self.single_observation_space.shape, np.float32)
        self._rew = np.zeros(n)
        self._term = np.zeros(n, bool)
        self._trunc = np.zeros(n, bool)
        self._autoreset = np.zeros(n, bool)

    # ------------------------------------------------------------------
    def reset(self, *, seed: int | list[int | None] | None = None, options: dict | None = None):
        n = self.num_envs
        if seed is None:
            seeds = [None] * n
        elif isinstance(seed, (int, np.integer)):
            seeds = [int(seed) + i for i in range(n)]
        else:
            seeds = list(seed)
            if len(seeds) != n:
                raise ValueError(f"reset: {len(seeds)} seeds given for num_envs={n}")
        options = dict(options or {})
        mask = options.pop("reset_mask", None)
        if mask is None:
            mask = np.ones(n, bool)
        else:
            mask = np.asarray(mask)
            if mask.shape != (n,) or mask.dtype != np.bool_ or not mask.any():
                raise ValueError(f"options['reset_mask'] must be a bool array of shape ({n},) with a True entry")
        infos: dict[str, Any] = {}
        for i in np.flatnonzero(mask):
            self._obs[i], info = self.envs[i].reset(seed=seeds[i], options=options)
            infos = self._add_info(infos, info, int(i))
        self._term[mask] = False
        self._trunc[mask] = False
        self._autoreset[mask] = False
        return self._obs.copy(), infos

    def step(self, actions):
        actions = np.asarray(actions, dtype=np.float32).reshape((self.num_envs,) + self.single_action_space.shape)
        infos: dict[str, Any] = {}
        mode = self.autoreset_mode
        for i, env in enumerate(self.envs):
            if mode == AutoresetMode.NEXT_STEP and self._autoreset[i]:
                self._obs[i], info = env.reset()
                self._rew[i] = 0.0
                self._term[i] = self._trunc[i] = False
            else:
                if mode == AutoresetMode.DISABLED and self._autoreset[i]:
                    raise RuntimeError(f"sub-environment {i} finished: reset it with options={{'reset_mask': ...}}")
                self._obs[i], self._rew[i], self._term[i], self._trunc[i], info = env.step(actions[i])
                if mode == AutoresetMode.SAME_STEP and (self._term[i] or self._trunc[i]):
                    infos = self._add_info(infos, {"final_obs": self._obs[i].copy(), "final_info": info}, i)
                    self._obs[i], info = env.reset()
            if self.batch_infos:
                infos = self._add_info(infos, info, i)
            else:
                extra = {k: info[k] for k in ("failure", "termination") if k in info}
                if extra:
                    infos = self._add_info(infos, extra, i)
        if mode == AutoresetMode.SAME_STEP:
            self._autoreset[:] = False
        else:
            self._autoreset = self._term | self._trunc
        return self._obs.copy(), self._rew.copy(), self._term.copy(), self._trunc.copy(), infos

    def render(self):
        return tuple(env.render() for env in self.envs)

    def close_extras(self, **kwargs):
        for env in self.envs:
            env.close()

    # ------------------------------------------------------------------ SyncVectorEnv-style helpers
    def call(self, name: str, *args, **kwargs) -> tuple:
        out = []
        for env in self.envs:
            f = getattr(env, name)
            out.append(f(*args, **kwargs) if callable(f) else f)
        return tuple(out)

    def get_attr(self, name: str) -> tuple:
        return tuple(getattr(env, name) for env in self.envs)

    def set_attr(self, name: str, values) -> None:
        if not isinstance(values, (list, tuple)):
            values = [values] * self.num_envs
        for env, v in zip(self.envs, values, strict=True):
            setattr(env, name, v)


class CompensatorGainsVectorEnv(TowVectorEnv):
    """Vector entry point of ``towenv/CompensatorGains-v0``."""
    env_class = CompensatorGainsEnv


class WinchPayoutVectorEnv(TowVectorEnv):
    """Vector entry point of ``towenv/WinchPayout-v0``."""
    env_class = WinchPayoutEnv
