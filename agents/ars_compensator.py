"""Augmented Random Search (ARS) on a linear residual over the skyhook law, for ``towenv/CompensatorGains-v0``.

The pattern of :mod:`agents.ars` (WinchPayout) applied to the semi-active compensator (issue 14): PPO residuals on
skyhook reached 14–22 % less significant heave than ``best_passive`` but with 77–85 end-stop hits in 24
episodes (docs/agents.md). Here the residual sees a few seconds of the tow point's vertical motion, the stroke
and nonlinear stroke features that let it stiffen or damp near the end stops, and it is trained by random
search in parameter space (Mania et al. 2018, ARS V1-t: fixed feature scales, the best b of N directions, step
normalised by the rewards' standard deviation) with an explicit end-stop penalty in the cost. The policy::

    a = clip(a_skyhook(obs) + Θ_c · φ(history), −1, 1)           a = (log-stiffness, log-damping) action

* ``a_skyhook`` — the skyhook semi-active law (``agents/classical.py``) with its tuned per-sea-state gains (the
  table is copied into the policy file, so retuning ``baselines.yml`` later does not change a trained policy);
* ``φ`` — :data:`HISTORY_CHANNELS` (MRU tow-point vertical velocity, acceleration, heave displacement) at the
  lags :data:`LAG_STEPS` (0, 0.2, …, 2.0 s); :data:`INSTANT_CHANNELS` (stroke, stroke velocity, fish heave about
  its running mean and its rate, fish pitch about its running mean and its rate); :data:`NONLINEAR` stroke
  features (|s|, s², s⁴, s·ṡ, max(s·ṡ, 0); s = stroke / half stroke, ṡ = stroke velocity / half stroke) and
  a constant, each divided by a fixed scale (:data:`FEATURE_SCALES`). The stroke features are *even* in s
  (or signed by the direction of travel relative to the nearer stop) because the action is a gain, not a
  force: a stiffness that grows near *both* stops is a function of |s|, not of s|s| or s³;
* ``Θ_c`` — a (2 × n_features) matrix per sea state of the skyhook gain table (the same schedule as the base).

These 45 features are feature set ``"h"`` (files without a feature set are "h"). Feature set ``"hq"`` adds, before the
constant, the tow point's vertical velocity, acceleration and heave 0.2, 0.4, …, 2.0 s *ahead* as predicted by a causal
linear predictor from the last 10 s of the MRU's vertical motion (``agents/predictor.py``, stored in the policy file;
75 features). On the evaluation set it did not beat "h" (docs/agents.md). Feature set ``"hs"`` adds a copy of every "h"
feature (the constant included) multiplied by skyhook's switching state (1 while the base law damps, ż_abs·ṡ > 0, else
0; :func:`skyhook_on`): separate residual weights for the damping-on and damping-off phases (90 features). Feature
set ``"hst"`` adds to "hs" the cable's state at the sheave, ungated: the top tension's deviation from its static value
and the tow point's velocity along the top cable at the same lags (112 features; :data:`CABLE_CHANNELS`). Feature set
``"hsf"`` adds to "hs" a second gated copy of every "h" feature, multiplied by the *fish's* switching state (1 while the
fish's heave rate and the stroke velocity have one sign, :func:`fish_on`; 135 features). Feature set ``"hsfo"`` adds to
"hsf" a third gated copy, multiplied by the stroke's direction of travel: 1 while the stroke moves *outward*, towards
the nearer end stop (stroke and stroke velocity of one sign, :func:`outward_on`; 180 features).

Θ = 0 is the skyhook law exactly. The policy is causal: it acts on the observation vector and its own memory of
earlier observations, plus the sea-state estimate at episode start (as the base does).

Training (:func:`train`, ``python scripts/train_ars_compensator.py``) evaluates all perturbations of an
iteration as one batch of :class:`towenv.envs.vector.CompensatorGainsVectorEnv`, with common random numbers:
the + and − perturbation of a direction run the same sea states and wave seeds, and the skyhook law runs them
too. Cost of an episode::

    ln(σ_h / σ_h,skyhook) + w_p · ln(σ_θ / σ_θ,skyhook) + w_hit · (end-stop hits in the episode)
        + w_margin · mean_t max(|s| − m0, 0)²

(σ and the margin mean over t ≥ 60 s, hits over the whole episode; the winch pattern's cost plus the hit and
stroke-margin terms; s = the ``comp_stroke`` observation channel, the stroke as a fraction of the half stroke,
read from the observation after every control step exactly as the single-environment policy reads it). The
margin term is dense where the hit count is sparse: it charges every step the stroke spends beyond m0 (default
0.85) of the half stroke. Defaults (:data:`DEFAULT_HIT_WEIGHT`, :data:`DEFAULT_MARGIN_WEIGHT`,
:data:`DEFAULT_MARGIN_START`): w_hit = 0.3 (one extra hit in an episode costs as much as ≈ 30 % more σ_h) and
w_margin = 1000. The stroke spends very little time beyond 0.85 (σ(s) ≈ 0.26; the end-stop hits are short
excursions): under skyhook the mean of max(|s| − 0.85, 0)² on the 12 training episodes of an iteration is
≈ 1e-6 … 3e-5 (first iterations of the second probe), so w_margin = 30 — sized on the idea "0.95 for 10 % of
the window costs ≈ 3 % of σ_h" — contributes ≤ 0.001 and does nothing; 1000 makes skyhook's term ≈ 0.001 …
0.03 and a doubled tail a few % of σ_h (a stroke at 0.95 for 10 % of the window would cost 1.0). The first
probe's cost is ``--hit-weight 0.05 --margin-weight 0``. Optional per-sea-state hit weights (``hit_weights`` =
{WMO code: w}, CLI ``--hit-weights 3:1.0,4:0.3``; the code of an entry is its base wave seed // 1000): an episode
of a listed code is charged that weight per hit instead of w_hit (default none: w_hit everywhere).

Optional stop guard (``stop_guard`` = g, 0 = off; stored in the policy file's metadata): outside the linear
part, when |s| > g and the stroke moves outward (s · ṡ > 0), the action is (1, 1) — maximum stiffness and
damping — whatever the skyhook law and the residual say; applied after the clip, identically in the single-env
policy and the batched rollout. Wave seeds are
fresh every iteration: ``1000·code + j + 50000 + 100·iteration + 100000·seed`` (iteration < 100) — never an
evaluation (+0…400), tuning (+500), validation (+700), Hover design (+900), final (+20000…), clairvoyant-teacher
(+30000…) or WinchPayout-ARS (+40000 + 100·iteration, iteration < 100) seed.
"""
from __future__ import annotations

import hashlib
import json
import math
import time
from pathlib import Path

import numpy as np
from numba import njit

from .common import (COMPENSATOR_ID, ObsReader, add_parallel_flag, nearest_key, read_ars_file, reset_copies,
                     save_ars_file)
from .predictor import COMP_PRED_CHANNELS, check_channels, from_policy_file, push
from .predictor import feature_names as predicted_names

__all__ = ["ARSCompensatorPolicy", "FEATURE_SETS", "PREDICTED", "GATED", "GATE_PREFIX", "FISH_GATED", "FISH_GATE_PREFIX",
           "fish_on", "OUTWARD_GATED", "OUTWARD_GATE_PREFIX", "outward_on", "GATES", "gate_functions", "CABLE", "CABLE_CHANNELS",
           "CABLE_OFFSETS", "ADDED_KINDS", "added_features",
           "skyhook_on", "n_features", "train", "save_policy", "load_policy", "rollout_batch", "measure_scales",
           "rollout_series", "feature_names", "HISTORY_CHANNELS", "INSTANT_CHANNELS", "NONLINEAR", "LAG_STEPS", "FEATURE_SCALES",
           "TRAIN_SEED_OFFSET", "MAX_ITERATIONS", "ALGO", "DEFAULT_HIT_WEIGHT", "DEFAULT_MARGIN_WEIGHT",
           "DEFAULT_MARGIN_START", "margin_penalty", "stop_guard_mask", "entry_hit_weights", "parse_hit_weights",
           "main"]

ENV_ID = COMPENSATOR_ID
#: ``meta["algo"]`` of the policy files (scripts/evaluate.py dispatches on env_id + algo)
ALGO = "ars_skyhook"
#: channels whose recent history the policy sees, and the lags (control steps of 0.1 s): 0, 0.2, …, 2.0 s
HISTORY_CHANNELS = ("tow_vel_z", "tow_acc_z", "tow_heave")
LAG_STEPS = tuple(range(0, 21, 2))
#: channels the policy sees at the current step only
INSTANT_CHANNELS = ("comp_stroke", "comp_stroke_vel", "fish_heave_dev", "fish_heave_rate", "fish_pitch_dev",
                    "fish_pitch_rate")
#: nonlinear stroke features (s = stroke / half stroke, v = stroke velocity / half stroke, in 1/s)
NONLINEAR = ("stroke_abs", "stroke_sq", "stroke_4", "stroke_out", "stroke_out_pos")
#: fixed feature scales: each feature's standard deviation under the skyhook law on the 12 training-seed episodes
#: of iteration 0, training seed 0 (180 s; :func:`measure_scales`; measured once and kept fixed so that the
#: policy is a fixed function of its inputs)
FEATURE_SCALES = {"tow_vel_z": 1.333, "tow_acc_z": 2.43, "tow_heave": 0.821, "comp_stroke": 0.2596,
                  "comp_stroke_vel": 0.5161, "fish_heave_dev": 0.2817, "fish_heave_rate": 0.2249,
                  "fish_pitch_dev": 0.1161, "fish_pitch_rate": 0.2979, "stroke_abs": 0.1687, "stroke_sq": 0.1059,
                  "stroke_4": 0.05032, "stroke_out": 0.1397, "stroke_out_pos": 0.0905,
                  "top_tension": 0.2969, "tow_vel_along": 0.6825}     # the last two: feature set "hst" (2026-12-06)
#: wave seeds of training: base seed (1000·code + j) + 50000 + 100·iteration + 100000·training seed
TRAIN_SEED_OFFSET = 50000
#: iterations per run: 100·iteration stays below 10000, so the training seeds of one run stay in
#: [+50000, +59900] and never reach another run's (+100000·seed) or WinchPayout ARS's (+40000 … +49900) seeds
MAX_ITERATIONS = 100
#: cost defaults (module docstring): hit weight, stroke-margin weight and start (fraction of the half stroke)
DEFAULT_HIT_WEIGHT = 0.3
DEFAULT_MARGIN_WEIGHT = 1000.0
DEFAULT_MARGIN_START = 0.85
N_HISTORY = max(LAG_STEPS) + 1
GAIN_KEYS = ("c_sky", "b0", "k0", "margin", "k_stop")
N_ACT = 2


#: feature sets: "h" (the history, instant and stroke features above; every policy before feature sets had
#: names) and "hq" = "h" + the tow point's vertical velocity, acceleration and heave 0.2, 0.4, …, 2.0 s *ahead* as
#: predicted by the policy's own causal linear predictor from the last 10 s of the MRU's vertical motion
#: (``agents/predictor.py``, :data:`agents.predictor.COMP_PRED_CHANNELS`, stored in the policy file), scaled as the
#: channel's history features, placed before the constant
FEATURE_SETS = ("h", "hq", "hs", "hst", "hsf", "hsfo")
PREDICTED = frozenset({"hq"})
#: feature set "hs" = "h" + every "h" feature (the constant included) multiplied by skyhook's switching state
#: ``on`` = 1 while the sheave's absolute velocity has the stroke velocity's sign (skyhook damps; the same condition
#: as the base law, read from the same observation), else 0: a residual with separate weights for the damping-on and
#: damping-off phases (90 features; the gated names are prefixed ``on*``)
GATED = frozenset({"hs", "hst", "hsf", "hsfo"})
GATE_PREFIX = "on*"
#: feature set "hsf" = "hs" + a second copy of every "h" feature multiplied by the *fish's* switching state
#: ``fish_on`` = 1 while the fish's heave rate and the stroke velocity have the same sign, else 0 (:func:`fish_on`):
#: the skyhook gate splits the residual by what the sheave does, this one by what the fish does relative to the
#: stroke — whether the damper's force on the cable (−b·ṡ) currently pushes the tension with or against the fish's
#: motion, the switching condition of a semi-active law aimed at the fish (135 features; the names prefixed
#: ``fish*``; after the skyhook-gated copy). Either sign convention gives the same class: the ungated weights cover
#: the other phase
FISH_GATED = frozenset({"hsf", "hsfo"})
FISH_GATE_PREFIX = "fish*"
#: feature set "hsfo" = "hsf" + a third copy of every "h" feature multiplied by the stroke's direction of travel
#: ``outward_on`` = 1 while the stroke moves away from mid-stroke, towards the nearer end stop (the stroke and its
#: velocity have one sign), else 0 (:func:`outward_on`): separate weights for the half cycle in which the spring
#: stores energy and the stop comes nearer and the half cycle in which it gives the energy back (180 features; the
#: names prefixed ``out*``; after the fish-gated copy)
OUTWARD_GATED = frozenset({"hsfo"})
OUTWARD_GATE_PREFIX = "out*"
#: feature set "hst" = "hs" + the cable's state at the sheave: the top tension's deviation from its static value
#: (``top_tension`` − 1, in units of the static top tension) and the tow point's velocity along the top cable
#: (``tow_vel_along``, m/s) at the lags :data:`LAG_STEPS`, ungated, after the gated copy (112 features). Under
#: skyhook the fish heave is poorly explained by the tow point's vertical-motion history alone (leave-one-episode-out
#: R² of a linear fit on 10 s of it: 0.43 / 0.24 / 0.16 in codes 3 / 4 / 5) and much better with the top tension's
#: (0.61 / 0.51 / 0.46; ``python scripts/probe_cable_state.py``): the tension carries the cable's dynamic state, which
#: "h" does not see. Searched from ``gns`` it gained no heave on the evaluation set (docs/agents.md, ``gnst``)
CABLE = frozenset({"hst"})
CABLE_CHANNELS = ("top_tension", "tow_vel_along")
#: the value subtracted from a cable channel before scaling (the static top tension is 1 in its channel's units)
CABLE_OFFSETS = {"top_tension": 1.0, "tow_vel_along": 0.0}
#: the kinds of features a feature set adds to "h", and the sets that add them (a set adding two kinds lists both)
ADDED_KINDS = {"predicted": PREDICTED, "gated": GATED, "cable": CABLE, "fish": FISH_GATED, "outward": OUTWARD_GATED}


def skyhook_on(reader, obs):
    """Skyhook's switching state per row of a batch of observations (1.0 where the law damps, else 0.0): the sheave's
    absolute velocity ż_abs = tow_vel_z + comp_stroke_vel has the stroke velocity's sign, and |ṡ| > 1e-6 — the
    condition of ``classical.SkyhookCompensator`` and :meth:`_Batch.base_action`."""
    sd = reader.batch(obs, "comp_stroke_vel")
    z_abs = reader.batch(obs, "tow_vel_z") + sd
    return ((z_abs * sd > 0.0) & (np.abs(sd) > 1e-6)).astype(float)


def fish_on(reader, obs):
    """The fish's switching state per row of a batch of observations (feature set "hsf"): 1.0 where the fish's heave
    rate (``fish_heave_rate``) and the stroke velocity (``comp_stroke_vel``) have the same sign, else 0.0."""
    return (reader.batch(obs, "fish_heave_rate") * reader.batch(obs, "comp_stroke_vel") > 0.0).astype(float)


def outward_on(reader, obs):
    """The stroke's direction of travel per row of a batch of observations (feature set "hsfo"): 1.0 where the stroke
    (``comp_stroke``) and the stroke velocity (``comp_stroke_vel``) have the same sign — the stroke moves towards the
    nearer end stop —, else 0.0."""
    return (reader.batch(obs, "comp_stroke") * reader.batch(obs, "comp_stroke_vel") > 0.0).astype(float)


#: the gated copies of the "h" features, in feature order: (kind, the feature sets that have it, name prefix, gate
#: function of a batch of observations)
GATES = (("gated", GATED, GATE_PREFIX, skyhook_on), ("fish", FISH_GATED, FISH_GATE_PREFIX, fish_on),
         ("outward", OUTWARD_GATED, OUTWARD_GATE_PREFIX, outward_on))


def gate_functions(feature_set: str) -> tuple:
    """The gate functions of ``feature_set``'s gated copies, in feature order (empty for a set without any)."""
    return tuple(on for _kind, sets, _prefix, on in GATES if feature_set in sets)


def feature_names(feature_set: str = "h") -> list[str]:
    if feature_set not in FEATURE_SETS:
        raise ValueError(f"unknown compensator feature set {feature_set!r} (known: {', '.join(FEATURE_SETS)})")
    pred = []
    if feature_set in PREDICTED:
        pred = predicted_names(COMP_PRED_CHANNELS)
    names = ([f"{c}@-{lag / 10:.1f}s" for c in HISTORY_CHANNELS for lag in LAG_STEPS] + list(INSTANT_CHANNELS)
             + list(NONLINEAR) + pred + ["const"])
    base = list(names)
    for _kind, sets, prefix, _on in GATES:
        if feature_set in sets:
            names += [prefix + nm for nm in base]
    if feature_set in CABLE:
        names += [f"{c}@-{lag / 10:.1f}s" for c in CABLE_CHANNELS for lag in LAG_STEPS]
    return names


#: features of feature set "h" (the policies without a feature set in their metadata)
N_FEATURES = len(feature_names())


def added_features(feature_set: str, kind: str | None = None) -> tuple[str, np.ndarray]:
    """(kind, mask) of the features ``feature_set`` adds to "h": kind "predicted" (hq: the predicted tow-point
    motion), "gated" (hs: the skyhook-gated copy), "cable" (hst: the top tension and along-cable velocity
    histories; hst also has the gated copy, so ``kind`` picks which: default the last added) or "" (h), and a
    boolean mask over ``feature_names(feature_set)``."""
    names = feature_names(feature_set)
    kinds = [k for k, sets in ADDED_KINDS.items() if feature_set in sets]
    if kind is None:
        kind = kinds[-1] if kinds else ""
    elif kind not in kinds:
        return "", np.zeros(len(names), bool)
    if kind == "predicted":
        return "predicted", np.array([nm.endswith("(pred)") for nm in names])
    for gate_kind, _sets, prefix, _on in GATES:
        if kind == gate_kind:
            return kind, np.array([nm.startswith(prefix) for nm in names])
    if kind == "cable":
        n_cable = len(CABLE_CHANNELS) * len(LAG_STEPS)
        return "cable", np.arange(len(names)) >= len(names) - n_cable
    return "", np.zeros(len(names), bool)


def n_features(feature_set: str = "h") -> int:
    return len(feature_names(feature_set))


def _check_predictor(feature_set: str, predictor, what: str) -> None:
    if feature_set not in FEATURE_SETS:
        raise ValueError(f"{what}: unknown feature set {feature_set!r} (known: {', '.join(FEATURE_SETS)})")
    if (feature_set in PREDICTED) != (predictor is not None):
        raise ValueError(f"{what}: feature set {feature_set!r} " + (
            "needs a predictor (python -m agents.predictor --env towenv/CompensatorGains-v0)" if predictor is None
            else "has no predictor"))
    check_channels(predictor, COMP_PRED_CHANNELS, what)


def _train_seed(base_seed: int, iteration: int, seed: int) -> int:
    if not 0 <= int(iteration) < MAX_ITERATIONS:
        raise ValueError(f"training iteration {iteration} outside 0..{MAX_ITERATIONS - 1} (seed-set disjointness)")
    return int(base_seed) + TRAIN_SEED_OFFSET + 100 * int(iteration) + 100000 * int(seed)


# ============================================================================ features (batch; one env = batch of 1)
class _Features:
    """φ for a batch of observations ``(n, obs_size)`` with the history ring of every row. The single-environment
    policy uses it with n = 1, so training and deployment share one arithmetic."""

    def __init__(self, reader: ObsReader, half_stroke: float, scales: dict, predictor=None, gates=(),
                 cable: bool = False):
        self.reader = reader
        self.half = float(half_stroke)
        self.gates = tuple(gates)           # the gate functions of the gated copies, in feature order
        self.cable = bool(cable)
        self.chist = None                   # the cable channels' history ring (n, channels, N_HISTORY), newest first
        self.scales = dict(scales)
        self.hist = None
        self.predictor = predictor
        self.pring = None                   # the predictor's 10 s history ring (n, channels, RING), newest first
        self.pkeys = None                   # the predictor's sea-state key of every row (set by the owner)

    def load_rows(self, source: "_Features", src) -> None:
        """Every row's history rings set to ``source``'s rows ``src`` (row i ← source row src[i]): a copy loaded
        from another with ``TowVectorEnv.load_copies`` continues its features too."""
        for name in ("hist", "chist", "pring"):
            v = getattr(source, name)
            setattr(self, name, None if v is None else v[src].copy())

    def __call__(self, obs, first: bool):
        r, sc = self.reader, self.scales
        n = obs.shape[0]
        h = np.stack([r.batch(obs, c) / sc[c] for c in HISTORY_CHANNELS], axis=1)
        if first or self.hist is None:
            self.hist = np.repeat(h[:, :, None], N_HISTORY, axis=2)
        else:
            self.hist = np.roll(self.hist, 1, axis=2)
            self.hist[:, :, 0] = h
        lagged = self.hist[:, :, list(LAG_STEPS)].reshape(n, -1)
        inst = [r.batch(obs, c) / sc[c] for c in INSTANT_CHANNELS]
        s = r.batch(obs, "comp_stroke")                     # fraction of the half stroke
        v = r.batch(obs, "comp_stroke_vel") / self.half     # half strokes per second
        a = np.abs(s)
        s2 = s * s
        out = s * v
        nl = {"stroke_abs": a, "stroke_sq": s2, "stroke_4": s2 * s2, "stroke_out": out,
              "stroke_out_pos": np.maximum(out, 0.0)}
        cols = inst + [nl[k] / sc[k] for k in NONLINEAR]
        parts = [lagged, np.stack(cols, axis=1)]
        if self.predictor is not None:
            p = self.predictor
            x = p.sample(np.stack([r.batch(obs, c) for c in p.channels], axis=1))
            self.pring = push(self.pring, x, first or self.pring is None)
            parts.append(p.predict(self.pring, self.pkeys))
        parts.append(np.ones((n, 1)))
        phi = np.concatenate(parts, axis=1)
        base = phi
        for on in self.gates:
            phi = np.concatenate([phi, base * on(r, obs)[:, None]], axis=1)
        if self.cable:
            c = np.stack([(r.batch(obs, ch) - CABLE_OFFSETS[ch]) / sc[ch] for ch in CABLE_CHANNELS], axis=1)
            if first or self.chist is None:
                self.chist = np.repeat(c[:, :, None], N_HISTORY, axis=2)
            else:
                self.chist = np.roll(self.chist, 1, axis=2)
                self.chist[:, :, 0] = c
            phi = np.concatenate([phi, self.chist[:, :, list(LAG_STEPS)].reshape(n, -1)], axis=1)
        return phi


def _residual(theta, phi):
    """Θ·φ per row: theta (n, 2, F), phi (n, F) -> (n, 2) (one arithmetic for the batch and the single env)."""
    return (theta * phi[:, None, :]).sum(axis=2)


def margin_penalty(s, m0: float = DEFAULT_MARGIN_START):
    """max(|s| − m0, 0)² element-wise (s = stroke as a fraction of the half stroke)."""
    return np.maximum(np.abs(np.asarray(s, float)) - float(m0), 0.0) ** 2


def entry_hit_weights(entries, hit_weight: float, hit_weights: dict | None = None) -> np.ndarray:
    """The hit weight of every ``(sea, base_seed)`` entry of the evaluation list: ``hit_weights[code]`` for the
    entries of a listed WMO code (code = base seed // 1000, the seeds being 1000·code + j), else ``hit_weight``.
    A listed code absent from ``entries`` is an error (a typo would silently change nothing)."""
    codes = [int(b) // 1000 for _s, b in entries]
    hw = {int(c): float(w) for c, w in (hit_weights or {}).items()}
    missing = sorted(set(hw) - set(codes))
    if missing:
        raise ValueError(f"hit_weights: codes {missing} are not sea states of the training set {sorted(set(codes))}")
    bad = [c for c, w in hw.items() if not (math.isfinite(w) and w >= 0)]
    if bad:
        raise ValueError(f"hit_weights: the weights of codes {bad} must be finite and >= 0")
    return np.array([hw.get(c, float(hit_weight)) for c in codes])


def parse_hit_weights(text: str | None) -> dict:
    """``"3:1.0,4:0.3"`` -> {3: 1.0, 4: 0.3} (the CLI's ``--hit-weights``); empty/None -> {}."""
    out = {}
    for part in (text or "").split(","):
        if not part.strip():
            continue
        code, sep, w = part.partition(":")
        if not sep:
            raise ValueError(f"--hit-weights: {part!r} is not CODE:WEIGHT")
        out[int(code)] = float(w)
    return out


def stop_guard_mask(reader, obs, guard: float):
    """Rows of a batch of observations ``(n, obs_size)`` where the stop guard acts: |s| > guard and s · ṡ > 0
    (s = ``comp_stroke``, fraction of the half stroke; ṡ = ``comp_stroke_vel``); all False when guard is 0."""
    obs = np.asarray(obs)
    if not guard:
        return np.zeros(obs.shape[0], bool)
    s = reader.batch(obs, "comp_stroke")
    sd = reader.batch(obs, "comp_stroke_vel")
    return (np.abs(s) > float(guard)) & (s * sd > 0.0)


def _apply_guard(a, reader, obs, guard: float):
    """(1, 1) — maximum stiffness and damping — on the rows of ``a`` (n, 2) where the stop guard acts."""
    if not guard:
        return a
    return np.where(stop_guard_mask(reader, obs, guard)[:, None], 1.0, a)


# ============================================================================ the policy (one environment)
class ARSCompensatorPolicy:
    """A trained linear residual over skyhook (module docstring) with SB3's ``predict``. Bind it to the
    environment it acts in with :meth:`bind_env` (``scripts/evaluate.py`` does); pass ``episode_start=True`` on
    the first step of every episode (it reads the sea-state estimate then and clears its memory)."""
    acts_on = "observations (and their history) + sea state"

    def __init__(self, theta: dict, base_table: dict, scales: dict | None = None, meta: dict | None = None,
                 name: str = "ars_compensator", predictor=None):
        self.feature_set = str((meta or {}).get("feature_set") or "h")
        _check_predictor(self.feature_set, predictor, "ARSCompensatorPolicy")
        self.predictor = predictor
        nf = n_features(self.feature_set)
        self.theta = {k: np.asarray(v, float) for k, v in theta.items()}
        bad = [k for k, v in self.theta.items() if v.shape != (N_ACT, nf)]
        if bad:
            raise ValueError(f"ARSCompensatorPolicy: theta entries {bad} are not ({N_ACT}, {nf}) (feature set "
                             f"{self.feature_set!r})")
        self.base_table = dict(base_table)
        self.scales = dict(FEATURE_SCALES | (scales or {}))
        self.meta = dict(meta or {})
        self.meta.setdefault("algo", ALGO)
        self.meta.setdefault("env_id", ENV_ID)
        self.meta.setdefault("env_kwargs", {})
        self.meta.setdefault("stop_guard", 0.0)
        self.meta["feature_set"] = self.feature_set
        self.stop_guard = float(self.meta["stop_guard"] or 0.0)
        if not 0.0 <= self.stop_guard <= 1.0:
            raise ValueError(f"ARSCompensatorPolicy: stop_guard must be 0 (off) or in (0, 1] (got {self.stop_guard})")
        self.name = name
        self.env = None
        self._th = None
        self._feat = None

    def bind_env(self, env):
        from .classical import SkyhookCompensator
        self.env = env
        self.base = SkyhookCompensator(env, table=self.base_table)
        self.reader = self.base.reader
        self.u = env.unwrapped
        self._feat = _Features(self.reader, self.u.half_stroke, self.scales, self.predictor,
                                gates=gate_functions(self.feature_set), cable=self.feature_set in CABLE)
        self._th = None
        return self

    def reset(self, env=None):
        if env is not None:
            self.bind_env(env)
        self._th = None

    def predict(self, obs, state=None, episode_start=None, deterministic: bool = True):
        if self.env is None:
            raise RuntimeError("ARSCompensatorPolicy: call bind_env(env) before predict()")
        o = np.asarray(obs, dtype=float)
        if o.ndim == 2:
            o = o[0]
        start = episode_start is not None and bool(np.any(episode_start))
        first = start or self._th is None
        if first:
            self.base.reset()
            self._th = self.theta[nearest_key(self.theta, self.u.sea[0])][None]
            if self.predictor is not None:
                self._feat.pkeys = [nearest_key(self.predictor.W, self.u.sea[0])]
        a_base = np.asarray(self.base.act(o), float)
        o32 = np.asarray(obs, np.float32).reshape(1, -1)
        phi = self._feat(o32, first)
        a = np.clip(a_base + _residual(self._th, phi)[0], -1.0, 1.0)
        a = _apply_guard(a[None], self.reader, o32, self.stop_guard)[0]
        out = a.astype(np.float32)
        return (out[None, :] if np.asarray(obs).ndim == 2 else out), state


# ============================================================================ batched rollouts (training)
def _to_action_py(g, lo, hi):
    """``CompensatorGainsEnv._to_action`` element-wise, with ``math.log`` (the single env's arithmetic): the plain
    Python twin of :func:`_to_action`."""
    if hi <= lo:
        return np.full(len(g), -1.0)
    den = math.log(hi / lo)
    x = np.array([2.0 * math.log(gi / lo) / den - 1.0 if gi > 0 else -1.0 for gi in g])
    return np.clip(x, -1.0, 1.0)


@njit(cache=True)
def _to_action_kernel(g, lo, hi, out):
    den = math.log(hi / lo)
    for i in range(g.shape[0]):
        gi = g[i]
        x = 2.0 * math.log(gi / lo) / den - 1.0 if gi > 0 else -1.0
        if x < -1.0:
            x = -1.0
        elif x > 1.0:
            x = 1.0
        out[i] = x


def _to_action(g, lo, hi):
    """:func:`_to_action_py` compiled (numba's ``math.log`` is the C library's, as Python's: the same bits, tested):
    the list of ``math.log`` calls was ~4 % of a Gauss–Newton training rollout's wall time on both cores."""
    if hi <= lo:
        return np.full(len(g), -1.0)
    out = np.empty(len(g))
    _to_action_kernel(np.ascontiguousarray(g, dtype=float), float(lo), float(hi), out)
    return out


class _Batch:
    """The skyhook law (``classical.SkyhookCompensator.gains`` + ``env.action_of``, element-wise) and the
    features for a batch of observations."""

    def __init__(self, venv, base_table: dict, scales: dict, feature_set: str = "h", predictor=None):
        _check_predictor(feature_set, predictor, "ars_compensator._Batch")
        e0 = venv.envs[0]
        self.reader = ObsReader(e0)
        self.kmap, self.bmap = e0.stiffness_range, e0.damping_range
        self.table = base_table
        self.feature_set = feature_set
        self.features = _Features(self.reader, e0.half_stroke, scales, predictor, gates=gate_functions(feature_set),
                                  cable=feature_set in CABLE)

    def load_rows(self, source: "_Batch", src) -> None:
        """Row i's feature history from ``source``'s row src[i] (:meth:`_Features.load_rows`; the sea states are
        set with :meth:`set_seas`)."""
        self.features.load_rows(source.features, np.asarray(src, np.int64))

    def set_seas(self, seas):
        from .classical import DEFAULT_SKYHOOK_GAINS
        if self.features.predictor is not None:
            self.features.pkeys = [nearest_key(self.features.predictor.W, s) for s in seas]
        self.G = np.array([[float((DEFAULT_SKYHOOK_GAINS | self.table[nearest_key(self.table, s)])[k])
                            for k in GAIN_KEYS] for s in seas])

    def base_action(self, obs):
        r, G = self.reader, self.G
        k_lo, k_hi = self.kmap[0], self.kmap[1]
        b_lo, b_hi = self.bmap[0], self.bmap[1]
        s = r.batch(obs, "comp_stroke")
        sd = r.batch(obs, "comp_stroke_vel")
        z_abs = r.batch(obs, "tow_vel_z") + sd
        b0 = np.minimum(np.maximum(G[:, 1], b_lo), b_hi)
        on = (z_abs * sd > 0.0) & (np.abs(sd) > 1e-6)
        sky = np.minimum(np.maximum(G[:, 0] * z_abs / np.where(on, sd, 1.0), b0), b_hi)
        b = np.where(on, sky, b0)
        m = np.minimum(np.maximum(G[:, 3], 1e-3), 1.0)
        x = (np.abs(s) - (1.0 - m)) / m
        k0 = np.minimum(np.maximum(G[:, 2], k_lo), k_hi)
        k = k0 + np.maximum(G[:, 4] - k0, 0.0) * np.minimum(np.maximum(x, 0.0), 1.0)
        k = np.minimum(np.maximum(k, k_lo), k_hi)
        return np.stack([_to_action(k, self.kmap[0], self.kmap[1]), _to_action(b, self.bmap[0], self.bmap[1])],
                        axis=1)


def rollout_series(venv, batch: _Batch, seas, seeds, theta, record_actions: bool = False, stop_guard: float = 0.0):
    """One episode in every copy of ``venv`` (copy i in (seas[i], seeds[i]) with weights theta[i], (2, F), and the
    stop guard ``stop_guard``); returns per control step the fish heave (m), pitch (rad) and the ``comp_stroke``
    observation after the step (fraction of the half stroke), ``(T, n)`` each, the time of each step, the end-stop
    hits of the whole episode and a per-copy flag of copies that ended early (and with ``record_actions`` the
    actions (T, n, 2) as stepped)."""
    n = venv.num_envs
    obs = reset_copies(venv, seas, seeds)
    batch.set_seas(seas)
    out = _series_arrays(venv.envs[0].max_steps, n, record_actions)
    _run_steps(venv, batch, obs, np.asarray(theta, float), 0, out, stop_guard)
    return out


def rollout_series_shared(venv_w, batch_w: _Batch, venv, batch: _Batch, seas, seeds, theta_w, theta, warm_steps: int,
                          stop_guard: float = 0.0):
    """:func:`rollout_series` of every copy i of ``venv`` — episode e = i mod n_w of the ``n_w`` = ``venv_w.num_envs``
    episodes (seas[e], seeds[e]), weights theta[i] — whose first ``warm_steps`` control steps are *shared*: run once per
    episode in ``venv_w`` with weights ``theta_w[e]`` and loaded into every copy of that episode
    (``TowVectorEnv.load_copies``; the features' history rows likewise), which then continues with its own weights.
    The rows before ``warm_steps`` are the warm-up's. With theta[i] = theta_w[i mod n_w] for every i the result is
    :func:`rollout_series` under those weights, bit for bit (tested); the warm-up's cost is paid n_w times instead
    of n."""
    n_w, n = venv_w.num_envs, venv.num_envs
    if len(seas) != n_w or len(seeds) != n_w or n % n_w:
        raise ValueError(f"rollout_series_shared: one (sea, seed) per warm-up copy ({n_w}) and a multiple of "
                         f"them in venv (got {len(seas)}, {len(seeds)} and {n})")
    T = venv.envs[0].max_steps
    if venv_w.envs[0].max_steps != T or not 0 < int(warm_steps) < T:
        raise ValueError(f"rollout_series_shared: warm_steps must be in 1..{T - 1} and both vector envs' episodes "
                         f"{T} control steps (got {warm_steps}, {venv_w.envs[0].max_steps})")
    warm = int(warm_steps)
    obs_w = reset_copies(venv_w, seas, seeds)
    batch_w.set_seas(seas)
    out_w = _series_arrays(T, n_w, False)
    obs_w = _run_steps(venv_w, batch_w, obs_w, np.asarray(theta_w, float), 0, out_w, stop_guard, stop=warm)
    reps = n // n_w
    reset_copies(venv, list(seas) * reps, list(seeds) * reps)
    batch.set_seas(list(seas) * reps)
    src = np.arange(n) % n_w
    venv.load_copies(venv_w, src, np.arange(n))
    batch.load_rows(batch_w, src)
    out = _series_arrays(T, n, False)
    for a, b in zip(out[:4], out_w[:4]):
        a[:warm] = b[:warm][:, src] if b.ndim == 2 else b[:warm]
    out[4][:] = out_w[4][src]
    out[5][:] = out_w[5][src]
    _run_steps(venv, batch, obs_w[src], np.asarray(theta, float), warm, out, stop_guard)
    return out


def _series_arrays(T, n, record_actions):
    """The per-step arrays of :func:`rollout_series`: H, P, S (T, n), t (T,), hits (n,), ended (n,), actions."""
    return (np.zeros((T, n)), np.zeros((T, n)), np.zeros((T, n)), np.zeros(T), np.zeros(n), np.zeros(n, bool),
            np.zeros((T, n, N_ACT), np.float32) if record_actions else None)


def _run_steps(venv, batch: _Batch, obs, theta, start, out, stop_guard, stop=None):
    """Control steps ``start`` … ``stop`` − 1 (default: to the episode's end) of :func:`rollout_series` from the
    observations ``obs``, filling ``out`` (:func:`_series_arrays`); returns the last observations."""
    H, P, S, t, hits, ended, acts = out
    T = len(t)
    for k in range(start, T if stop is None else stop):
        phi = batch.features(obs, k == 0)
        a = np.clip(batch.base_action(obs) + _residual(theta, phi), -1.0, 1.0)
        a = _apply_guard(a, batch.reader, obs, stop_guard).astype(np.float32)
        if acts is not None:
            acts[k] = a
        obs, _r, term, trunc, infos = venv.step(a)
        H[k] = infos["fish_heave"]
        P[k] = infos["fish_pitch"]
        S[k] = batch.reader.batch(obs, "comp_stroke")
        t[k] = infos["t"][0]
        hits += np.where(ended, 0, infos["end_stop_hits"])
        if k < T - 1:
            ended |= term | trunc
    return obs


def rollout_batch(venv, batch: _Batch, seas, seeds, theta, discard: float = 60.0, record_actions: bool = False,
                  margin_start: float = DEFAULT_MARGIN_START, stop_guard: float = 0.0):
    """One episode in every copy of ``venv`` (:func:`rollout_series`); returns σ(fish heave) (m) and σ(pitch) (deg)
    over t ≥ discard, the end-stop hits of the whole episode and the mean over t ≥ discard of
    :func:`margin_penalty` (|s|, ``margin_start``) of the ``comp_stroke`` observation after every step, per copy
    (σ and margin NaN for a copy that ended early), and with ``record_actions`` the actions (T, n, 2) as stepped."""
    H, P, S, t, hits, ended, acts = rollout_series(venv, batch, seas, seeds, theta, record_actions, stop_guard)
    w = t >= discard
    sh = H[w].std(axis=0)
    sp = np.degrees(P[w].std(axis=0))
    mg = margin_penalty(S[w], margin_start).mean(axis=0)
    sh[ended] = np.nan
    sp[ended] = np.nan
    mg[ended] = np.nan
    return (sh, sp, hits, mg, acts) if record_actions else (sh, sp, hits, mg)


def _setup(episode_seconds: float, n_copies: int, scales: dict, feature_set: str = "h", parallel: bool = False):
    import gymnasium as gym
    __import__("towenv")                    # registers the ids
    from towenv.envs.vector import CompensatorGainsVectorEnv
    from .baselines import load_tuned
    table = dict(load_tuned().get("skyhook") or {})
    if not table:
        raise RuntimeError("no tuned skyhook table (agents/hyperparams/baselines.yml): run python -m agents.tuning")
    env = gym.make(ENV_ID)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    venv = CompensatorGainsVectorEnv(num_envs=n_copies, autoreset_mode="NextStep", batch_infos=True,
                                     episode_seconds=float(episode_seconds), parallel=bool(parallel))
    return table, ev, venv, _Batch(venv, table, scales, feature_set)


def measure_scales(seed: int = 0, episode_seconds: float = 180.0) -> dict:
    """The standard deviation of every feature (before scaling) under the skyhook law on the 12 training-seed
    episodes of iteration 0 of training seed ``seed``, pooled over all steps (how :data:`FEATURE_SCALES` was
    measured)."""
    unit = {k: 1.0 for k in FEATURE_SCALES}
    probe = _setup(episode_seconds, 12, unit, "hst")
    table, ev, venv, batch = probe
    seas = [s for s, _ in ev]
    seeds = [_train_seed(b, 0, seed) for _, b in ev]
    obs = reset_copies(venv, seas, seeds)
    batch.set_seas(seas)
    rows = []
    for k in range(venv.envs[0].max_steps):
        phi = batch.features(obs, k == 0)
        rows.append(phi)
        obs, *_ = venv.step(batch.base_action(obs).astype(np.float32))
    venv.close()
    X = np.concatenate(rows, axis=0)
    names = feature_names("hst")
    out = {}
    for c in HISTORY_CHANNELS + CABLE_CHANNELS:
        out[c] = float(X[:, names.index(f"{c}@-0.0s")].std())
    for c in list(INSTANT_CHANNELS) + list(NONLINEAR):
        out[c] = float(X[:, names.index(c)].std())
    return {k: float(f"{v:.4g}") for k, v in out.items()}


# ============================================================================ training
def train(seed: int = 0, minutes: float = 30.0, max_iterations: int = MAX_ITERATIONS, directions: int = 8,
          top: int = 4, nu: float = 0.01, alpha: float = 0.01, pitch_weight: float = 0.5,
          hit_weight: float = DEFAULT_HIT_WEIGHT, episode_seconds: float = 180.0, fail_penalty: float = 1.0,
          margin_weight: float = DEFAULT_MARGIN_WEIGHT, margin_start: float = DEFAULT_MARGIN_START,
          stop_guard: float = 0.0, hit_weights: dict | None = None, progress: bool = True,
          parallel: bool = False, log=print) -> ARSCompensatorPolicy:
    """ARS V1-t (module docstring) on the 12 evaluation (Hs, Tp, heading) entries with training wave seeds; one
    search per sea state of the skyhook table, sharing one batched rollout per iteration. Cost of an episode:
    ln(σ_h/σ_h,sky) + pitch_weight · ln(σ_θ/σ_θ,sky) + hit_weight · hits + margin_weight · mean max(|s| −
    margin_start, 0)² on the same waves (``margin_weight=0, hit_weight=0.05``: the first probe's cost), with the
    stop guard ``stop_guard`` (0 = off) in every rollout and in the returned policy. ``hit_weights`` ({WMO code:
    w}, :func:`entry_hit_weights`) replaces hit_weight in the episodes of the listed codes. Stops after
    ``max_iterations`` (≤ :data:`MAX_ITERATIONS`) or when the next iteration would pass ``minutes`` of wall time.
    ``parallel``: step the batch's copies on all numba threads (the vector env's ``parallel=True``; every copy is
    independent, so the result is the same as serial, bit for bit — only the wall time changes)."""
    if not 1 <= int(max_iterations) <= MAX_ITERATIONS:
        raise ValueError(f"max_iterations must be in 1..{MAX_ITERATIONS} (training seeds stay disjoint)")
    t_start = time.perf_counter()
    import gymnasium as gym
    __import__("towenv")
    from .baselines import load_tuned
    table = dict(load_tuned().get("skyhook") or {})
    env = gym.make(ENV_ID)
    ev0 = env.unwrapped.eval_sea_states()
    env.close()
    keys0 = sorted(table)
    ent = {k: [i for i, (sea, _s) in enumerate(ev0) if nearest_key(table, sea) == k] for k in keys0}
    keys = [k for k in keys0 if ent[k]]
    w_hit = entry_hit_weights(ev0, hit_weight, hit_weights)         # per evaluation entry
    hit_weights = {int(c): float(w) for c, w in (hit_weights or {}).items()}
    codes = [int(b) // 1000 for _s, b in ev0]
    code_set = sorted(set(codes))
    C, K = len(keys), int(directions)
    n_pert = sum(2 * K * len(ent[k]) for k in keys)
    n_ref = len(ev0)
    n_copies = n_pert + 2 * n_ref
    table, ev, venv, batch = _setup(episode_seconds, n_copies, dict(FEATURE_SCALES), parallel=parallel)
    rng = np.random.default_rng(int(seed))
    theta = np.zeros((C, N_ACT, N_FEATURES))
    curve = []
    log(f"[ars_comp] seed {seed}: {C} sea states x {K} directions x 2 signs + 2 x {n_ref} reference episodes = "
        f"{n_copies} copies of {episode_seconds:g} s per iteration; nu={nu} alpha={alpha} top={top} "
        f"pitch_weight={pitch_weight} hit_weight={hit_weight} margin_weight={margin_weight} "
        f"margin_start={margin_start} stop_guard={stop_guard} hit_weights={hit_weights or 'none'}; "
        f"{N_ACT} x {N_FEATURES} weights per sea state")
    it = 0
    last = 0.0
    while it < max_iterations:
        elapsed = time.perf_counter() - t_start
        if elapsed + last > 60.0 * minutes:
            break
        t0 = time.perf_counter()
        delta = rng.standard_normal((C, K, N_ACT, N_FEATURES))
        seas, seeds, th, owner = [], [], [], []
        for ci, k in enumerate(keys):
            for d in range(K):
                for sign in (1.0, -1.0):
                    for e in ent[k]:
                        seas.append(ev[e][0])
                        seeds.append(_train_seed(ev[e][1], it, seed))
                        th.append(theta[ci] + sign * nu * delta[ci, d])
                        owner.append(e)
        for which in ("theta", "skyhook"):
            for e, (sea, s) in enumerate(ev):
                ci = keys.index(nearest_key(table, sea))
                seas.append(sea)
                seeds.append(_train_seed(s, it, seed))
                th.append(theta[ci] if which == "theta" else np.zeros((N_ACT, N_FEATURES)))
        sh, sp, hits, mg = rollout_batch(venv, batch, seas, seeds, np.array(th), margin_start=margin_start,
                                         stop_guard=stop_guard)
        cur_h, base_h = sh[n_pert:n_pert + n_ref], sh[n_pert + n_ref:]
        cur_m, base_m = mg[n_pert:n_pert + n_ref], mg[n_pert + n_ref:]
        cur_p, base_p = sp[n_pert:n_pert + n_ref], sp[n_pert + n_ref:]
        cur_hits, base_hits = hits[n_pert:n_pert + n_ref], hits[n_pert + n_ref:]
        with np.errstate(invalid="ignore", divide="ignore"):
            cost = np.where(np.isfinite(sh[:n_pert]),
                            np.log(sh[:n_pert] / base_h[owner]) + pitch_weight * np.log(sp[:n_pert] / base_p[owner])
                            + w_hit[owner] * hits[:n_pert] + margin_weight * mg[:n_pert],
                            fail_penalty + w_hit[owner] * hits[:n_pert])
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
            step = alpha / (top * sd) * np.einsum("d,dcf->cf", rp[order] - rm[order], delta[ci, order])
            theta[ci] += step
            steps.append(float(np.linalg.norm(step)))
        pooled_h = float(np.nanmean(cur_h) / np.nanmean(base_h))
        pooled_p = float(np.nanmean(cur_p) / np.nanmean(base_p))
        last = time.perf_counter() - t0
        curve.append({"iteration": it, "heave_ratio": pooled_h, "pitch_ratio": pooled_p, "hits": float(cur_hits.sum()),
                      "hits_skyhook": float(base_hits.sum()), "hits_perturbed_mean": float(hits[:n_pert].mean()),
                      "margin": float(np.nanmean(cur_m)), "margin_skyhook": float(np.nanmean(base_m)),
                      "cost": float(np.nanmean(np.log(cur_h / base_h) + pitch_weight * np.log(cur_p / base_p)
                                               + w_hit * cur_hits + margin_weight * cur_m)),
                      "hits_by_code": {str(c): float(cur_hits[np.array(codes) == c].sum()) for c in code_set},
                      "hits_skyhook_by_code": {str(c): float(base_hits[np.array(codes) == c].sum())
                                               for c in code_set},
                      "seconds": last, "failures": int(np.sum(~np.isfinite(sh)))})
        if progress:
            log(f"[ars_comp] it {it:3d} ({last:5.1f} s, {(time.perf_counter() - t_start) / 60:5.1f} min): policy "
                f"before this step vs skyhook on {n_ref} fresh training episodes: heave {100 * (pooled_h - 1):+6.2f} %, "
                f"pitch {100 * (pooled_p - 1):+5.1f} %, hits {int(cur_hits.sum())} (by code "
                f"{'/'.join(str(int(cur_hits[np.array(codes) == c].sum())) for c in code_set)}; skyhook "
                f"{int(base_hits.sum())}; "
                f"perturbed mean {hits[:n_pert].mean():.2f}/episode); margin {np.nanmean(cur_m):.2e} (skyhook "
                f"{np.nanmean(base_m):.2e}); |step| {', '.join(f'{s:.4f}' for s in steps)}")
        it += 1
    steps_per_episode = int(venv.envs[0].max_steps)
    venv.close()
    wall = time.perf_counter() - t_start
    meta = {"algo": ALGO, "env_id": ENV_ID, "env_kwargs": {}, "seed": int(seed), "iterations": it,
            "stop_guard": float(stop_guard),
            "num_timesteps": it * n_copies * steps_per_episode, "wall_seconds": wall, "parallel": bool(parallel),
            "hyperparameters": {"directions": K, "top": top, "nu": nu, "alpha": alpha, "pitch_weight": pitch_weight,
                                "hit_weight": hit_weight, "episode_seconds": episode_seconds, "minutes": minutes,
                                "max_iterations": max_iterations, "fail_penalty": fail_penalty,
                                "margin_weight": margin_weight, "margin_start": margin_start,
                                "stop_guard": float(stop_guard),
                                "hit_weights": {str(c): w for c, w in sorted(hit_weights.items())}},
            "train_seeds": f"1000*code + j + {TRAIN_SEED_OFFSET} + 100*iteration + 100000*{int(seed)}",
            "curve": curve}
    return ARSCompensatorPolicy({k: theta[ci] for ci, k in enumerate(keys)}, table, FEATURE_SCALES, meta,
                                name=f"ars_compensator_s{seed}")


# ============================================================================ files
def save_policy(policy: ARSCompensatorPolicy, path: str | Path) -> Path:
    """Write the policy as an .npz (weights per sea-state key, the base's gain table, scales, metadata JSON with
    ``env_id`` and ``algo``), atomically."""
    fs = policy.feature_set
    meta = dict(policy.meta) | {"feature_set": fs, "features": feature_names(fs), "lag_steps": list(LAG_STEPS),
                                "history_channels": list(HISTORY_CHANNELS), "instant_channels": list(INSTANT_CHANNELS),
                                "nonlinear": list(NONLINEAR)}
    extra = policy.predictor.arrays() if policy.predictor is not None else None
    return save_ars_file(path, policy.theta, policy.base_table, policy.scales, meta, extra)


def load_policy(path: str | Path) -> ARSCompensatorPolicy:
    """Read a policy written by :func:`save_policy` (bind it to an environment before use)."""
    def names_for(meta):
        fs = meta.get("feature_set") or "h"
        if fs not in FEATURE_SETS:
            raise ValueError(f"{path}: unknown compensator feature set {fs!r} (this version knows "
                             f"{', '.join(FEATURE_SETS)})")
        return feature_names(fs)
    theta, table, scales, meta = read_ars_file(path, names_for, {"env_id": ENV_ID, "algo": ALGO},
                                               "an ARS skyhook-residual policy")
    fs = meta.get("feature_set") or "h"
    predictor = from_policy_file(path, fs) if fs in PREDICTED else None
    return ARSCompensatorPolicy(theta, table, scales, meta, name=Path(path).stem, predictor=predictor)


def lift_policy(policy: ARSCompensatorPolicy, feature_set: str) -> ARSCompensatorPolicy:
    """``policy`` written in the larger feature set ``feature_set``: its weights copied by feature name, the features
    it lacks at weight 0, so it acts as before (e.g. a fish-gated ``hsf`` iterate in the outward-gated ``hsfo`` set of
    the stage after it, for :func:`average_policies`). ValueError naming the features ``feature_set`` lacks if it is
    not a superset of the policy's (or if the policy has a predictor and ``feature_set`` is not predicted alike)."""
    mine, target = feature_names(policy.feature_set), feature_names(feature_set)
    lost = [nm for nm in mine if nm not in target]
    if lost:
        raise ValueError(f"lift_policy: feature set {feature_set!r} lacks {len(lost)} features of {policy.name}'s "
                         f"{policy.feature_set!r} (e.g. {', '.join(lost[:3])}); it can only add features")
    if feature_set == policy.feature_set:
        return policy
    if policy.predictor is not None and feature_set not in PREDICTED:
        raise ValueError(f"lift_policy: {policy.name} has a predictor; feature set {feature_set!r} does not use one")
    keys = sorted(policy.theta)
    from .common import weights_by_name
    theta = weights_by_name(policy.theta, keys, mine, target, (N_ACT,))
    meta = dict(policy.meta) | {"feature_set": feature_set, "lifted_from": policy.feature_set}
    return ARSCompensatorPolicy(dict(zip(keys, theta)), policy.base_table, policy.scales, meta, name=policy.name,
                                predictor=policy.predictor)


#: metadata fields a weight average keeps of each member (with its ``init``: what the report says of each member)
MEMBER_FIELDS = ("algo", "method", "seed", "iterations", "first_iteration", "feature_set")


def average_policies(policies: list, seed: int) -> ARSCompensatorPolicy:
    """The policy whose weights are the mean of ``policies``' weights, sea state by sea state (the residual is linear
    in its weights, so it is also the mean of their log-gain residuals before the action clip). The members must be
    one class acting alike: the same feature set, feature scales, skyhook gain table, stop guard, environment
    keywords and sea-state keys, and the same stored predictor or none (ValueError naming the differing field and
    members otherwise; the average keeps the members' predictor). ``seed`` labels the average (its members carry
    their own training seeds); ``meta["averaged_from"]`` lists the members' names (scripts/training_cost.py follows
    them to the members' files and their ``--init`` chains) and ``meta["members"]`` their training records
    (``init`` included; the report's description)."""
    if len(policies) < 2:
        raise ValueError(f"average_policies: needs at least 2 policies (got {len(policies)})")
    first = policies[0]
    names = [p.name for p in policies]
    if len(set(names)) != len(names):
        raise ValueError(f"average_policies: a member appears twice ({', '.join(names)})")

    def same(field, value):
        a = value(first)
        for p in policies[1:]:
            b = value(p)
            equal = (a.keys() == b.keys() and all(np.array_equal(np.asarray(a[k]), np.asarray(b[k])) for k in a)
                     if isinstance(a, dict) and isinstance(b, dict) else a == b)
            if not equal:
                raise ValueError(f"average_policies: {field} differs between {first.name} ({a!r}) and {p.name} "
                                 f"({b!r}); a weight average needs members of one class acting alike")
    same("feature_set", lambda p: p.feature_set)
    same("feature scales", lambda p: p.scales)
    same("skyhook gain table (base_table)", lambda p: p.base_table)
    same("stop_guard", lambda p: p.stop_guard)
    same("env_kwargs", lambda p: p.meta.get("env_kwargs") or {})
    same("sea-state keys of theta", lambda p: sorted(p.theta))
    same("predictor (SHA-1 of its arrays)", _predictor_digest)
    theta = {k: np.mean([p.theta[k] for p in policies], axis=0) for k in first.theta}
    members = [{"name": p.name, **{f: p.meta.get(f) for f in MEMBER_FIELDS},
                "init": (p.meta.get("hyperparameters") or {}).get("init")} for p in policies]
    meta = {"algo": ALGO, "method": "weight-average", "env_id": ENV_ID,
            "env_kwargs": dict(first.meta.get("env_kwargs") or {}), "seed": int(seed),
            "stop_guard": first.stop_guard, "feature_set": first.feature_set, "averaged_from": names,
            "members": members, "num_timesteps": 0, "curve": []}
    return ARSCompensatorPolicy(theta, first.base_table, first.scales, meta, name=f"average_s{seed}",
                                predictor=first.predictor)


def _predictor_digest(policy) -> str | None:
    """SHA-1 over a policy's stored predictor (its weights, scales and metadata as saved), None without one."""
    if policy.predictor is None:
        return None
    h = hashlib.sha1()
    for key, arr in sorted(policy.predictor.arrays().items()):
        arr = np.asarray(arr)
        h.update(key.encode())
        h.update(str(arr.dtype).encode() + str(arr.shape).encode())
        h.update(arr.tobytes())
    return h.hexdigest()


def main(argv=None) -> int:
    """``python scripts/train_ars_compensator.py --seed 0 --minutes 30 --export runs/ars_CompensatorGains-v0_s0.npz``"""
    import argparse
    ap = argparse.ArgumentParser(description="Train an ARS linear residual over the skyhook law "
                                             "(towenv/CompensatorGains-v0); agents/ars_compensator.py explains it.")
    ap.add_argument("--seed", type=int, default=0, help="training seed: ARS directions and training wave seeds")
    ap.add_argument("--minutes", type=float, default=30.0, help="wall-clock budget (default 30)")
    ap.add_argument("--max-iterations", type=int, default=MAX_ITERATIONS, help=f"at most {MAX_ITERATIONS}")
    ap.add_argument("--directions", type=int, default=8)
    ap.add_argument("--top", type=int, default=4)
    ap.add_argument("--nu", type=float, default=0.01, help="exploration noise in parameter space")
    ap.add_argument("--alpha", type=float, default=0.01, help="step size")
    ap.add_argument("--pitch-weight", type=float, default=0.5, help="weight of ln(σ_pitch ratio) in the cost")
    ap.add_argument("--hit-weight", type=float, default=DEFAULT_HIT_WEIGHT,
                    help=f"cost of one end-stop hit (in ln σ units; default {DEFAULT_HIT_WEIGHT}; the first probe: 0.05)")
    ap.add_argument("--hit-weights", default="",
                    help="per-sea-state hit weights CODE:W[,CODE:W...] (WMO codes of the training set, e.g. "
                         "3:1.0); the other codes keep --hit-weight (default: none)")
    ap.add_argument("--margin-weight", type=float, default=DEFAULT_MARGIN_WEIGHT,
                    help="weight of the stroke-margin term mean max(|s| - m0, 0)^2 over the scored window "
                         f"(default {DEFAULT_MARGIN_WEIGHT:g}; 0 = the first probe's cost)")
    ap.add_argument("--margin-start", type=float, default=DEFAULT_MARGIN_START,
                    help=f"m0 of the stroke-margin term, fraction of the half stroke (default {DEFAULT_MARGIN_START})")
    ap.add_argument("--stop-guard", type=float, default=0.0,
                    help="stop guard threshold g in (0, 1]: (max stiffness, max damping) when |s| > g and moving "
                         "outward; stored in the policy file (default 0 = off; e.g. 0.9)")
    ap.add_argument("--episode-seconds", type=float, default=180.0, help="training episode length (s; >= 120)")
    ap.add_argument("--measure-scales", action="store_true", help="print the feature scales (skyhook, training "
                                                                  "seeds of iteration 0) and exit")
    add_parallel_flag(ap)
    ap.add_argument("--export", default=None, help="policy file (default runs/ars_CompensatorGains-v0_s<seed>.npz)")
    a = ap.parse_args(argv)
    for name in ("minutes", "nu", "alpha", "episode_seconds"):
        v = getattr(a, name)
        if not (math.isfinite(v) and v > 0):
            ap.error(f"--{name.replace('_', '-')} must be a positive number (got {v})")
    if a.directions < 1 or not 1 <= a.top <= a.directions or not 1 <= a.max_iterations <= MAX_ITERATIONS \
            or not a.pitch_weight >= 0 or not a.hit_weight >= 0 or a.seed < 0 or not a.margin_weight >= 0 \
            or not 0 <= a.margin_start < 1 or not 0 <= a.stop_guard <= 1:
        ap.error(f"need --directions >= 1, 1 <= --top <= --directions, 1 <= --max-iterations <= {MAX_ITERATIONS}, "
                 f"--pitch-weight >= 0, --hit-weight >= 0, --margin-weight >= 0, 0 <= --margin-start < 1, "
                 f"0 <= --stop-guard <= 1, --seed >= 0")
    try:
        hit_weights = parse_hit_weights(a.hit_weights)
        if any(not (math.isfinite(w) and w >= 0) for w in hit_weights.values()):
            raise ValueError("--hit-weights: every weight must be finite and >= 0")
    except ValueError as exc:
        ap.error(str(exc))
    if a.episode_seconds < 120.0:
        ap.error("--episode-seconds must be >= 120 (the score starts at 60 s)")
    if a.measure_scales:
        print(json.dumps(measure_scales(a.seed, a.episode_seconds)))
        return 0
    out = Path(a.export or f"runs/ars_CompensatorGains-v0_s{a.seed}.npz")
    pol = train(a.seed, a.minutes, a.max_iterations, a.directions, a.top, a.nu, a.alpha, a.pitch_weight,
                a.hit_weight, a.episode_seconds, margin_weight=a.margin_weight, margin_start=a.margin_start,
                stop_guard=a.stop_guard, hit_weights=hit_weights, parallel=a.parallel)
    save_policy(pol, out)
    print(f"[ars_comp] wrote {out} ({pol.meta['iterations']} iterations, {pol.meta['wall_seconds'] / 60:.1f} min)")
    return 0
