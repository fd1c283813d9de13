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

__all__ = ["ResidualAction", "ResidualVecAction", "GainScheduleAction", "GainScheduleVecAction", "make_base",
           "GAIN_NAMES"]

#: the along-cable gains a gain-scheduling policy modulates: multiplicatively (× exp(spread·a)) except k_d
#: (added: spread·a·0.5 m/s per m/s, it changes sign in the tuned tables)
GAIN_NAMES = ("g_ff", "tau", "kl", "kp", "kd")


def scheduled_gains(g0: dict, a, spread: float) -> dict:
    """The along-cable gains ``g0`` modulated by an action ``a`` ∈ [-1, 1]^5 (order :data:`GAIN_NAMES`)."""
    a = np.clip(np.nan_to_num(np.asarray(a, float).reshape(-1), nan=0.0), -1.0, 1.0)
    g = dict(g0)
    for i, n in enumerate(GAIN_NAMES):
        g[n] = g0[n] + 0.5 * spread * a[i] if n == "kd" else g0[n] * float(np.exp(spread * a[i]))
    return g


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


class GainScheduleAction(gym.Wrapper):
    """Gain-scheduling policy on the along-cable law (WinchPayout): the agent's action a ∈ [-1, 1]^5 modulates the
    law's gains every control step — g_ff, τ, k_l, k_p multiplied by exp(spread·a_i), k_d shifted by
    0.5·spread·a — around the tuned per-sea-state gains (``table``) or fixed ``gains``; the law then computes the
    payout speed from the observation. a = 0 is the baseline itself; every action is a stable, centred law, so
    exploration cannot random-walk the winch off its travel."""

    def __init__(self, env, spread: float = 0.5, gains: dict | None = None, table: str | dict | None = None):
        super().__init__(env)
        self.base = make_base(env, "along_cable", gains=gains, table=table)
        self.spread = float(spread)
        self.action_space = gym.spaces.Box(-1.0, 1.0, (len(GAIN_NAMES),), np.float32)
        self._obs = None
        self._start = True

    def reset(self, **kwargs):
        obs, info = self.env.reset(**kwargs)
        self._obs = obs
        self._start = True
        return obs, info

    def env_action(self, action):
        if self._start:
            self.base.predict(self._obs, episode_start=np.array([True]))      # picks the sea state's gains
            self._start = False
        g = scheduled_gains(self.base.g, action, self.spread)
        v = self.base.velocity(self._obs, g)
        return np.array([min(max(v / self.base.vmax, -1.0), 1.0)], np.float32)

    def step(self, action):
        obs, r, term, trunc, info = self.env.step(self.env_action(action))
        self._obs = obs
        return obs, r, term, trunc, info


class GainScheduleVecAction:
    """:class:`GainScheduleAction` for a batched SB3 ``VecEnv`` (one base law per copy)."""

    def __new__(cls, venv, **kw):
        from stable_baselines3.common.vec_env import VecEnvWrapper

        class _Sched(VecEnvWrapper):
            def __init__(self, venv, spread=0.5, gains=None, table=None):
                super().__init__(venv, action_space=gym.spaces.Box(-1.0, 1.0, (len(GAIN_NAMES),), np.float32))
                self.bases = [make_base(e, "along_cable", gains=gains, table=table) for e in venv.envs]
                self.spread = float(spread)
                self._obs = None
                self._start = np.ones(venv.num_envs, bool)

            def reset(self):
                self._obs = self.venv.reset()
                self._start[:] = True
                return self._obs

            def step_async(self, actions):
                a = np.asarray(actions, np.float32).reshape(self.num_envs, -1)
                out = np.empty((self.num_envs, 1), np.float32)
                for i, b in enumerate(self.bases):
                    if self._start[i]:
                        b.predict(self._obs[i], episode_start=np.array([True]))
                    g = scheduled_gains(b.g, a[i], self.spread)
                    out[i, 0] = min(max(b.velocity(self._obs[i], g) / b.vmax, -1.0), 1.0)
                self._start[:] = False
                self.venv.step_async(out)

            def step_wait(self):
                obs, rew, dones, infos = self.venv.step_wait()
                self._obs = obs
                self._start[:] = dones
                return obs, rew, dones, infos

        return _Sched(venv, **kw)
