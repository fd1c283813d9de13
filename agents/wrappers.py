"""Environment wrappers for training (referenced by name from the hyperparameter YAML's ``env_wrapper``).

:class:`ResidualAction` — residual policy learning: the agent's action is added (scaled) to a baseline
controller's action, ``a_env = clip(a_base(obs) + scale · a_agent, -1, 1)``. The agent sees the
environment's own observations; the baseline is one of :mod:`agents.baselines` with its parameters
given in the wrapper keywords (stored in the policy zip's metadata, so evaluation rebuilds exactly the
same controller). With ``a_agent = 0`` the wrapped environment behaves as the baseline.
"""
from __future__ import annotations

import gymnasium as gym
import numpy as np

__all__ = ["ResidualAction"]


class ResidualAction(gym.Wrapper):
    """Residual action on top of a baseline controller.

    Parameters
    ----------
    base : ``"pd_ff"`` (WinchPayout: gains ``gains``, fixed for every sea state) or ``"fixed_passive"``
        (CompensatorGains: ``stiffness``/``damping``).
    scale : the agent's action is multiplied by this before it is added.
    gains, stiffness, damping : the baseline's parameters.
    """

    def __init__(self, env, base: str = "pd_ff", scale: float = 0.3, gains: dict | None = None,
                 stiffness: float | None = None, damping: float | None = None):
        super().__init__(env)
        from .baselines import FixedPassive, PDFeedForwardWinch
        if base == "pd_ff":
            self.base = PDFeedForwardWinch(env, gains=gains, name="pd_ff_fixed")
        elif base == "fixed_passive":
            self.base = FixedPassive(env, stiffness, damping)
        else:
            raise ValueError(f"ResidualAction: unsupported base {base!r}")
        self.scale = float(scale)
        self._obs = None
        self._start = True

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self._obs = obs
        self._start = True
        return obs, info

    def step(self, action):
        a_base, _ = self.base.predict(self._obs, episode_start=np.array([self._start]))
        self._start = False
        a = np.clip(np.asarray(a_base, np.float32).reshape(-1)
                    + self.scale * np.asarray(action, np.float32).reshape(-1), -1.0, 1.0)
        obs, r, term, trunc, info = self.env.step(a)
        self._obs = obs
        return obs, r, term, trunc, info
