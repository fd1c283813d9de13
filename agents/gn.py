"""Gauss–Newton policy search for the WinchPayout linear residual (the ARS policy class of ``agents/ars.py``).

ARS learns θ from one number per episode (its cost). But an episode gives a whole time series — the fish heave and
pitch at every control step — and θ enters linearly into the action. This search uses that series:

1. **Jacobian by finite differences on the simulator.** For the current θ, run the batch of training episodes
   (one per (sea state, heading) and replicate; fresh wave seeds every iteration) once as it is and once per
   feature i with θ_i + ε (``ε = 0.005``; every sea state's θ perturbed in the same copy — an episode only sees its
   own sea state's weights). J_i = (y(θ + ε e_i) − y(θ))/ε over the scored window, for heave and pitch, each with
   its window mean removed. The simulator is deterministic, so J is the secant of the real closed loop, winch
   limits, slack and feedback features included — what the one-shot linear design (``scripts/probe_linear_design.py``)
   misses.
2. **Gauss–Newton step per sea state**: minimise Σ_e ‖y_e + J_e Δθ‖²/σ_h,e² + w_p ‖p_e + J^p_e Δθ‖²/σ_p,e²
   + λ·(mean diagonal)·‖Δθ‖² — the linearisation of the ARS cost ln σ_h + w_p ln σ_p — for each ridge λ in
   ``ridges``.
3. **Line search on fresh episodes** (other wave seeds than step 1): θ, θ + Δθ(λ) for each λ and the along-cable law
   on the same waves; per sea state keep the candidate with the lowest mean cost
   ln(σ_h/σ_h,along) + w_p ln(σ_p/σ_p,along) — no step if none beats the current θ.

The result is an :class:`agents.ars.ARSPolicy` (same features, same file format, ``meta["method"] =
"gauss-newton"``), so ``scripts/evaluate.py`` and everything that loads ARS policies load it unchanged.

Wave seeds: Jacobian episodes ``1000·code + j + 10·replicate + 80000 + 200·iteration + 100000·seed``, line-search
episodes the same + 100, for iterations 0–48; iterations 49–97 (continuations past that block) use
``1000·code + j + 10·replicate + 1000000 + 200·(iteration − 49) + 100000·seed`` (+ 100), above every other set;
iteration < :data:`MAX_ITERATIONS`, replicate < 10, training seed < 10 — never an evaluation (+0…400), tuning (+500), validation (+700), Hover
design (+900), final (+20000…), clairvoyant-teacher (+30000), ARS-training (+40000…, +50000…), probe (+75000,
+76000) or semi-active teacher-plan (+92000…) seed.
"""
from __future__ import annotations

import math
import os
import time
from pathlib import Path

import numpy as np

from . import ars
from .common import add_parallel_flag, nearest_key

__all__ = ["train", "train_seed", "initial_theta", "gauss_newton_steps", "replicates_per_sea_state", "MAX_ITERATIONS",
           "SEED_OFFSET", "SECOND_BLOCK_OFFSET", "ITERATIONS_PER_BLOCK", "main"]

#: wave seeds of the search: base seed (1000·code + j) + SEED_OFFSET + 200·iteration (+ 100 for the line search)
#: + 100000·training seed, for iterations 0 … ITERATIONS_PER_BLOCK − 1
SEED_OFFSET = 80000
#: 200·iteration + 100 stays below 10000: a run's seeds stay inside its own block of 10000
ITERATIONS_PER_BLOCK = 49
#: iterations ITERATIONS_PER_BLOCK … MAX_ITERATIONS − 1 (continuations past the first block) use a second block:
#: base seed + SECOND_BLOCK_OFFSET + 200·(iteration − ITERATIONS_PER_BLOCK) (+ 100) + 100000·training seed — above
#: every other wave-seed set of the project for training seeds 0 … 9 (the largest of those, a first-block seed of
#: training seed 9, is below 996000)
SECOND_BLOCK_OFFSET = 1_000_000
MAX_ITERATIONS = 2 * ITERATIONS_PER_BLOCK


def check_training_seed(seed) -> None:
    """ValueError naming the training seed unless it is an integer 0..9 (100000·seed keeps a run's seeds in its own
    block; 1.5 or "1" are refused, not truncated)."""
    import numbers
    if isinstance(seed, bool) or not isinstance(seed, numbers.Integral):
        raise ValueError(f"seed (the training seed) must be an integer in 0..9 (got {seed!r})")
    if not 0 <= int(seed) < 10:
        raise ValueError(f"seed (the training seed) must be in 0..9 (got {seed}; 100000·seed stays in its block)")


def train_seed(base_seed: int, iteration: int, seed: int, line_search: bool = False) -> int:
    if not 0 <= int(iteration) < MAX_ITERATIONS:
        raise ValueError(f"iteration must be in 0..{MAX_ITERATIONS - 1} (got {iteration})")
    check_training_seed(seed)
    block, k = divmod(int(iteration), ITERATIONS_PER_BLOCK)
    offset = SEED_OFFSET if block == 0 else SECOND_BLOCK_OFFSET
    return int(base_seed) + offset + 200 * k + (100 if line_search else 0) + 100000 * int(seed)


def initial_theta(init, keys, feature_set: str) -> np.ndarray:
    """θ (len(keys), n_features(feature_set)) to start from: zeros (the along-cable law), or ``init``'s weights copied
    by feature name (features ``init`` does not have start at 0)."""
    from .common import weights_by_name
    return weights_by_name(None if init is None else init.theta, keys,
                           None if init is None else ars.feature_names(init.feature_set), ars.feature_names(feature_set))


def check_settings(iterations, eps, ridges, replicates, episode_seconds, discard, max_iterations=MAX_ITERATIONS):
    """ValueError naming the field for a search setting out of range (shared by the winch and compensator
    searches)."""
    if not 1 <= int(iterations) <= max_iterations:
        raise ValueError(f"iterations must be in 1..{max_iterations} (got {iterations})")
    if not (math.isfinite(eps) and eps > 0) or not ridges or any(not (math.isfinite(r) and r > 0) for r in ridges):
        raise ValueError(f"eps and every ridge must be positive numbers (got eps={eps}, ridges={list(ridges)})")
    if replicates is not None and not 1 <= int(replicates) <= 10:      # None: the caller checks per sea state
        raise ValueError(f"replicates must be in 1..10 (got {replicates}; 10·replicate stays below the next seed block)")
    if not episode_seconds > discard + 1.0:
        raise ValueError(f"episode_seconds ({episode_seconds}) must exceed discard ({discard}) by more than 1 s")


def replicates_per_sea_state(replicates, keys) -> list[int]:
    """Wave seeds per (sea state, heading) per iteration for every sea state of ``keys`` (sorted, as trained): one
    integer for all, or one per sea state (more episodes where the cost is noisiest, at the same cost per iteration);
    ValueError naming ``replicates`` for another count or a value outside 1..10."""
    reps = [int(r) for r in np.atleast_1d(replicates)]
    if len(reps) == 1:
        reps = reps * len(keys)
    if len(reps) != len(keys):
        raise ValueError(f"replicates: give one count or one per trained sea state ({len(keys)}: {', '.join(keys)}; "
                         f"got {list(np.atleast_1d(replicates))})")
    if any(not 1 <= r <= 10 for r in reps):
        raise ValueError(f"replicates must be in 1..10 (got {reps}; 10·replicate stays below the next seed block)")
    return reps


def first_iteration(init, iterations, max_iterations=MAX_ITERATIONS) -> int:
    """The iteration a search starts at: a Gauss–Newton ``init``'s count continued (its wave seeds stay fresh), else
    0; ValueError if ``iterations`` more would leave the seed blocks."""
    gn_init = init is not None and init.meta.get("method") == "gauss-newton"
    first = int(init.meta.get("iterations", 0) + init.meta.get("first_iteration", 0)) if gn_init else 0
    if first + int(iterations) > max_iterations:
        raise ValueError(f"iterations: the initial policy has {first} iterations; {first} + {iterations} exceeds "
                         f"{max_iterations} (the seed blocks)")
    return first


def training_entries(env_id, table, entries):
    """(evaluation list, indices trained on, sorted sea-state keys of ``table`` they map to); ValueError naming
    ``entries`` for indices outside the list (or none)."""
    import gymnasium as gym
    __import__("towenv")                    # registers the ids
    env = gym.make(env_id)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    idx = list(range(len(ev))) if entries is None else [int(i) for i in entries]
    if not idx or any(not 0 <= i < len(ev) for i in idx):
        raise ValueError(f"entries must be indices in 0..{len(ev) - 1} of the evaluation list (got {entries})")
    return ev, idx, sorted({nearest_key(table, ev[i][0]) for i in idx})


def gauss_newton_steps(terms, code, ok, n_codes: int, ridges) -> np.ndarray:
    """Ridge-regularised Gauss–Newton steps per sea state (module docstring, step 2): for every sea state c,
    Δθ(λ) = −(A + λ·tr(A)/NF·I)⁻¹ b with A = Σ_terms Σ_e w_e J_eᵀJ_e, b = Σ_terms Σ_e w_e J_eᵀ r_e over the episodes e
    of c that are ``ok``. ``terms``: (J (T, NF, n_ep), r (T, n_ep), w (n_ep,)) per residual series; ``code``: the
    sea-state index of every episode. Returns (len(ridges), n_codes, NF) (zero rows for a sea state without
    episodes)."""
    NF = terms[0][0].shape[1]
    steps = np.zeros((len(ridges), n_codes, NF))
    for c in range(n_codes):
        es = np.flatnonzero((code == c) & ok)
        if es.size == 0:
            continue
        A = np.zeros((NF, NF))
        b = np.zeros(NF)
        for e in es:
            for J, r, w in terms:
                A += J[:, :, e].T @ J[:, :, e] * w[e]
                b += J[:, :, e].T @ r[:, e] * w[e]
        d = np.trace(A) / NF
        for j, lam in enumerate(ridges):
            steps[j, c] = -np.linalg.solve(A + lam * d * np.eye(NF), b)
    return steps


def _cost(sh, sp, sh_ref, sp_ref, pitch_weight, fail_penalty=1.0):
    c = np.log(sh / sh_ref) + pitch_weight * np.log(sp / sp_ref)
    return np.where(np.isfinite(c), c, fail_penalty)


def train(seed: int = 0, iterations: int = 10, minutes: float = 55.0, replicates: int = 1, eps: float = 0.005,
          ridges=(0.01, 0.1, 1.0), pitch_weight: float = 0.5, episode_seconds: float = 180.0,
          discard: float = 60.0, feature_set: str = ars.DEFAULT_FEATURE_SET, entries=None, progress: bool = True,
          log=print, init: ars.ARSPolicy | None = None, predictor=None, wave_seed=None,
          parallel: bool = False) -> ars.ARSPolicy:
    """Gauss–Newton search (module docstring) from θ = 0 (the along-cable law), or from the policy ``init`` (an
    :class:`agents.ars.ARSPolicy` of any feature set: its weights are copied by feature name, features it does not
    have start at 0; its along-cable table is kept; the iterations continue its count, so the wave seeds are fresh).
    Stops after ``iterations`` more or when the next iteration would pass ``minutes`` of wall time. ``entries``:
    indices into the evaluation (sea state, heading) list to train on (default all 12). ``replicates``: wave seeds per
    (sea state, heading) per iteration, one count or one per trained sea state (:func:`replicates_per_sea_state`).
    ``predictor``: the causal predictor of a :data:`agents.ars.PREDICTED` feature set (agents/predictor.py; default
    ``init``'s). ``wave_seed``:
    ``f(base seed + 10·replicate, iteration, seed, line_search) -> wave seed`` of every episode (default
    :func:`train_seed`; ``scripts/probe_class_bound.py`` passes the evaluation set's own seeds). ``parallel``: step
    the batches' copies on all numba threads (the vector env's ``parallel=True``; every copy is independent, so the
    result is the serial one bit for bit, in less wall time on several cores)."""
    import towenv  # noqa: F401  (registers the ids)
    from towenv.envs.vector import WinchPayoutVectorEnv
    from .baselines import load_tuned
    check_settings(iterations, eps, ridges, None, episode_seconds, discard)
    check_training_seed(seed)
    # the line search's episodes are fresh (other seeds than the Jacobian's) with the training seeds; a caller's
    # wave_seed (the class-bound probe: the evaluation's own episodes) says nothing of the kind
    episodes_word = "fresh episodes" if wave_seed is None else "line-search episodes"
    wave_seed = train_seed if wave_seed is None else wave_seed
    if feature_set in ars.PREDICTED:
        predictor = predictor if predictor is not None else getattr(init, "predictor", None)
        if predictor is None:
            raise ValueError(f"feature set {feature_set} needs a predictor (--predictor FILE: python -m agents.predictor)")
    else:
        predictor = None
    t_start = time.perf_counter()
    first = first_iteration(init, iterations)
    table = dict(init.base_table) if init is not None else dict(load_tuned().get("along_cable") or {})
    if not table:
        raise RuntimeError("no tuned along_cable table (agents/hyperparams/baselines.yml): run python -m agents.tuning")
    ev, idx, keys = training_entries(ars.ENV_ID, table, entries)
    C, NF = len(keys), ars.n_features(feature_set)
    reps_by_code = replicates_per_sea_state(replicates, keys)
    entry_code = {i: keys.index(nearest_key(table, ev[i][0])) for i in idx}
    # (replicate, entry) pairs of every iteration: replicate-major, so a uniform count keeps the historical order
    pairs = [(r, i) for r in range(max(reps_by_code)) for i in idx if r < reps_by_code[entry_code[i]]]
    ents = [(ev[i][0], ev[i][1]) for _r, i in pairs]          # the same (sea state, heading) list every iteration;
    reps = [r for r, _i in pairs]                             # only the wave seeds change with the iteration
    code = np.array([entry_code[i] for _r, i in pairs])
    seas = [sea for sea, _s in ents]
    ridges = [float(r) for r in ridges]
    n_ep = len(pairs)
    n_jac, n_ls = n_ep * (NF + 1), n_ep * (len(ridges) + 2)
    kw = dict(autoreset_mode="NextStep", batch_infos=True, episode_seconds=float(episode_seconds),
              parallel=bool(parallel))
    venv_j = WinchPayoutVectorEnv(num_envs=n_jac, **kw)
    venv_l = WinchPayoutVectorEnv(num_envs=n_ls, **kw)
    scales = dict(ars.FEATURE_SCALES)
    batch_j = ars._Batch(venv_j, table, scales, feature_set, predictor)
    batch_l = ars._Batch(venv_l, table, scales, feature_set, predictor)
    theta = initial_theta(init, keys, feature_set)
    curve = []
    log(f"[gn] seed {seed}: {C} sea states, {NF} features each; per iteration {n_ep} episodes x ({NF} + 1) for the "
        f"Jacobian and {n_ep} x ({len(ridges)} ridges + current + along_cable) for the line search, "
        f"{episode_seconds:g} s each; eps={eps} ridges={ridges} pitch_weight={pitch_weight}")
    it, last = first, 0.0
    while it < first + iterations:
        if time.perf_counter() - t_start + last > 60.0 * minutes:
            break
        t0 = time.perf_counter()
        # 1. Jacobian: copy block 0 runs θ, block i + 1 runs θ + ε e_i
        seeds = [wave_seed(s + 10 * r, it, seed) for (_sea, s), r in zip(ents, reps)]
        th = np.repeat(theta[code][None], NF + 1, axis=0)
        for i in range(NF):
            th[i + 1, :, i] += eps
        H, P, t, ended = ars.rollout_series(venv_j, batch_j, seas * (NF + 1), seeds * (NF + 1), th.reshape(-1, NF))
        w = t >= discard
        Y = H[w].reshape(-1, NF + 1, n_ep)
        Q = P[w].reshape(-1, NF + 1, n_ep)
        Y = Y - Y.mean(axis=0)
        Q = Q - Q.mean(axis=0)
        y0, q0 = Y[:, 0], Q[:, 0]
        Jy = (Y[:, 1:] - y0[:, None]) / eps
        Jq = (Q[:, 1:] - q0[:, None]) / eps
        sy, sq = y0.std(axis=0), q0.std(axis=0)
        ok = ~ended.reshape(NF + 1, n_ep).any(axis=0) & (sy > 0) & (sq > 0)
        # 2. Gauss–Newton steps per sea state and ridge
        steps = gauss_newton_steps([(Jy, y0, 1.0 / sy ** 2), (Jq, q0, pitch_weight / sq ** 2)], code, ok, C,
                                   ridges)
        # 3. line search on fresh episodes: along_cable, θ, θ + Δθ(λ) for every λ, on the same waves
        seeds_l = [wave_seed(s + 10 * r, it, seed, line_search=True) for (_sea, s), r in zip(ents, reps)]
        cand = np.concatenate([np.zeros((1, n_ep, NF)), theta[code][None], theta[code][None] + steps[:, code]])
        H, P, t, ended = ars.rollout_series(venv_l, batch_l, seas * len(cand), seeds_l * len(cand),
                                            cand.reshape(-1, NF))
        w = t >= discard
        sh = H[w].std(axis=0).reshape(len(cand), n_ep)
        sp = P[w].std(axis=0).reshape(len(cand), n_ep)
        bad = ended.reshape(len(cand), n_ep)
        sh[bad] = np.nan
        sp[bad] = np.nan
        cost = _cost(sh[1:], sp[1:], sh[0], sp[0], pitch_weight)
        picks = []
        for c in range(C):
            m = code == c
            cc = cost[:, m].mean(axis=1)           # current θ, then one per ridge
            j = int(np.argmin(cc))
            if j > 0:
                theta[c] += steps[j - 1, c]
            picks.append({"sea_state": keys[c], "cost_current": float(cc[0]), "cost_after": float(cc[j]),
                          "ridge": ridges[j - 1] if j else None, "step_norm": float(np.linalg.norm(steps[j - 1, c])) if j else 0.0})
        ratio_h = float(np.nanmean(sh[1]) / np.nanmean(sh[0]))
        ratio_p = float(np.nanmean(sp[1]) / np.nanmean(sp[0]))
        last = time.perf_counter() - t0
        curve.append({"iteration": it, "heave_ratio": ratio_h, "pitch_ratio": ratio_p, "seconds": last,
                      "picks": picks, "failures": int(bad.sum())})
        if progress:
            log(f"[gn] it {it:2d} ({last:4.0f} s, {(time.perf_counter() - t_start) / 60:5.1f} min): θ before this "
                f"step vs along_cable on {n_ep} {episodes_word}: heave {100 * (ratio_h - 1):+6.2f} %, pitch "
                f"{100 * (ratio_p - 1):+5.1f} %; cost per sea state " + ", ".join(
                    f"{p['cost_current']:+.3f} -> {p['cost_after']:+.3f}"
                    + (f" (ridge {p['ridge']:g})" if p["ridge"] is not None else " (no step)") for p in picks))
        it += 1
    steps_per_episode = int(venv_j.envs[0].max_steps)
    venv_j.close()
    venv_l.close()
    wall = time.perf_counter() - t_start
    meta = {"algo": "ars", "method": "gauss-newton", "env_id": ars.ENV_ID, "env_kwargs": {},
            "feature_set": feature_set, "seed": int(seed), "iterations": it - first, "first_iteration": first,
            "num_timesteps": (it - first) * (n_jac + n_ls) * steps_per_episode, "wall_seconds": wall,
            "parallel": bool(parallel),
            "hyperparameters": {"iterations": iterations, "minutes": minutes,
                                "replicates": reps_by_code[0] if len(set(reps_by_code)) == 1 else reps_by_code,
                                "eps": eps,
                                "ridges": ridges, "pitch_weight": pitch_weight, "episode_seconds": episode_seconds,
                                "discard": discard, "entries": idx,
                                "init": init.name if init is not None else None},
            "blas_env": {v: os.environ.get(v) for v in ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS")},
            "init_num_timesteps": int(init.meta.get("num_timesteps", 0)) if init is not None else 0,
            "train_seeds": f"1000*code + j + 10*replicate + {SEED_OFFSET} + 200*iteration (+100 line search) "
                           f"+ 100000*{int(seed)} for iterations < {ITERATIONS_PER_BLOCK}, then "
                           f"{SECOND_BLOCK_OFFSET} + 200*(iteration - {ITERATIONS_PER_BLOCK}) in place of "
                           f"{SEED_OFFSET} + 200*iteration",
            "curve": curve}
    out = {k: theta[c] for c, k in enumerate(keys)}
    if init is not None:                        # sea states not trained on (``entries``) keep the initial weights
        rest = sorted(set(init.theta) - set(keys))
        out |= {k: row for k, row in zip(rest, initial_theta(init, rest, feature_set))}
    return ars.ARSPolicy(out, table, ars.FEATURE_SCALES, meta,
                         name=f"gn_s{seed}", feature_set=feature_set, predictor=predictor)


def default_export(seed: int, feature_set: str = "v2") -> Path:
    # feature set v3 as "gn_v3": "gn2" … "gn5" name the committed continuations of the v2 search (docs/agents.md)
    prefix = "gn" if feature_set in ("v1", "v2") else f"gn_{feature_set}"
    return Path("runs") / f"{prefix}_WinchPayout-v0_s{int(seed)}.npz"


def main(argv=None) -> int:
    """``python scripts/train_gn.py --seed 0`` (writes :func:`default_export`)."""
    import argparse
    ap = argparse.ArgumentParser(description="Gauss-Newton policy search for the linear residual over the along-cable "
                                             "winch law (towenv/WinchPayout-v0); agents/gn.py explains the method.")
    ap.add_argument("--seed", type=int, default=0, help="training seed (the training wave seeds)")
    ap.add_argument("--iterations", type=int, default=10, help=f"1..{MAX_ITERATIONS} (default 10)")
    ap.add_argument("--minutes", type=float, default=55.0, help="wall-clock budget (default 55)")
    ap.add_argument("--replicates", type=int, nargs="+", default=[1],
                    help="wave seeds per (sea state, heading) per iteration: one count, or one per trained sea state "
                         "(in the order of the sea-state keys, increasing Hs for the evaluation list)")
    ap.add_argument("--eps", type=float, default=0.005, help="finite-difference step of a weight")
    ap.add_argument("--ridges", type=float, nargs="+", default=[0.01, 0.1, 1.0],
                    help="ridge weights tried by the line search (relative to the normal matrix's mean diagonal)")
    ap.add_argument("--pitch-weight", type=float, default=0.5, help="weight of ln(σ_pitch ratio) in the cost")
    ap.add_argument("--features", choices=sorted(ars.FEATURE_SETS), default=ars.DEFAULT_FEATURE_SET,
                    help=f"feature set (agents/ars.py; default {ars.DEFAULT_FEATURE_SET})")
    ap.add_argument("--init", default=None, help="start from this ARS/GN policy file (weights copied by feature "
                                                 "name, new features at 0; a GN file's iteration count continues)")
    ap.add_argument("--entries", type=int, nargs="+", default=None,
                    help="indices of the evaluation (sea state, heading) list to train on (default all 12; the other "
                         "sea states keep the --init policy's weights)")
    ap.add_argument("--predictor", default=None, help="predictor file of feature set v2q (python -m agents.predictor; "
                                                     "default: the --init policy's)")
    ap.add_argument("--export", default=None, help="policy file (default runs/gn_WinchPayout-v0_s<seed>.npz, "
                                                  "gn_v3_... for feature set v3)")
    add_parallel_flag(ap)
    a = ap.parse_args(argv)
    if not 1 <= a.iterations <= MAX_ITERATIONS:
        ap.error(f"--iterations must be in 1..{MAX_ITERATIONS} (got {a.iterations})")
    if any(not 1 <= r <= 10 for r in a.replicates) or a.pitch_weight < 0:
        ap.error("need 1 <= --replicates <= 10 and --pitch-weight >= 0")
    try:
        check_training_seed(a.seed)
    except ValueError as e:
        ap.error(f"--{e}")
    for name in ("minutes", "eps"):
        v = getattr(a, name)
        if not (math.isfinite(v) and v > 0):
            ap.error(f"--{name} must be a positive number (got {v})")
    if any(not (math.isfinite(r) and r > 0) for r in a.ridges):
        ap.error(f"--ridges must be positive numbers (got {a.ridges})")
    init = None
    if a.init:
        try:
            init = ars.load_ars_policy(a.init)
        except (OSError, ValueError, KeyError) as e:
            ap.error(f"--init: {e}")
    from .predictor import load_option
    predictor = load_option(ap, a.predictor)
    out = Path(a.export or default_export(a.seed, a.features))
    try:
        reps = a.replicates[0] if len(a.replicates) == 1 else a.replicates
        pol = train(a.seed, a.iterations, a.minutes, reps, a.eps, a.ridges, a.pitch_weight,
                    feature_set=a.features, entries=a.entries, init=init, predictor=predictor,
                    parallel=a.parallel)
    except ValueError as e:
        ap.error(str(e))
    ars.save_policy(pol, out)
    print(f"[gn] wrote {out} ({pol.meta['iterations']} iterations, {pol.meta['wall_seconds'] / 60:.1f} min)")
    return 0
