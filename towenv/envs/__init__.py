"""Gymnasium environments of towenv (optional extra ``.[rl]``).

Importing this module registers, idempotently (ids already in the registry are skipped, so re-imports,
notebook reloads and subprocess workers are safe):

* ``towenv/CompensatorGains-v0`` — :class:`~towenv.envs.compensator.CompensatorGainsEnv`
* ``towenv/WinchPayout-v0`` — :class:`~towenv.envs.winch.WinchPayoutEnv`

with string entry points (the environment modules are imported only by ``gym.make``) and
``vector_entry_point`` = the batched :mod:`towenv.envs.vector` classes (all copies stepped by one compiled
call; ``gym.make_vec(id, num_envs=N, vectorization_mode="vector_entry_point")``). The stable-baselines3
adapter is :class:`towenv.envs.sb3.TowSB3VecEnv`. No ``max_episode_steps`` is
registered: the environments truncate themselves at ``episode_seconds`` (default 300 s = 3000 steps).

Errors (:mod:`towenv.envs.checks`, docs/environments.md "Errors and validation"): an invalid constructor keyword or
``reset`` option raises :class:`ConfigError` (a ``ValueError``), a malformed action :class:`ActionError` (a
``ValueError``), and ``step`` before ``reset`` or after an episode ended :class:`ResetNeeded` (a
``gymnasium.error.ResetNeeded`` and a ``RuntimeError``).
"""
from __future__ import annotations

from gymnasium.envs.registration import register, registry

ENV_IDS = ("towenv/CompensatorGains-v0", "towenv/WinchPayout-v0")

_ENVS = (
    ("towenv/CompensatorGains-v0", "towenv.envs.compensator:CompensatorGainsEnv",
     "towenv.envs.vector:CompensatorGainsVectorEnv"),
    ("towenv/WinchPayout-v0", "towenv.envs.winch:WinchPayoutEnv", "towenv.envs.vector:WinchPayoutVectorEnv"),
)

for _id, _ep, _vep in _ENVS:
    if _id not in registry:
        register(id=_id, entry_point=_ep, vector_entry_point=_vep)

_LAZY = {
    "TowEnv": ".base", "CompensatorGainsEnv": ".compensator", "WinchPayoutEnv": ".winch",
    "TowVectorEnv": ".vector", "CompensatorGainsVectorEnv": ".vector", "WinchPayoutVectorEnv": ".vector",
    "TowSB3VecEnv": ".sb3",
    "Observer": ".pieces", "CHANNELS": ".pieces", "RandomCodeSeas": ".pieces", "FixedSeas": ".pieces",
    "HeavePitchReward": ".pieces", "HeaveOnlyReward": ".pieces", "default_eval_sea_states": ".pieces",
    "Termination": ".pieces", "Limit": ".pieces", "Limits": ".pieces", "PartedOrGrounded": ".pieces",
    "ConfigError": ".checks", "ActionError": ".checks", "ResetNeeded": ".checks",
}

__all__ = ["ENV_IDS", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        import importlib
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
