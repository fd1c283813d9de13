"""Augmented Random Search (ARS) on a linear residual over the along-cable law, for ``towenv/WinchPayout-v0``.

PPO residual policies on the along-cable law never beat it (docs/agents.md, "What was tried"): a memoryless
policy cannot anticipate the tow point's motion, and the policy-gradient noise moves it off a sharp optimum.
The tow point's along-cable motion *is* predictable from its own recent past (a linear predictor of its
displacement from the last 3 s: R² 0.98 at 1 s ahead, 0.95 at 2 s in the code-3 sea), so the policy here
sees that past, and is trained by random search in parameter space (Mania et al. 2018, "Simple random search
provides a competitive approach to reinforcement learning": ARS V1-t, fixed feature scales, the best b of N
directions, step normalised by the rewards' standard deviation). The policy::

    a = clip(a_along(obs) + θ_c · φ(history), −1, 1)

* ``a_along`` — the along-cable law (``agents/classical.py``) with its tuned per-sea-state gains (the table is
  copied into the policy file, so retuning ``baselines.yml`` later does not change a trained policy);
* ``φ`` — :data:`HISTORY_CHANNELS` (MRU along-cable velocity, acceleration, displacement) at the lags
  :data:`LAG_STEPS` (0, 0.2, …, 2.0 s), :data:`INSTANT_CHANNELS` (winch-line length change, fish heave about its
  running mean and its rate) and a constant, each divided by a fixed scale (:data:`FEATURE_SCALES`); feature set
  ``"v2"`` (:data:`FEATURE_SETS`, the default for new training) adds six instant channels the ``"v1"`` policies
  (committed before 2026-12-03) do not see: the winch's actual speed, the policy's own last action, top tension,
  the sheave's cable angle, fish pitch about its running mean and its rate, each as (x − offset)/scale with
  :data:`EXTRA_SCALES`;
  ``"v2q"`` adds to v2, before the constant, the along-cable channels 0.2–2.0 s *ahead* as predicted by a causal
  linear predictor from the last 10 s of the MRU's motion (``agents/predictor.py``; fitted on its own wave seeds
  and stored in the policy file, :data:`PREDICTED`);
  ``"v2qa"`` adds to v2q, before the constant, hinges of the predicted along-cable *acceleration* at each lead,
  sign(a)·max(|a| − c, 0)/:data:`HINGE_SCALE` for the thresholds c of :data:`HINGES` (m/s²): the part of the coming
  motion beyond what a 1.5 m/s² winch can follow, a nonlinearity the linear v2q class cannot express (the standard
  winch's acceleration limit binds 27–34 % of the scored time under the committed v2q policy in codes 4–5);
* ``θ_c`` — one weight vector per sea state of the along-cable gain table (the same schedule as the base).

θ = 0 is the along-cable law exactly. The policy is causal: it acts on the observation vector and its own
memory of earlier observations, plus the sea-state estimate at episode start (as the base does).

Training (:func:`train`, ``python scripts/train_ars.py``) evaluates all perturbations of an iteration as one
batch of the vector environment, with common random numbers: the + and − perturbation of a direction run the
same sea states and wave seeds, and the along-cable law runs them too, so the reward of an episode is the log
ratio of its σ(fish heave) (and, weighted, σ(pitch)) to the along-cable law's on the same waves. Wave seeds are
fresh every iteration: ``1000·code + j + 40000 + 100·iteration + 100000·seed`` — never an evaluation (+0…400),
tuning (+500), validation (+700), Hover design (+900), final (+20000) or clairvoyant-teacher (+30000) seed.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from .common import ObsReader, add_parallel_flag, nearest_key
from .predictor import PRED_CHANNELS, check_channels, from_policy_file, push

__all__ = ["ARSPolicy", "train", "save_policy", "load_ars_policy", "features_single", "HISTORY_CHANNELS",
           "INSTANT_CHANNELS", "LAG_STEPS", "FEATURE_SCALES", "TRAIN_SEED_OFFSET", "feature_names", "theta_rows"]

ENV_ID = "towenv/WinchPayout-v0"
#: channels whose recent history the policy sees, and the lags (control steps of 0.1 s): 0, 0.2, …, 2.0 s
HISTORY_CHANNELS = ("tow_vel_along", "tow_acc_along", "tow_disp_along")
LAG_STEPS = tuple(range(0, 21, 2))
#: channels the policy sees at the current step only
INSTANT_CHANNELS = ("winch_length_dev", "fish_heave_dev", "fish_heave_rate")
#: fixed feature scales: each channel's standard deviation under the along-cable law on training-seed episodes
#: (all three coastal sea states pooled; measured once, kept fixed so that the policy is a fixed function)
FEATURE_SCALES = {"tow_vel_along": 0.7089, "tow_acc_along": 1.4686, "tow_disp_along": 0.3845,
                  "winch_length_dev": 0.6488, "fish_heave_dev": 0.1043, "fish_heave_rate": 0.1499}
#: wave seeds of training: base seed (1000·code + j) + 40000 + 100·iteration + 100000·training seed
TRAIN_SEED_OFFSET = 40000
N_HISTORY = max(LAG_STEPS) + 1
GAIN_KEYS = ("g_ff", "tau", "kl", "kp", "kd")
#: the extra instant channels of feature set "v2": channel -> (offset, scale), the feature is (x − offset)/scale.
#: Offset and scale: each channel's mean and standard deviation under the along-cable law (3 × 180 s code-4
#: episodes, wave seeds + 77777, in the channel's physical unit: winch speed and last action as a fraction of the
#: winch's maximum speed, top tension as a ratio to its static value, angles in rad, rates in rad/s); measured
#: once and kept fixed so that the policy is a fixed function.
EXTRA_SCALES = {"winch_speed": (0.0, 0.284), "last_action": (0.0, 0.320), "top_tension": (0.996, 0.178),
                "cable_angle": (0.467, 0.0533), "fish_pitch_dev": (0.0, 0.0772), "fish_pitch_rate": (0.0, 0.190)}
#: feature sets: name -> extra instant channels after the v1 features (before the constant)
FEATURE_SETS = {"v1": (), "v2": tuple(EXTRA_SCALES), "v3": tuple(EXTRA_SCALES), "v2q": tuple(EXTRA_SCALES),
                "v2qa": tuple(EXTRA_SCALES)}
#: feature sets that add, before the constant, the along-cable channels 0.2–2.0 s ahead as predicted by the policy's
#: own causal linear predictor (agents/predictor.py, stored in the policy file) from 10 s of MRU history
PREDICTED = frozenset({"v2q", "v2qa"})
#: feature sets that add, after the predicted ones, hinges of the predicted along-cable acceleration at every lead:
#: name -> thresholds c (m/s²); the feature is sign(a)·max(|a| − c, 0)/HINGE_SCALE, a in m/s². Fixed physical values
#: chosen for the standard winch (1.5 m/s²: 2/3 of its limit and the limit itself), not scaled to another winch class
HINGES = {"v2qa": (1.0, 1.5)}
#: the winch acceleration limit (m/s²) the hinge thresholds were set for: the standard winch class's. Acting on an
#: environment with another limit warns (the thresholds, and any weights trained on them, mean something else
#: there); training on one is refused (:func:`check_hinge_winch`)
HINGE_WINCH_ACCELERATION = 1.5
#: scale of a hinge feature (m/s²): a prediction 0.5 m/s² beyond its threshold gives 1
HINGE_SCALE = 0.5
#: lagged channels a feature set adds after its extra instant channels: name -> ((channel, lags in control steps),
#: …). "v3": the policy's own earlier actions (0.2–1.1 s back: with them the residual is a recursive filter, which
#: can shape its command to the winch's acceleration limit) and the MRU along-cable velocity 2.4–4 s back (a longer
#: window for the predictor of the tow point's motion). Scaled as the channel's instant or v1 feature.
LONG_HISTORY = {"v1": (), "v2": (), "v2q": (), "v2qa": (),
                "v3": (("last_action", (1, 2, 3, 4, 6, 8, 10)), ("tow_vel_along", (24, 28, 32, 36, 40)))}
#: the feature set of new training runs (policy files without a ``feature_set`` entry are "v1")
DEFAULT_FEATURE_SET = "v2"


def _check_feature_set(feature_set: str) -> str:
    if feature_set not in FEATURE_SETS:
        raise ValueError(f"feature_set must be one of {sorted(FEATURE_SETS)} (got {feature_set!r})")
    return feature_set


def _require_channels(reader, feature_set: str, who: str):
    """KeyError naming the channels of ``feature_set`` the environment behind ``reader`` does not observe."""
    missing = [c for c in FEATURE_SETS[_check_feature_set(feature_set)] if not reader.has(c)]
    if missing:
        raise KeyError(f"{who} (feature set {feature_set!r}) needs observation channels {missing}; "
                       f"the environment observes {reader.names}")


def feature_names(feature_set: str = "v1") -> list[str]:
    extra = FEATURE_SETS[_check_feature_set(feature_set)]
    long = [f"{c}@-{lag / 10:.1f}s" for c, lags in LONG_HISTORY[feature_set] for lag in lags]
    if feature_set in PREDICTED:
        from .predictor import LEADS, feature_names as predicted_names
        long = long + predicted_names() + [f"hinge{c:g}(tow_acc_along@+{lead / 10:.1f}s(pred))"
                                           for c in HINGES.get(feature_set, ()) for lead in LEADS]
    return ([f"{c}@-{lag / 10:.1f}s" for c in HISTORY_CHANNELS for lag in LAG_STEPS] + list(INSTANT_CHANNELS)
            + list(extra) + long + ["const"])


def _long_scale(c):
    """(offset, scale) of a LONG_HISTORY channel: its extra-channel scaling, else its v1 feature scale."""
    return EXTRA_SCALES[c] if c in EXTRA_SCALES else (0.0, FEATURE_SCALES[c])


def _long_ring_size(feature_set):
    return max((max(lags) for _c, lags in LONG_HISTORY[feature_set]), default=0) + 1


def n_features(feature_set: str = "v1") -> int:
    return len(feature_names(feature_set))


#: the number of v1 features (kept for the v1 callers; use :func:`n_features` for a given set)
N_FEATURES = n_features("v1")


def _train_seed(base_seed: int, iteration: int, seed: int) -> int:
    return int(base_seed) + TRAIN_SEED_OFFSET + 100 * int(iteration) + 100000 * int(seed)


# ============================================================================ the policy (one environment)
class ARSPolicy:
    """A trained linear residual (module docstring) with SB3's ``predict``. Bind it to the environment it acts in
    with :meth:`bind_env` (``scripts/evaluate.py`` does); pass ``episode_start=True`` on the first step of every
    episode (it reads the sea-state estimate then and clears its memory)."""
    acts_on = "observations (and their history) + sea state"

    def __init__(self, theta: dict, base_table: dict, scales: dict | None = None, meta: dict | None = None,
                 name: str = "ars", feature_set: str | None = None, predictor=None):
        self.feature_set = _check_feature_set(feature_set or (meta or {}).get("feature_set", "v1"))
        if (self.feature_set in PREDICTED) != (predictor is not None):
            raise ValueError(f"ARSPolicy: feature set {self.feature_set!r} "
                             + ("needs a predictor (agents/predictor.py)" if predictor is None else "has no predictor"))
        check_channels(predictor, PRED_CHANNELS, "ARSPolicy")
        self.predictor = predictor
        self.theta = {k: np.asarray(v, float) for k, v in theta.items()}
        nf = n_features(self.feature_set)
        bad = [k for k, v in self.theta.items() if v.shape != (nf,)]
        if bad:
            raise ValueError(f"ARSPolicy: theta entries {bad} do not have the {nf} features of feature set "
                             f"{self.feature_set!r}")
        self.base_table = dict(base_table)
        self.scales = dict(FEATURE_SCALES | (scales or {}))
        self.meta = dict(meta or {})
        self.meta["feature_set"] = self.feature_set
        self.meta.setdefault("algo", "ars")
        self.meta.setdefault("env_id", ENV_ID)
        self.meta.setdefault("env_kwargs", {})
        self.name = name
        self.env = None
        self._hist = None
        self._th = None

    def bind_env(self, env):
        from .classical import AlongCableWinch
        self.env = env
        self.base = AlongCableWinch(env, table=self.base_table)
        self.reader = self.base.reader
        _require_channels(self.reader, self.feature_set, "ARSPolicy")
        check_hinge_winch(env, self.feature_set, f"ARSPolicy {self.name}", error=False)
        self.u = env.unwrapped
        return self

    def reset(self, env=None):
        if env is not None:
            self.bind_env(env)
        self._hist = None

    def predict(self, obs, state=None, episode_start=None, deterministic: bool = True):
        if self.env is None:
            raise RuntimeError("ARSPolicy: call bind_env(env) before predict()")
        o = np.asarray(obs, dtype=float)
        if o.ndim == 2:
            o = o[0]
        start = episode_start is not None and bool(np.any(episode_start))
        if start or self._hist is None:
            self.base.reset()
            self._th = self.theta[nearest_key(self.theta, self.u.sea[0])]
            self._pkey = nearest_key(self.predictor.W, self.u.sea[0]) if self.predictor is not None else None
            self._hist = None
        a_base = float(self.base.act(o)[0])
        phi, self._hist = features_single(self.reader, o, self.scales, self._hist, self.feature_set,
                                          self.predictor, self._pkey)
        a = min(max(a_base + float(self._th @ phi), -1.0), 1.0)
        out = np.array([a], np.float32)
        return (out[None, :] if np.asarray(obs).ndim == 2 else out), state


def check_hinge_winch(env, feature_set: str, who: str, error: bool) -> None:
    """Warn (``error=False``: a trained policy acting) or raise ValueError (the batched rollouts of training and of the
    comparison scripts) when ``feature_set`` has hinges (:data:`HINGES`) and ``env``'s winch acceleration limit is
    not :data:`HINGE_WINCH_ACCELERATION` (an env without a winch has no limit to compare: nothing to say)."""
    if not HINGES.get(feature_set):
        return
    a_max = float(getattr(getattr(env, "unwrapped", env), "winch_max_acceleration", HINGE_WINCH_ACCELERATION))
    if a_max == HINGE_WINCH_ACCELERATION:
        return
    msg = (f"{who}: feature set {feature_set!r} has hinges of the predicted acceleration at "
           f"{', '.join(f'{c:g}' for c in HINGES[feature_set])} m/s², set for a winch acceleration limit of "
           f"{HINGE_WINCH_ACCELERATION:g} m/s² (the standard winch); this environment's winch_max_acceleration is "
           f"{a_max:g} m/s²")
    if error:
        raise ValueError(msg + " - train feature set 'v2q' for another winch class")
    import warnings
    warnings.warn(msg + " - the policy acts, but outside the winch it was designed and trained for", stacklevel=3)


def hinge_features(predictor, predicted, thresholds) -> np.ndarray:
    """(n, len(thresholds)·len(LEADS)) hinge features of the predicted along-cable acceleration (the predictor's
    second channel, stored scaled by its channel scale) for predictions (n, 3·len(LEADS)); threshold-major."""
    L = predicted.shape[1] // 3                                      # leads per predicted channel
    acc = predicted[:, L:2 * L] * predictor.scales[1]                # m/s²
    return np.concatenate([np.sign(acc) * np.maximum(np.abs(acc) - c, 0.0) / HINGE_SCALE for c in thresholds], axis=1)


def _extra_single(reader, obs, name):
    v = reader(obs, name)
    return float(np.asarray(v).reshape(-1)[0])


def features_single(reader, obs, scales, hist, feature_set: str = "v1", predictor=None, pkey=None):
    """φ of one observation given the history ring ``hist`` ((3, N_HISTORY), newest first; None at episode start:
    filled with the first observation; for a feature set with :data:`LONG_HISTORY` or a predictor (:data:`PREDICTED`;
    ``predictor`` and its sea-state key ``pkey``) a pair (ring, long or predictor ring)).
    Returns (φ, new ring). Same arithmetic as the batched :class:`_Batch`."""
    long = LONG_HISTORY[feature_set]
    pred = feature_set in PREDICTED
    ring, lring = (hist if (long or pred) and hist is not None else (hist, None))
    h = np.array([reader(obs, c) / scales[c] for c in HISTORY_CHANNELS])
    if ring is None:
        ring = np.repeat(h[:, None], N_HISTORY, axis=1)
    else:
        ring = np.roll(ring, 1, axis=1)
        ring[:, 0] = h
    inst = [reader(obs, c) / scales[c] for c in INSTANT_CHANNELS]
    extra = [(_extra_single(reader, obs, c) - EXTRA_SCALES[c][0]) / EXTRA_SCALES[c][1]
             for c in FEATURE_SETS[feature_set]]
    phi = [ring[:, list(LAG_STEPS)].reshape(-1), inst, extra]
    if long:
        lh = np.array([(_extra_single(reader, obs, c) - _long_scale(c)[0]) / _long_scale(c)[1] for c, _l in long])
        if lring is None:
            lring = np.repeat(lh[:, None], _long_ring_size(feature_set), axis=1)
        else:
            lring = np.roll(lring, 1, axis=1)
            lring[:, 0] = lh
        phi.append(np.concatenate([lring[i, list(lags)] for i, (_c, lags) in enumerate(long)]))
        ring = (ring, lring)
    if pred:
        x = predictor.sample([[reader(obs, c) for c in PRED_CHANNELS]])
        lring = push(None if lring is None else lring[None], x, lring is None)[0]
        pr = predictor.predict(lring[None], [pkey])
        phi.append(pr[0])
        if HINGES.get(feature_set):
            phi.append(hinge_features(predictor, pr, HINGES[feature_set])[0])
        ring = (ring, lring)
    return np.concatenate(phi + [[1.0]]), ring


# ============================================================================ batched rollouts (training)
class _Batch:
    """The along-cable law (``classical.along_cable_velocity``, shared with the single-env baseline) and the
    features for a batch of observations (observation float32 → float64 × channel scale, as ``ObsReader``)."""

    def __init__(self, venv, base_table: dict, scales: dict, feature_set: str = "v1", predictor=None):
        if (feature_set in PREDICTED) != (predictor is not None):
            raise ValueError(f"feature set {feature_set!r} " + ("needs a predictor (agents/predictor.py)"
                                                                if predictor is None else "has no predictor"))
        check_channels(predictor, PRED_CHANNELS, "ARS training")
        self.predictor = predictor
        self.reader = ObsReader(venv.envs[0])
        _require_channels(self.reader, feature_set, "ARS training")
        self.extra = FEATURE_SETS[feature_set]
        self.long = LONG_HISTORY[feature_set]
        self.long_size = _long_ring_size(feature_set)
        self.hinges = HINGES.get(feature_set, ())
        check_hinge_winch(venv.envs[0], feature_set, "batched ARS/GN rollout (training or comparison)", error=True)
        self.vmax = float(venv.envs[0].winch_max_speed)
        self.table = base_table
        self.scales = scales

    def ch(self, obs, name):
        return self.reader.batch(obs, name)

    def ch_first(self, obs, name):
        """The first entry of a (possibly vector) channel for a batch, as :func:`_extra_single` row by row."""
        sl, scale, _vec = self.reader._slices[name]
        return np.asarray(obs)[:, sl.start].astype(float) * scale

    def set_seas(self, seas):
        from .classical import DEFAULT_ALONG_GAINS
        self.G = np.array([[float((DEFAULT_ALONG_GAINS | self.table[nearest_key(self.table, s)])[k]) for k in GAIN_KEYS]
                           for s in seas])
        if self.predictor is not None:
            self.pkeys = [nearest_key(self.predictor.W, s) for s in seas]

    def base_action(self, obs):
        from .classical import AlongCableWinch, along_cable_velocity
        v = along_cable_velocity(*(self.G[:, k] for k in range(5)),
                                 *(self.ch(obs, c) for c in AlongCableWinch.CHANNELS))
        return np.minimum(np.maximum(v / self.vmax, -1.0), 1.0)

    def features(self, obs, first: bool):
        n = obs.shape[0]
        h = np.stack([self.ch(obs, c) / self.scales[c] for c in HISTORY_CHANNELS], axis=1)
        if first:
            self.hist = np.repeat(h[:, :, None], N_HISTORY, axis=2)
        else:
            self.hist = np.roll(self.hist, 1, axis=2)
            self.hist[:, :, 0] = h
        lagged = self.hist[:, :, list(LAG_STEPS)].reshape(n, -1)
        inst = np.stack([self.ch(obs, c) / self.scales[c] for c in INSTANT_CHANNELS], axis=1)
        extra = np.stack([(self.ch_first(obs, c) - EXTRA_SCALES[c][0]) / EXTRA_SCALES[c][1] for c in self.extra],
                         axis=1) if self.extra else np.zeros((n, 0))
        parts = [lagged, inst, extra]
        if self.long:
            lh = np.stack([(self.ch_first(obs, c) - _long_scale(c)[0]) / _long_scale(c)[1] for c, _l in self.long],
                          axis=1)
            if first:
                self.lring = np.repeat(lh[:, :, None], self.long_size, axis=2)
            else:
                self.lring = np.roll(self.lring, 1, axis=2)
                self.lring[:, :, 0] = lh
            parts.append(np.concatenate([self.lring[:, i, list(lags)] for i, (_c, lags) in enumerate(self.long)],
                                        axis=1))
        if self.predictor is not None:
            x = self.predictor.sample(np.stack([self.ch(obs, c) for c in PRED_CHANNELS], axis=1))
            self.pring = push(getattr(self, "pring", None), x, first)
            pr = self.predictor.predict(self.pring, self.pkeys)
            parts.append(pr)
            if self.hinges:
                parts.append(hinge_features(self.predictor, pr, self.hinges))
        return np.concatenate(parts + [np.ones((n, 1))], axis=1)


def rollout_series(venv, batch: _Batch, seas, seeds, theta):
    """One episode in every copy of ``venv`` (copy i in (seas[i], seeds[i]) with weights theta[i]); returns the fish
    heave (m) and pitch (rad) per control step, ``(T, n)`` each, the time of each step and a per-copy flag of copies
    that ended early."""
    from .common import reset_copies
    n = venv.num_envs
    obs = reset_copies(venv, seas, seeds)
    batch.set_seas(seas)
    T = venv.envs[0].max_steps
    H = np.zeros((T, n))
    P = np.zeros((T, n))
    t = np.zeros(T)
    ended = np.zeros(n, bool)
    for k in range(T):
        phi = batch.features(obs, k == 0)
        a = np.clip(batch.base_action(obs) + np.einsum("nf,nf->n", theta, phi), -1.0, 1.0)
        obs, _r, term, trunc, infos = venv.step(a.astype(np.float32)[:, None])
        H[k] = infos["fish_heave"]
        P[k] = infos["fish_pitch"]
        t[k] = infos["t"][0]
        if k < T - 1:
            ended |= term | trunc
    return H, P, t, ended


def rollout_batch(venv, batch: _Batch, seas, seeds, theta, discard: float = 60.0):
    """One episode in every copy of ``venv`` (:func:`rollout_series`); returns σ(fish heave) (m) and σ(pitch) (deg)
    over t ≥ discard per copy (NaN for a copy that ended early)."""
    H, P, t, ended = rollout_series(venv, batch, seas, seeds, theta)
    w = t >= discard
    sh = H[w].std(axis=0)
    sp = np.degrees(P[w].std(axis=0))
    sh[ended] = np.nan
    sp[ended] = np.nan
    return sh, sp


# ============================================================================ training
def train(seed: int = 0, minutes: float = 40.0, max_iterations: int = 1000, directions: int = 8, top: int = 4,
          nu: float = 0.001, alpha: float = 0.0007, pitch_weight: float = 0.5, episode_seconds: float = 180.0,
          fail_penalty: float = 1.0, progress: bool = True, log=print,
          feature_set: str = DEFAULT_FEATURE_SET, parallel: bool = False) -> ARSPolicy:
    """ARS V1-t (module docstring) on the 12 evaluation (Hs, Tp, heading) entries with training wave seeds; one
    search per sea state of the along-cable table, sharing one batched rollout per iteration. Reward of an
    episode: −[ln(σ_h/σ_h,along) + pitch_weight · ln(σ_θ/σ_θ,along)] on the same waves. Stops after
    ``max_iterations`` or when the next iteration would pass ``minutes`` of wall time. ``parallel``: step the batch's
    copies on all numba threads (the vector env's ``parallel=True``: the serial result bit for bit, less wall time)."""
    import gymnasium as gym
    import towenv  # noqa: F401  (registers the ids)
    from towenv.envs.vector import WinchPayoutVectorEnv
    from .baselines import load_tuned
    t_start = time.perf_counter()
    table = dict(load_tuned().get("along_cable") or {})
    if not table:
        raise RuntimeError("no tuned along_cable table (agents/hyperparams/baselines.yml): run python -m agents.tuning")
    env = gym.make(ENV_ID)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    keys = sorted(table)
    ent = {k: [i for i, (sea, _s) in enumerate(ev) if nearest_key(table, sea) == k] for k in keys}
    keys = [k for k in keys if ent[k]]
    C, K = len(keys), int(directions)
    n_pert = sum(2 * K * len(ent[k]) for k in keys)
    n_copies = n_pert + 2 * len(ev)
    venv = WinchPayoutVectorEnv(num_envs=n_copies, autoreset_mode="NextStep", batch_infos=True,
                                episode_seconds=float(episode_seconds), parallel=bool(parallel))
    batch = _Batch(venv, table, dict(FEATURE_SCALES), feature_set)
    NF = n_features(feature_set)
    rng = np.random.default_rng(int(seed))
    theta = np.zeros((C, NF))
    curve = []
    log(f"[ars] seed {seed}: {C} sea states x {K} directions x 2 signs + 2 x {len(ev)} reference episodes = "
        f"{n_copies} copies of {episode_seconds:g} s per iteration; nu={nu} alpha={alpha} top={top} "
        f"pitch_weight={pitch_weight}; {NF} features per sea state (feature set {feature_set})")
    it = 0
    last = 0.0
    while it < max_iterations:
        elapsed = time.perf_counter() - t_start
        if elapsed + last > 60.0 * minutes:
            break
        t0 = time.perf_counter()
        delta = rng.standard_normal((C, K, NF))
        seas, seeds, th, owner = [], [], [], []
        for ci, k in enumerate(keys):
            for d in range(K):
                for sign in (1.0, -1.0):
                    for e in ent[k]:
                        seas.append(ev[e][0])
                        seeds.append(_train_seed(ev[e][1], it, seed))
                        th.append(theta[ci] + sign * nu * delta[ci, d])
                        owner.append(e)
        for which in ("theta", "along"):
            for e, (sea, s) in enumerate(ev):
                ci = keys.index(nearest_key(table, sea))
                seas.append(sea)
                seeds.append(_train_seed(s, it, seed))
                th.append(theta[ci] if which == "theta" else np.zeros(NF))
        sh, sp = rollout_batch(venv, batch, seas, seeds, np.array(th))
        cur_h, base_h = sh[n_pert:n_pert + len(ev)], sh[n_pert + len(ev):]
        cur_p, base_p = sp[n_pert:n_pert + len(ev)], sp[n_pert + len(ev):]
        cost = np.where(np.isfinite(sh[:n_pert]),
                        np.log(sh[:n_pert] / base_h[owner]) + pitch_weight * np.log(sp[:n_pert] / base_p[owner]),
                        fail_penalty)
        j = 0
        steps = []
        for ci, k in enumerate(keys):
            ne = len(ent[k])
            R = -cost[j:j + 2 * K * ne].reshape(K, 2, ne).mean(axis=2)
            j += 2 * K * ne
            rp, rm = R[:, 0], R[:, 1]
            order = np.argsort(-np.maximum(rp, rm))[:top]
            sd = float(np.concatenate([rp[order], rm[order]]).std())
            sd = sd if sd > 1e-12 else 1.0
            step = alpha / (top * sd) * ((rp[order] - rm[order])[:, None] * delta[ci, order]).sum(axis=0)
            theta[ci] += step
            steps.append(float(np.linalg.norm(step)))
        pooled_h = float(np.nanmean(cur_h) / np.nanmean(base_h))
        pooled_p = float(np.nanmean(cur_p) / np.nanmean(base_p))
        last = time.perf_counter() - t0
        curve.append({"iteration": it, "heave_ratio": pooled_h, "pitch_ratio": pooled_p, "seconds": last,
                      "failures": int(np.sum(~np.isfinite(sh)))})
        if progress:
            log(f"[ars] it {it:3d} ({last:4.1f} s, {(time.perf_counter() - t_start) / 60:5.1f} min): policy before "
                f"this step vs along_cable on {len(ev)} fresh training episodes: heave {100 * (pooled_h - 1):+6.2f} %, "
                f"pitch {100 * (pooled_p - 1):+5.1f} %; |step| {', '.join(f'{s:.4f}' for s in steps)}")
        it += 1
    steps_per_episode = int(venv.envs[0].max_steps)
    venv.close()
    wall = time.perf_counter() - t_start
    meta = {"algo": "ars", "env_id": ENV_ID, "env_kwargs": {}, "feature_set": feature_set, "seed": int(seed),
            "iterations": it,
            "num_timesteps": it * n_copies * steps_per_episode, "wall_seconds": wall, "parallel": bool(parallel),
            "wall_seconds_this_session": round(wall),
            "hyperparameters": {"directions": K, "top": top, "nu": nu, "alpha": alpha, "pitch_weight": pitch_weight,
                                "episode_seconds": episode_seconds, "minutes": minutes,
                                "max_iterations": max_iterations, "fail_penalty": fail_penalty},
            "train_seeds": f"1000*code + j + {TRAIN_SEED_OFFSET} + 100*iteration + 100000*{int(seed)}",
            "curve": curve}
    return ARSPolicy({k: theta[ci] for ci, k in enumerate(keys)}, table, FEATURE_SCALES, meta, name=f"ars_s{seed}",
                     feature_set=feature_set)


# ============================================================================ files
def theta_rows(policy: ARSPolicy, seas, names) -> np.ndarray:
    """(len(seas), len(names)) weights of ``policy`` for each sea state in ``seas`` (its nearest sea-state key), placed
    by feature name in the wider feature list ``names`` (0 for features the policy does not have); ValueError naming
    the policy's features that ``names`` lacks (its feature set does not nest in the batch's)."""
    own = feature_names(policy.feature_set)
    missing = [nm for nm in own if nm not in names]
    if missing:
        raise ValueError(f"policy {policy.name!r} (feature set {policy.feature_set!r}) has features {missing[:3]}"
                         f"{' …' if len(missing) > 3 else ''} that the batch's feature list does not have")
    cols = [names.index(nm) for nm in own]
    out = np.zeros((len(seas), len(names)))
    for e, sea in enumerate(seas):
        out[e, cols] = policy.theta[nearest_key(policy.theta, sea)]
    return out


def save_policy(policy: ARSPolicy, path: str | Path) -> Path:
    """Write the policy as an .npz (weights per sea-state key, the base's gain table, scales, metadata JSON),
    atomically."""
    from .common import save_ars_file
    fs = policy.feature_set
    meta = dict(policy.meta) | {"feature_set": fs, "features": feature_names(fs), "lag_steps": list(LAG_STEPS),
                                "history_channels": list(HISTORY_CHANNELS),
                                "instant_channels": list(INSTANT_CHANNELS) + list(FEATURE_SETS[fs])}
    if LONG_HISTORY[fs]:
        meta["long_history"] = [[c, list(lags)] for c, lags in LONG_HISTORY[fs]]
    if fs != "v1":
        meta["extra_scales"] = {c: list(EXTRA_SCALES[c]) for c in FEATURE_SETS[fs]}
    extra = policy.predictor.arrays() if policy.predictor is not None else None
    return save_ars_file(path, policy.theta, policy.base_table, policy.scales, meta, extra)


def load_ars_policy(path: str | Path) -> ARSPolicy:
    """Read a policy written by :func:`save_policy` (bind it to an environment before use)."""
    from .common import read_ars_file
    def names_for(meta):
        fs = meta.get("feature_set", "v1")
        if fs not in FEATURE_SETS:
            raise ValueError(f"{path}: unknown ARS feature set {fs!r} (this version knows {sorted(FEATURE_SETS)})")
        want = {c: list(EXTRA_SCALES[c]) for c in FEATURE_SETS[fs]}
        if fs != "v1" and meta.get("extra_scales") != want:
            raise ValueError(f"{path}: its feature scales {meta.get('extra_scales')} differ from this version's "
                             f"{want} (the policy would see other features)")
        return feature_names(fs)
    theta, table, scales, meta = read_ars_file(path, names_for, {"env_id": ENV_ID, "algo": "ars"},
                                               "an ARS along-cable-residual policy")
    predictor = from_policy_file(path, meta["feature_set"]) if meta.get("feature_set") in PREDICTED else None
    return ARSPolicy(theta, table, scales, meta, name=Path(path).stem, predictor=predictor)


def default_export(feature_set: str, seed: int) -> Path:
    """Where ``train_ars.py`` writes without ``--export``: the policy family's name by feature set (``ars_`` for
    v1, ``ars2_`` for v2 — the names of the committed policies), under ``runs/`` in the current directory."""
    prefix = "ars" if _check_feature_set(feature_set) == "v1" else f"ars{feature_set[1:]}"
    return Path("runs") / f"{prefix}_WinchPayout-v0_s{int(seed)}.npz"


def main(argv=None) -> int:
    """``python scripts/train_ars.py --seed 0 --minutes 110 --max-iterations 70`` (the v2 recipe; writes
    :func:`default_export`)"""
    import argparse
    ap = argparse.ArgumentParser(description="Train an ARS linear residual over the along-cable winch law "
                                             "(towenv/WinchPayout-v0); agents/ars.py explains the method.")
    ap.add_argument("--seed", type=int, default=0, help="training seed: ARS directions and training wave seeds")
    ap.add_argument("--minutes", type=float, default=40.0, help="wall-clock budget (default 40)")
    ap.add_argument("--max-iterations", type=int, default=1000)
    ap.add_argument("--directions", type=int, default=8)
    ap.add_argument("--top", type=int, default=4)
    ap.add_argument("--nu", type=float, default=0.001, help="exploration noise in parameter space")
    ap.add_argument("--alpha", type=float, default=0.0007, help="step size")
    ap.add_argument("--pitch-weight", type=float, default=0.5, help="weight of ln(σ_pitch ratio) in the cost")
    ap.add_argument("--episode-seconds", type=float, default=180.0)
    ap.add_argument("--features", choices=sorted(FEATURE_SETS), default=DEFAULT_FEATURE_SET,
                    help=f"feature set (default {DEFAULT_FEATURE_SET}; v1 is the set of the policies committed "
                         "before 2026-12-03)")
    ap.add_argument("--export", default=None, help="policy file (default runs/ars2_WinchPayout-v0_s<seed>.npz for "
                                                  "feature set v2, runs/ars_WinchPayout-v0_s<seed>.npz for v1)")
    add_parallel_flag(ap)
    a = ap.parse_args(argv)
    for name in ("minutes", "nu", "alpha", "episode_seconds"):
        v = getattr(a, name)
        if not (math.isfinite(v) and v > 0):
            ap.error(f"--{name.replace('_', '-')} must be a positive number (got {v})")
    if a.directions < 1 or not 1 <= a.top <= a.directions or a.max_iterations < 1 or a.pitch_weight < 0:
        ap.error("need --directions >= 1, 1 <= --top <= --directions, --max-iterations >= 1, --pitch-weight >= 0")
    if a.episode_seconds < 120.0:
        ap.error("--episode-seconds must be >= 120 (the score starts at 60 s)")
    out = Path(a.export or default_export(a.features, a.seed))
    pol = train(a.seed, a.minutes, a.max_iterations, a.directions, a.top, a.nu, a.alpha, a.pitch_weight,
                a.episode_seconds, feature_set=a.features, parallel=a.parallel)
    save_policy(pol, out)
    print(f"[ars] wrote {out} ({pol.meta['iterations']} iterations, {pol.meta['wall_seconds'] / 60:.1f} min)")
    return 0
