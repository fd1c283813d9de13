"""Causal linear predictor of the tow point's along-cable motion (feature set "v2q" of ``agents/ars.py``).

The WinchPayout residual policies see the MRU's along-cable velocity, acceleration and displacement over the last
2 s. This predictor turns the last 10 s of the MRU's motion into the same three channels 0.2, 0.4, …, 2.0 s
*ahead*: a per-sea-state linear map (ridge regression) from the history of :data:`PRED_CHANNELS` sampled every
0.2 s (51 lags × 7 channels + a constant) to the 30 future values, scaled as the v2 features. It is fitted once,
on episodes run under the tuned along-cable law on **predictor-fit wave seeds** ``1000·code + j + 97000 +
10·replicate`` (disjoint from every evaluation, final, tuning, validation, training, probe and teacher seed;
tested), and stored inside the policy file, so a "v2q" policy is a fixed causal function of its observations:
it only reads the past (tested). The held-out R² (the last replicate left out of the fit) is in its metadata and
printed by ``python -m agents.predictor``.

    python -m agents.predictor --out agents/trained/predictor_WinchPayout-v0.npz     # ~1 min (12 entries × 6 seeds)

The same construction predicts the tow point's *vertical* motion for the semi-active compensator (feature set "hq"
of ``agents/ars_compensator.py``): :data:`COMP_PRED_CHANNELS` (the MRU's vertical velocity, acceleration and
heave, all three predicted), fitted on the same predictor-fit wave seeds under the tuned skyhook law:

    python -m agents.predictor --env towenv/CompensatorGains-v0 --out agents/trained/predictor_CompensatorGains-v0.npz
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

__all__ = ["Predictor", "fit_predictor", "predictor_seed", "check_channels", "from_policy_file", "load_option", "push", "LEADS", "PRED_CHANNELS", "COMP_PRED_CHANNELS",
           "PRED_LAGS", "PREDICTOR_SEED_OFFSET", "main"]

#: prediction leads in control steps (0.2 … 2.0 s ahead)
LEADS = tuple(range(2, 21, 2))
#: channels the predictor reads (the three along-cable ones first: they are what it predicts) and its lags in
#: control steps (0 … 10 s back, every 0.2 s)
PRED_CHANNELS = ("tow_vel_along", "tow_acc_along", "tow_disp_along", "tow_vel_x", "tow_vel_z", "tow_acc_x", "tow_acc_z")
PRED_LAGS = tuple(range(0, 101, 2))
#: the compensator's predictor (``towenv/CompensatorGains-v0``, feature set "hq" of ``agents/ars_compensator.py``):
#: the MRU's vertical channels, all three predicted. The tow point's motion does not depend on the compensator,
#: so what the predictor sees is the same under every controller.
COMP_PRED_CHANNELS = ("tow_vel_z", "tow_acc_z", "tow_heave")
#: the channels a predictor file may read, by environment id (the first three are predicted)
CHANNELS_BY_ENV = {"towenv/WinchPayout-v0": PRED_CHANNELS, "towenv/CompensatorGains-v0": COMP_PRED_CHANNELS}
RING = max(PRED_LAGS) + 1
#: PRED_LAGS as a slice of the ring (:meth:`Predictor.design`)
_LAG_SLICE = slice(PRED_LAGS[0], PRED_LAGS[-1] + 1, PRED_LAGS[1] - PRED_LAGS[0])
if tuple(range(RING)[_LAG_SLICE]) != PRED_LAGS:
    raise RuntimeError("agents.predictor: PRED_LAGS must be an arithmetic range (Predictor.design slices the ring)")
#: wave seeds of the fitting episodes: base seed (1000·code + j) + 97000 + 10·replicate, replicate < 10
PREDICTOR_SEED_OFFSET = 97000
MAX_REPLICATES = 10


def predictor_seed(base_seed: int, replicate: int) -> int:
    """Wave seed of a predictor-fitting episode (module docstring); ValueError outside replicate 0..9."""
    if not 0 <= int(replicate) < MAX_REPLICATES:
        raise ValueError(f"replicate must be in 0..{MAX_REPLICATES - 1} (got {replicate})")
    return int(base_seed) + PREDICTOR_SEED_OFFSET + 10 * int(replicate)


def feature_names(channels=PRED_CHANNELS) -> list[str]:
    """Names of the 30 predicted features, channel-major (as the policy's preview features), of a predictor reading
    ``channels`` (default the WinchPayout one's)."""
    return [f"{c}@+{lead / 10:.1f}s(pred)" for c in tuple(channels)[:3] for lead in LEADS]


class Predictor:
    """Per-sea-state linear predictor. ``W[key]``: (len(channels)·len(PRED_LAGS) + 1, 3·len(LEADS)), keys are
    ``agents.common.sea_key`` strings; ``scales``: each channel's scale (the history ring holds channel/scale);
    ``channels``: the observation channels it reads, the first three predicted (``meta["channels"]``; default
    :data:`PRED_CHANNELS`, the WinchPayout predictor's)."""

    def __init__(self, W: dict, scales, meta: dict | None = None):
        self.W = {str(k): np.asarray(v, float) for k, v in W.items()}
        self.scales = np.asarray(scales, float)
        self.meta = dict(meta or {})
        self.channels = tuple(self.meta.get("channels") or PRED_CHANNELS)
        if len(self.channels) < 3 or tuple(self.channels) not in CHANNELS_BY_ENV.values():
            raise ValueError(f"Predictor: channels {list(self.channels)} are not one of the known sets "
                             f"{[list(c) for c in CHANNELS_BY_ENV.values()]}")
        shape = (len(self.channels) * len(PRED_LAGS) + 1, 3 * len(LEADS))
        bad = [k for k, v in self.W.items() if v.shape != shape]
        if bad or self.scales.shape != (len(self.channels),) or not np.all(self.scales > 0):
            raise ValueError(f"Predictor: weights of sea states {bad} are not {shape}, or the scales are not "
                             f"{len(self.channels)} positive numbers")

    def feature_names(self) -> list[str]:
        """Names of the predicted features (:func:`feature_names` of this predictor's channels)."""
        return feature_names(self.channels)

    # -------------------------------------------------------------- files (as arrays inside a policy .npz)
    def arrays(self, prefix: str = "predictor_") -> dict:
        keys = sorted(self.W)
        return {prefix + "keys": np.array(keys), prefix + "W": np.array([self.W[k] for k in keys]),
                prefix + "scales": self.scales, prefix + "meta": np.array(json.dumps(self.meta))}

    @classmethod
    def from_arrays(cls, z, prefix: str = "predictor_") -> "Predictor":
        return cls(dict(zip([str(k) for k in z[prefix + "keys"]], z[prefix + "W"])), z[prefix + "scales"],
                   json.loads(str(z[prefix + "meta"])))

    def save(self, path) -> Path:
        from towenv.atomic import atomic_savez
        path = Path(path)
        path.parent.mkdir(parents=True, exist_ok=True)
        atomic_savez(path, self.arrays())
        return path

    @classmethod
    def load(cls, path) -> "Predictor":
        try:
            with np.load(path, allow_pickle=False) as z:
                return cls.from_arrays(z)
        except (OSError, KeyError, ValueError) as exc:
            raise ValueError(f"{path}: not a predictor file ({type(exc).__name__}: {exc})") from None

    # -------------------------------------------------------------- use
    def sample(self, reader_values) -> np.ndarray:
        """Scaled history sample from the raw channel values (…, len(channels))."""
        return np.asarray(reader_values, float) / self.scales

    @staticmethod
    def design(ring) -> np.ndarray:
        """(n, len(channels)·len(PRED_LAGS) + 1) regressors from rings (n, channels, RING), newest first. The lags
        are an arithmetic range, so the copy is one strided slice into the preallocated matrix (the same values and
        layout as gathering ``ring[:, :, list(PRED_LAGS)]``, ~15x faster for a training batch)."""
        ring = np.asarray(ring, float)
        n, c = ring.shape[:2]
        L = len(PRED_LAGS)
        X = np.empty((n, c * L + 1))
        lagged = np.lib.stride_tricks.as_strided(X, shape=(n, c, L), strides=(X.strides[0], L * X.itemsize,
                                                                                X.itemsize))
        lagged[...] = ring[:, :, _LAG_SLICE]
        X[:, -1] = 1.0
        return X

    def predict(self, ring, keys) -> np.ndarray:
        """(n, 3·len(LEADS)) predictions for history rings (n, channels, RING) of copies in sea states ``keys``
        (keys of :attr:`W`)."""
        X = self.design(ring)
        out = np.zeros((X.shape[0], 3 * len(LEADS)))
        keys = np.asarray(keys)
        for k in np.unique(keys):
            m = keys == k
            out[m] = X[m] @ self.W[str(k)]
        return out


def check_channels(predictor, expected, what: str) -> None:
    """ValueError unless ``predictor`` (if any) reads the channels ``expected`` (a value of :data:`CHANNELS_BY_ENV`),
    naming both lists: a policy class accepts only the predictor of its own environment."""
    if predictor is not None and tuple(predictor.channels) != tuple(expected):
        env = next(k for k, v in CHANNELS_BY_ENV.items() if v == tuple(expected))
        raise ValueError(f"{what}: the predictor reads {list(predictor.channels)}, not the {env} predictor's "
                         f"{list(expected)} (fit it with python -m agents.predictor --env {env})")


def from_policy_file(path, feature_set: str) -> "Predictor":
    """The predictor stored in a policy file of a predicted feature set; ValueError naming the file if it has none
    that can be read."""
    try:
        with np.load(path, allow_pickle=False) as z:
            return Predictor.from_arrays(z)
    except (KeyError, ValueError) as exc:
        raise ValueError(f"{path}: feature set {feature_set!r} but no readable predictor in the file "
                         f"({type(exc).__name__}: {exc})") from None


def load_option(ap, path, option: str = "--predictor"):
    """The predictor file given to a command-line ``option`` (None when not given); a usage error of the argparse
    parser ``ap`` (exit 2) naming the option when the file is missing or not a predictor file."""
    if not path:
        return None
    try:
        return Predictor.load(path)
    except (OSError, ValueError) as e:
        ap.error(f"{option}: {e}")


def shared_predictor(policies):
    """The one predictor the v2q policies among ``policies`` carry (equal weights), None if none carries one;
    ValueError if they carry different ones (one batch can apply only one)."""
    found = {tuple((k, v.tobytes()) for k, v in sorted(p.predictor.W.items())): p.predictor
             for p in policies if getattr(p, "predictor", None) is not None}
    if len(found) > 1:
        raise ValueError("the v2q policies carry different predictors (compare them in separate runs)")
    return next(iter(found.values()), None)


def push(ring, sample, first: bool):
    """The history ring (n, channels, RING), newest first, after ``sample`` (n, channels); filled with the first
    sample at an episode start (as the policy's 2 s ring)."""
    if first or ring is None:
        return np.repeat(sample[:, :, None], RING, axis=2)
    ring = np.roll(ring, 1, axis=2)
    ring[:, :, 0] = sample
    return ring


def record_channels(seas, seeds, channels, episode_seconds=None) -> np.ndarray:
    """(T, n, len(channels)) raw channel values of each (sea state, wave seed) episode run under the tuned
    along-cable law, one batched rollout."""
    from towenv.envs.vector import WinchPayoutVectorEnv
    from . import ars
    from .baselines import load_tuned
    from .common import reset_copies
    kw = {} if episode_seconds is None else {"episode_seconds": float(episode_seconds)}
    rv = WinchPayoutVectorEnv(num_envs=len(seas), autoreset_mode="NextStep", batch_infos=True, **kw)
    obs = reset_copies(rv, list(seas), seeds)
    rb = ars._Batch(rv, dict(load_tuned()["along_cable"]), dict(ars.FEATURE_SCALES), "v2")
    rb.set_seas(list(seas))
    T = rv.envs[0].max_steps
    X = np.zeros((T, len(seas), len(channels)))
    for k in range(T):
        X[k] = np.stack([rb.ch(obs, c) for c in channels], axis=1)
        obs, *_ = rv.step(rb.base_action(obs).astype(np.float32)[:, None])
    rv.close()
    return X


def record_compensator_channels(seas, seeds, channels, episode_seconds=None) -> np.ndarray:
    """(T, n, len(channels)) raw channel values of each (sea state, wave seed) CompensatorGains episode run under the
    tuned skyhook law, one batched rollout (the tow point's motion does not depend on the controller)."""
    from towenv.envs.vector import CompensatorGainsVectorEnv
    from . import ars_compensator as arc
    from .baselines import load_tuned
    from .common import reset_copies
    kw = {} if episode_seconds is None else {"episode_seconds": float(episode_seconds)}
    rv = CompensatorGainsVectorEnv(num_envs=len(seas), autoreset_mode="NextStep", batch_infos=True, **kw)
    obs = reset_copies(rv, list(seas), seeds)
    rb = arc._Batch(rv, dict(load_tuned()["skyhook"]), dict(arc.FEATURE_SCALES))
    rb.set_seas(list(seas))
    T = rv.envs[0].max_steps
    X = np.zeros((T, len(seas), len(channels)))
    for k in range(T):
        X[k] = np.stack([rb.reader.batch(obs, c) for c in channels], axis=1)
        obs, *_ = rv.step(rb.base_action(obs).astype(np.float32))
    rv.close()
    return X


def fit_predictor(replicates: int = 6, ridge: float = 1e-6, discard: float = 60.0, episode_seconds=None,
                  entries=None, log=print, env_id: str = "towenv/WinchPayout-v0") -> Predictor:
    """Fit the predictor per sea state on the evaluation entries (default all 12) × ``replicates`` predictor-fit wave
    seeds (under the along-cable law for WinchPayout, the skyhook law for CompensatorGains); logs the held-out R²
    (fitted without the last replicate, tested on it), then refits on all. ``ridge`` is relative to the number of
    samples. ``env_id``: a key of :data:`CHANNELS_BY_ENV` (its channels; the scales are the policy features')."""
    import gymnasium as gym

    import towenv  # noqa: F401  (registers the ids)
    from .common import sea_key
    if env_id not in CHANNELS_BY_ENV:
        raise ValueError(f"env_id must be one of {sorted(CHANNELS_BY_ENV)} (got {env_id!r})")
    if not 2 <= int(replicates) <= MAX_REPLICATES:
        raise ValueError(f"replicates must be in 2..{MAX_REPLICATES} (got {replicates})")
    if not (math.isfinite(ridge) and ridge > 0):
        raise ValueError(f"ridge must be a positive number (got {ridge})")
    channels = CHANNELS_BY_ENV[env_id]
    if env_id == "towenv/WinchPayout-v0":
        from . import ars
        known, record = ars.FEATURE_SCALES, record_channels
    else:
        from . import ars_compensator as arc
        known, record = arc.FEATURE_SCALES, record_compensator_channels
    env = gym.make(env_id)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    idx = range(len(ev)) if entries is None else [int(i) for i in entries]
    ents = [(ev[i][0], predictor_seed(ev[i][1], r), r) for r in range(int(replicates)) for i in idx]
    X = record([e[0] for e in ents], [e[1] for e in ents], channels, episode_seconds)
    d0 = int(round(10 * discard))
    if X.shape[0] - d0 < RING + max(LEADS) + 10:
        raise ValueError(f"episode_seconds too short for a {RING / 10:g} s history after {discard:g} s")
    scales = np.array([known[c] if c in known else float(X[d0:, :, j].std())
                       for j, c in enumerate(channels)])
    X = X / scales
    t = np.arange(max(d0, RING - 1), X.shape[0] - max(LEADS))
    ring = np.stack([X[t - lag] for lag in range(RING)], axis=3)                                   # (nt, n, ch, RING)
    Y = np.stack([X[t + lead][:, :, :3] for lead in LEADS], axis=3).reshape(len(t), X.shape[1], -1)  # (nt, n, 3·leads)
    keys = np.array([sea_key(e[0]) for e in ents])
    reps = np.array([e[2] for e in ents])
    meta = {"env_id": env_id, "replicates": int(replicates), "ridge": float(ridge), "discard": float(discard),
            "seeds": f"1000*code + j + {PREDICTOR_SEED_OFFSET} + 10*replicate", "channels": list(channels),
            "lags": list(PRED_LAGS), "leads": list(LEADS), "r2_heldout": {}}

    def stack(m):
        cols = np.flatnonzero(m)
        return (np.concatenate([Predictor.design(ring[:, i]) for i in cols]),
                np.concatenate([Y[:, i] for i in cols]))

    W = {}
    for k in sorted(set(keys)):
        A, B = stack((keys == k) & (reps < replicates - 1))
        w = np.linalg.solve(A.T @ A + ridge * len(A) * np.eye(A.shape[1]), A.T @ B)
        A, B = stack((keys == k) & (reps == replicates - 1))
        r2 = (1 - ((B - A @ w) ** 2).mean(axis=0) / B.var(axis=0)).reshape(3, len(LEADS))
        meta["r2_heldout"][k] = r2.round(4).tolist()
        log(f"  {k}: held-out R² at +{LEADS[0] / 10:.1f} / +1.0 / +{LEADS[-1] / 10:.1f} s: "
            + "; ".join(f"{c} {r2[j, 0]:.3f} / {r2[j, LEADS.index(10)]:.3f} / {r2[j, -1]:.3f}"
                        for j, c in enumerate(channels[:3])))
        A, B = stack(keys == k)
        W[k] = np.linalg.solve(A.T @ A + ridge * len(A) * np.eye(A.shape[1]), A.T @ B)
    return Predictor(W, scales, meta)


def main(argv=None) -> int:
    import argparse
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--replicates", type=int, default=6, help="wave seeds per evaluation entry (2..10; the last is "
                                                             "held out for the printed R²)")
    ap.add_argument("--ridge", type=float, default=1e-6, help="ridge, relative to the number of samples")
    ap.add_argument("--episode-seconds", type=float, default=None, help="episode length (default: the environment's)")
    ap.add_argument("--env", default="towenv/WinchPayout-v0", choices=sorted(CHANNELS_BY_ENV),
                    help="environment whose tow-point motion to predict (default towenv/WinchPayout-v0)")
    ap.add_argument("--out", required=True, help="predictor file to write (.npz)")
    a = ap.parse_args(argv)
    try:
        pred = fit_predictor(a.replicates, a.ridge, episode_seconds=a.episode_seconds, env_id=a.env)
    except ValueError as exc:
        ap.error(str(exc))
    pred.save(a.out)
    print(f"wrote {a.out}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
