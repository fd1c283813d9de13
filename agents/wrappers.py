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

__all__ = ["ResidualAction", "ResidualVecAction", "make_base"]


def make_base(env, base: str, gains: dict | None = None, stiffness: float | None = None,
              damping: float | None = None, table: str | dict | None = None):
    """The baseline controller of a residual policy, bound to ``env`` (a single environment):
    ``pd_ff`` / ``along_cable`` (WinchPayout) or ``fixed_passive`` / ``skyhook`` (CompensatorGains).
    ``gains`` fixes one gain set for every sea state; ``table="tuned"`` uses the tuned per-sea-state table of
    ``agents/hyperparams/baselines.yml`` (a gain-scheduled base, as the baseline itself)."""
    from .baselines import FixedPassive, PDFeedForwardWinch, load_tuned
    from .classical import AlongCableWinch, SkyhookCompensator
    tab = load_tuned().get(base) if table == "tuned" else table
    if base == "pd_ff":
        return PDFeedForwardWinch(env, gains=gains, table=tab, name="pd_ff_base")
    if base == "along_cable":
        return AlongCableWinch(env, gains=gains, table=tab, name="along_cable_base")
    if base == "skyhook":
        return SkyhookCompensator(env, gains=gains, table=tab, name="skyhook_base")
    if base == "fixed_passive":
        return FixedPassive(env, stiffness, damping)
    raise ValueError(f"ResidualAction: unsupported base {base!r} (pd_ff, along_cable, skyhook, fixed_passive)")


class ResidualAction(gym.Wrapper):
    """Residual action on top of a baseline controller.

    Parameters
    ----------
    base : ``"pd_ff"`` / ``"along_cable"`` (WinchPayout) or ``"fixed_passive"`` / ``"skyhook"``
        (CompensatorGains); see :func:`make_base`.
    scale : the agent's action is multiplied by this before it is added.
    gains, stiffness, damping, table : the baseline's parameters (``table="tuned"``: per sea state).
    """

    def __init__(self, env, base: str = "pd_ff", scale: float = 0.3, gains: dict | None = None,
                 stiffness: float | None = None, damping: float | None = None, table: str | dict | None = None):
        super().__init__(env)
        self.base = make_base(env, base, gains, stiffness, damping, table)
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


class ResidualVecAction:
    """The same residual action for a batched SB3 ``VecEnv`` (:class:`towenv.envs.sb3.TowSB3VecEnv`): one base
    controller per copy (bound to copy i's environment, so a gain-scheduled base reads that copy's sea state),
    ``a = clip(a_base_i(obs_i) + scale · a_agent_i, −1, 1)``. Same keywords as :class:`ResidualAction`, so a
    policy trained on the batched env is evaluated with :class:`ResidualAction` on single environments."""

    def __new__(cls, venv, **kw):
        from stable_baselines3.common.vec_env import VecEnvWrapper

        class _Residual(VecEnvWrapper):
            def __init__(self, venv, base="pd_ff", scale=0.3, gains=None, stiffness=None, damping=None, table=None):
                super().__init__(venv)
                self.bases = [make_base(e, base, gains, stiffness, damping, table) for e in venv.envs]
                self.scale = float(scale)
                self._obs = None
                self._start = np.ones(venv.num_envs, bool)

            def reset(self):
                self._obs = self.venv.reset()
                self._start[:] = True
                return self._obs

            def step_async(self, actions):
                a = np.asarray(actions, np.float32).reshape(self.num_envs, -1)
                out = np.empty_like(a)
                for i, b in enumerate(self.bases):
                    ab, _ = b.predict(self._obs[i], episode_start=np.array([self._start[i]]))
                    out[i] = np.clip(np.asarray(ab, np.float32).reshape(-1) + self.scale * a[i], -1.0, 1.0)
                self._start[:] = False
                self.venv.step_async(out)

            def step_wait(self):
                obs, rew, dones, infos = self.venv.step_wait()
                self._obs = obs
                self._start[:] = dones          # the next step of a finished copy starts a new episode
                return obs, rew, dones, infos

        return _Residual(venv, **kw)
