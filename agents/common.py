"""Small shared helpers: named observation channels, sea-state keys, environment ids."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["COMPENSATOR_ID", "WINCH_ID", "ObsReader", "sea_key", "sea_label", "nearest_key", "env_kind",
           "short_env_name"]

COMPENSATOR_ID = "towenv/CompensatorGains-v0"
WINCH_ID = "towenv/WinchPayout-v0"


def env_kind(env) -> str:
    """``"compensator"`` or ``"winch"`` for an env (wrapped or not) or an env id."""
    if isinstance(env, str):
        s = env
    else:
        s = type(getattr(env, "unwrapped", env)).__name__
    s = s.lower()
    if "compensator" in s:
        return "compensator"
    if "winch" in s:
        return "winch"
    raise ValueError(f"not a towenv CompensatorGains/WinchPayout environment: {env!r}")


def short_env_name(env_id: str) -> str:
    """``towenv/WinchPayout-v0`` -> ``WinchPayout-v0``."""
    return env_id.split("/")[-1].split(":")[-1]


class ObsReader:
    """Decode an observation vector of a :class:`towenv.envs.base.TowEnv` into named channels in their
    *physical* units (``obs × channel.scale``), e.g. ``reader(obs, "fish_heave")`` in m.

    Built from ``env.unwrapped.observer`` (its channel ``names`` and ``layout``), so it follows any
    ``observations=`` keyword the environment was made with. Vector channels (``last_action``,
    ``wave_preview``) return arrays."""

    def __init__(self, env):
        from towenv.envs.pieces import CHANNELS
        ob = env.unwrapped.observer
        self.names = list(ob.names)
        self._slices: dict[str, tuple[slice, float, bool]] = {}
        for name, (src, start, width) in zip(ob.names, ob.layout):
            scale = CHANNELS[name].scale
            self._slices[name] = (slice(start, start + width), float(scale), src in ("last_action", "wave_preview"))
        self.size = int(ob.size)

    def has(self, name: str) -> bool:
        return name in self._slices

    def __call__(self, obs, name: str, default: float | None = None):
        if name not in self._slices:
            if default is not None:
                return default
            raise KeyError(f"observation channel {name!r} not observed (channels: {self.names}); "
                           f"make the environment with observations=[..., {name!r}]")
        sl, scale, vec = self._slices[name]
        o = np.asarray(obs, dtype=float).reshape(-1)
        v = o[sl] * scale
        return v if vec else float(v[0])

    def batch(self, obs, name: str) -> np.ndarray:
        """A scalar channel for a batch of observations ``(n, size)``: ``(n,)`` float64 in physical units (the
        same arithmetic as :meth:`__call__` row by row)."""
        sl, scale, vec = self._slices[name]
        if vec:
            raise ValueError(f"batch(): channel {name!r} is a vector channel")
        return np.asarray(obs)[:, sl.start].astype(float) * scale


def sea_key(sea) -> str:
    """A stable text key of a sea state: ``"hs1.88_tp5.90"`` (heading not included: the baselines are
    tuned per (Hs, Tp) over the evaluation headings)."""
    return f"hs{float(sea.hs):.2f}_tp{float(sea.tp):.2f}"


def sea_label(sea, code: int | None = None) -> str:
    c = f"code {code}: " if code is not None else ""
    return f"{c}Hs {float(sea.hs):.2f} m, Tp {float(sea.tp):.2f} s"


def parse_key(key: str) -> tuple[float, float]:
    a, b = key.split("_")
    return float(a[2:]), float(b[2:])


def nearest_key(table: dict[str, Any], sea) -> str:
    """The key of ``table`` (``sea_key`` strings) nearest to ``sea`` in (log Hs, log Tp)."""
    if not table:
        raise ValueError("empty table")
    hs, tp = max(float(sea.hs), 1e-3), max(float(sea.tp), 1e-3)

    def dist(k):
        h, t = parse_key(k)
        return (math.log(h / hs)) ** 2 + (math.log(t / tp)) ** 2

    return min(table, key=dist)
