"""Small shared helpers: named observation channels, sea-state keys, environment ids."""
from __future__ import annotations

import math
from typing import Any

import numpy as np

__all__ = ["weights_by_name", "COMPENSATOR_ID", "WINCH_ID", "ObsReader", "sea_key", "sea_label", "nearest_key", "env_kind",
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


def reset_copies(venv, seas, seeds):
    """Reset copy i of the batched vector env ``venv`` into (seas[i], seeds[i]) — one masked reset per copy, as
    the ARS trainings (agents/ars.py, agents/ars_compensator.py) need; returns the observations after the last."""
    n = venv.num_envs
    seeds = [int(s) for s in seeds]
    obs = None
    for i in range(n):
        mask = np.zeros(n, bool)
        mask[i] = True
        obs, _ = venv.reset(seed=seeds, options={"sea_state": seas[i], "sea_seed": seeds[i], "reset_mask": mask})
    return obs


def weights_by_name(init_theta: dict, keys, init_names: list, names: list, lead: tuple = ()) -> np.ndarray:
    """Weights (len(keys), *lead, len(names)) for the feature list ``names``, copied by feature name from
    ``init_theta`` (sea-state key -> (*lead, len(init_names)) array; None: all zeros); features ``init_names`` lacks
    start at 0. ValueError naming the sea states ``init_theta`` has no weights for (a warm start of the linear
    residual searches, agents/gn.py and agents/gn_compensator.py)."""
    theta = np.zeros((len(keys),) + tuple(lead) + (len(names),))
    if init_theta is None:
        return theta
    missing = [k for k in keys if k not in init_theta]
    if missing:
        raise ValueError(f"init: the initial policy has no weights for sea states {missing}")
    cols = [(i, init_names.index(nm)) for i, nm in enumerate(names) if nm in init_names]
    dst, src = [i for i, _ in cols], [j for _, j in cols]
    for c, k in enumerate(keys):
        theta[c][..., dst] = np.asarray(init_theta[k], float)[..., src]
    return theta


def save_ars_file(path, theta: dict, base_table: dict, scales: dict, meta: dict, extra: dict | None = None):
    """Write an ARS policy file (.npz, atomically): weights per sea-state key, the base law's gain table, the
    feature scales, the metadata JSON and ``extra`` arrays (e.g. a v2q policy's predictor). Returns the path."""
    import json
    from pathlib import Path
    from towenv.atomic import atomic_savez
    path = Path(path)
    keys = sorted(theta)
    path.parent.mkdir(parents=True, exist_ok=True)
    atomic_savez(path, {"theta": np.array([theta[k] for k in keys]), "keys": np.array(keys),
                        "base_table": np.array(json.dumps(base_table)), "scales": np.array(json.dumps(scales)),
                        "meta": np.array(json.dumps(meta))} | dict(extra or {}))
    return path


def read_ars_file(path, feature_names: list, expect: dict | None = None, what: str = "this kind of ARS policy"):
    """Read an ARS policy file: (theta per key, base table, scales, meta). ValueError naming the file if it is not
    one, if its metadata differ from ``expect`` (e.g. env_id, algo: then it is not ``what``), or if its features
    differ from ``feature_names`` (a list, or a callable of the metadata giving it)."""
    import json
    from pathlib import Path
    import zipfile
    path = Path(path)
    if not path.is_file():
        raise ValueError(f"{path}: no such policy file")
    try:
        z = np.load(path, allow_pickle=False)
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise ValueError(f"{path}: not a readable ARS policy file (.npz): {type(exc).__name__}: {exc}") from None
    if not isinstance(z, np.lib.npyio.NpzFile):
        raise ValueError(f"{path}: not an ARS policy file (a single .npy array, not an .npz archive)")
    with z:
        if "theta" not in z or "keys" not in z or "meta" not in z:
            raise ValueError(f"{path}: not an ARS policy file (no theta/keys/meta)")
        try:
            meta = json.loads(str(z["meta"]))
        except (ValueError, OSError, EOFError, zipfile.BadZipFile) as exc:
            raise ValueError(f"{path}: damaged ARS policy file (its metadata cannot be read: {exc})") from None
        for k, v in (expect or {}).items():
            if meta.get(k) != v:
                raise ValueError(f"{path}: not {what} (its {k} is {meta.get(k)!r}, not {v!r})")
        if callable(feature_names):
            feature_names = feature_names(meta)
        if meta.get("features") != list(feature_names):
            raise ValueError(f"{path}: its features differ from this version's ({len(meta.get('features', []))} "
                             f"against {len(feature_names)})")
        theta = {str(k): np.array(v) for k, v in zip(z["keys"], z["theta"])}
        return theta, json.loads(str(z["base_table"])), json.loads(str(z["scales"])), meta


def add_parallel_flag(ap) -> None:
    """``--parallel`` of the ARS / Gauss–Newton trainers (one definition for the four): step the training batches on
    all numba threads; every copy is independent, so the result is the serial one bit for bit (tested per trainer)."""
    ap.add_argument("--parallel", action="store_true",
                    help="step the training batches on all numba threads (NUMBA_NUM_THREADS): the same result bit for "
                         "bit, less wall time when one run has the cores to itself")
