"""rl-zoo style hyperparameters, environment factories and the self-contained policy zip.

Hyperparameter files (``agents/hyperparams/<algo>.yml``) follow rl-baselines3-zoo: the top-level key is
the environment id, the values are the algorithm's constructor keywords plus the zoo's own keys::

    towenv/WinchPayout-v0:
      n_envs: 8
      n_timesteps: !!float 1e6
      policy: 'MlpPolicy'
      normalize: "{'norm_obs': True, 'norm_reward': False}"   # or true / false
      env_wrapper:                                              # optional, as in the zoo
        - gymnasium.wrappers.FrameStackObservation:
            stack_size: 4
      learning_rate: lin_3e-4                                   # lin_<x>: linear decay to 0
      policy_kwargs: "dict(net_arch=[256, 256])"
      env_kwargs: {reward_weights: {heave: 2.0}}                # extension: env constructor keywords

``env_kwargs`` is this project's extension (the zoo takes them on the command line, ``--env-kwargs``);
``scripts/train.py --env-kwargs`` overrides entries.

Policy zip: :func:`save_policy_zip` writes the SB3 model zip and appends two members that SB3's loader
ignores: ``towenv.json`` (algorithm, environment id and keywords, wrappers, training steps and time) and,
when the model was trained with ``VecNormalize``, ``vecnormalize.pkl``. :func:`load_policy` returns an
:class:`SB3Policy` that normalises observations itself, so evaluation needs neither a VecEnv nor a side
file.
"""
from __future__ import annotations

import ast
import importlib
import io
import json
import pickle
import zipfile
from pathlib import Path
from typing import Any, Callable

import numpy as np

__all__ = ["ALGOS", "load_hyperparams", "linear_schedule", "parse_normalize", "apply_wrappers", "make_env_fn",
           "save_policy_zip", "read_meta", "load_policy", "SB3Policy", "parse_env_kwargs", "HYPERPARAMS_DIR",
           "TRAINED_DIR"]

# package data (installed with the package: pip install ".[rl]")
HYPERPARAMS_DIR = Path(__file__).resolve().parent / "hyperparams"
TRAINED_DIR = Path(__file__).resolve().parent / "trained"

#: keys of the zoo's YAML that are not algorithm constructor keywords
ZOO_KEYS = ("n_envs", "n_timesteps", "policy", "normalize", "env_wrapper", "env_kwargs", "frame_stack",
            "callback", "vec_env_wrapper", "normalize_kwargs")


def _algos():
    from stable_baselines3 import A2C, DDPG, PPO, SAC, TD3
    return {"ppo": PPO, "sac": SAC, "td3": TD3, "a2c": A2C, "ddpg": DDPG}


class _LazyAlgos(dict):
    def __missing__(self, key):
        self.update(_algos())
        return dict.__getitem__(self, key)


#: algorithm name -> SB3 class (imported on first use)
ALGOS = _LazyAlgos()


def linear_schedule(initial: float) -> Callable[[float], float]:
    """The zoo's ``lin_<x>``: ``progress_remaining × x`` (1 at the start, 0 at the end)."""
    initial = float(initial)

    def f(progress_remaining: float) -> float:
        return progress_remaining * initial

    f.initial = initial          # for the metadata
    return f


def _literal(v):
    """A YAML string like ``"dict(net_arch=[64, 64])"`` or ``"{'norm_obs': True}"`` -> the object. Only
    literals, ``dict(...)`` and the activation names ``nn.Tanh``/``nn.ReLU`` are accepted (no eval)."""
    if not isinstance(v, str):
        return v
    s = v.strip()
    try:
        return ast.literal_eval(s)
    except (ValueError, SyntaxError):
        pass
    tree = ast.parse(s, mode="eval").body
    return _eval_node(tree)


def _eval_node(node):
    if isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id == "dict" and not node.args:
        return {kw.arg: _eval_node(kw.value) for kw in node.keywords}
    if isinstance(node, ast.Attribute) and isinstance(node.value, ast.Name) and node.value.id in ("nn", "th"):
        import torch.nn as nn
        return getattr(nn, node.attr)
    if isinstance(node, ast.Dict):
        return {_eval_node(k): _eval_node(v) for k, v in zip(node.keys, node.values)}
    if isinstance(node, (ast.List, ast.Tuple)):
        vals = [_eval_node(e) for e in node.elts]
        return vals if isinstance(node, ast.List) else tuple(vals)
    return ast.literal_eval(node)


def parse_normalize(v) -> dict | None:
    """The zoo's ``normalize`` value -> VecNormalize keywords or None."""
    v = _literal(v)
    if v is None or v is False:
        return None
    if v is True:
        return {"norm_obs": True, "norm_reward": True}
    if isinstance(v, dict):
        return dict(v)
    raise ValueError(f"normalize: expected a bool or a dict (got {v!r})")


def load_hyperparams(path: str | Path, env_id: str) -> dict:
    """The block of ``env_id`` in an rl-zoo YAML file, with ``lin_`` schedules and string literals parsed.

    Returns ``{"algo_kwargs": {...}, "n_envs", "n_timesteps", "policy", "normalize", "env_wrapper",
    "env_kwargs", "raw": <the block as written>}``."""
    try:
        import yaml
    except ImportError:
        raise ImportError("reading agents/hyperparams/*.yml needs PyYAML: pip install pyyaml") from None
    with open(path) as f:
        doc = yaml.safe_load(f) or {}
    if env_id not in doc:
        raise KeyError(f"{path}: no hyperparameters for {env_id!r} (has {sorted(doc)})")
    raw = dict(doc[env_id])
    out = {"raw": dict(raw), "n_envs": int(raw.get("n_envs", 1)),
           "n_timesteps": int(float(raw.get("n_timesteps", 1e5))), "policy": raw.get("policy", "MlpPolicy"),
           "normalize": parse_normalize(raw.get("normalize", False)),
           "env_wrapper": raw.get("env_wrapper") or [], "env_kwargs": dict(_literal(raw.get("env_kwargs")) or {})}
    if raw.get("frame_stack"):
        out["env_wrapper"] = list(out["env_wrapper"]) + [
            {"gymnasium.wrappers.FrameStackObservation": {"stack_size": int(raw["frame_stack"])}}]
    kw = {}
    for k, v in raw.items():
        if k in ZOO_KEYS:
            continue
        if isinstance(v, str) and v.startswith("lin_"):
            v = linear_schedule(float(v[4:]))
        elif k == "policy_kwargs" or (isinstance(v, str) and v[:1] in "{[(d"):
            v = _literal(v)
        kw[k] = v
    out["algo_kwargs"] = kw
    return out


def parse_env_kwargs(items: list[str] | None) -> dict:
    """``["episode_seconds:60", "reward_weights:{'heave': 2}"]`` -> dict (values as Python literals,
    else strings), the zoo's ``--env-kwargs`` syntax."""
    out = {}
    for it in items or []:
        if ":" not in it:
            raise ValueError(f"--env-kwargs: expected key:value (got {it!r})")
        k, v = it.split(":", 1)
        try:
            out[k] = ast.literal_eval(v)
        except (ValueError, SyntaxError):
            out[k] = v
    return out


def _wrapper_list(spec) -> list[tuple[str, dict]]:
    out = []
    for w in spec or []:
        if isinstance(w, str):
            out.append((w, {}))
        elif isinstance(w, dict):
            for name, kw in w.items():
                out.append((name, dict(kw or {})))
        else:
            raise ValueError(f"env_wrapper entries must be 'module.Class' or {{'module.Class': {{...}}}} (got {w!r})")
    return out


def apply_wrappers(env, spec):
    """Apply the zoo's ``env_wrapper`` list (``module.Class`` names with keyword dicts) in order."""
    for name, kw in _wrapper_list(spec):
        mod, cls = name.rsplit(".", 1)
        env = getattr(importlib.import_module(mod), cls)(env, **kw)
    return env


def make_env_fn(env_id: str, env_kwargs: dict | None = None, wrappers=None, seed: int | None = None,
                monitor: bool = True) -> Callable[[], Any]:
    """A picklable-enough thunk for SB3's ``DummyVecEnv``/``SubprocVecEnv``."""
    env_kwargs = dict(env_kwargs or {})

    def thunk():
        import gymnasium as gym
        import towenv.envs  # noqa: F401  (registers the ids)
        env = gym.make(env_id, **env_kwargs)
        env = apply_wrappers(env, wrappers)
        if monitor:
            from stable_baselines3.common.monitor import Monitor
            env = Monitor(env)
        if seed is not None:
            env.reset(seed=seed)
            env.action_space.seed(seed)
        return env

    return thunk


def _jsonable(v):
    if callable(v) and hasattr(v, "initial"):
        return f"lin_{v.initial:g}"
    if isinstance(v, (str, int, float, bool)) or v is None:
        return v
    if isinstance(v, dict):
        return {str(k): _jsonable(x) for k, x in v.items()}
    if isinstance(v, (list, tuple)):
        return [_jsonable(x) for x in v]
    if isinstance(v, type):
        return f"{v.__module__}.{v.__name__}"
    return repr(v)


def save_policy_zip(model, path: str | Path, meta: dict, vecnormalize=None, exclude_optimizer: bool = False) -> Path:
    """Save ``model`` (SB3) to ``path`` and append ``towenv.json`` (+ ``vecnormalize.pkl``)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    model.save(path)
    if exclude_optimizer:
        _strip_optimizer(path)
    with zipfile.ZipFile(path, "a", compression=zipfile.ZIP_DEFLATED) as zf:
        zf.writestr("towenv.json", json.dumps(_jsonable(meta), indent=2))
        if vecnormalize is not None:
            venv = vecnormalize.venv
            vecnormalize.venv = None          # VecNormalize.__getstate__ drops it too; be explicit
            try:
                zf.writestr("vecnormalize.pkl", pickle.dumps(vecnormalize))
            finally:
                vecnormalize.venv = venv
    return path


def _strip_optimizer(path: Path) -> None:
    """Drop the optimizer state dicts (``*optimizer*.pth``) from a saved SB3 zip (inference only)."""
    buf = io.BytesIO()
    with zipfile.ZipFile(path) as src, zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED) as dst:
        for item in src.infolist():
            if "optimizer" in item.filename or item.filename.startswith("ent_coef_optimizer"):
                continue
            dst.writestr(item, src.read(item.filename))
    path.write_bytes(buf.getvalue())


def read_meta(path: str | Path) -> dict:
    """The ``towenv.json`` member of a policy zip ({} if absent)."""
    with zipfile.ZipFile(path) as zf:
        if "towenv.json" not in zf.namelist():
            return {}
        return json.loads(zf.read("towenv.json").decode())


def _read_vecnormalize(path):
    with zipfile.ZipFile(path) as zf:
        if "vecnormalize.pkl" not in zf.namelist():
            return None
        vn = pickle.loads(zf.read("vecnormalize.pkl"))
    vn.training = False
    vn.norm_reward = False
    return vn


class SB3Policy:
    """An SB3 model plus its VecNormalize observation statistics, with SB3's ``predict`` signature.

    Acts on (unnormalised) observations of the environment described in ``meta`` (same wrappers)."""

    acts_on = "observations"

    def __init__(self, model, vecnormalize=None, meta: dict | None = None, name: str = "policy"):
        self.model = model
        self.vecnormalize = vecnormalize
        self.meta = dict(meta or {})
        self.name = name

    def predict(self, obs, state=None, episode_start=None, deterministic: bool = True):
        o = np.asarray(obs, dtype=np.float32)
        if self.vecnormalize is not None and self.vecnormalize.norm_obs:
            o = self.vecnormalize.normalize_obs(o).astype(np.float32)
        return self.model.predict(o, state=state, episode_start=episode_start, deterministic=deterministic)

    def reset(self, env=None):  # symmetric with the baselines
        return None


def load_policy(path: str | Path, algo: str | None = None, device: str = "cpu") -> SB3Policy:
    """Load a policy zip written by :func:`save_policy_zip` (or any SB3 zip: then give ``algo``)."""
    path = Path(path)
    meta = read_meta(path)
    algo = (algo or meta.get("algo") or "").lower()
    if not algo:
        raise ValueError(f"{path}: no towenv.json metadata; pass the algorithm (--algo ppo|sac|...)")
    if algo not in ("ppo", "sac", "td3", "a2c", "ddpg"):
        raise ValueError(f"unknown algorithm {algo!r}")
    model = ALGOS[algo].load(path, device=device)
    return SB3Policy(model, _read_vecnormalize(path), meta | {"algo": algo}, name=path.stem)
