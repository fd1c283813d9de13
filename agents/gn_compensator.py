"""Gauss–Newton policy search for the CompensatorGains linear residual over skyhook (the policy class of
``agents/ars_compensator.py``), the method of :mod:`agents.gn` applied to the semi-active compensator.

Per iteration:

1. **Jacobian by finite differences on the simulator.** The batch of training episodes (one per (sea state,
   heading) and replicate; fresh wave seeds every iteration) runs once with Θ and once per weight with that weight
   + ε (all 2 × n_features weights of Θ, the stiffness and the damping rows; every sea state's Θ perturbed in the
   same copy). J = (y(Θ + ε e_i) − y(Θ))/ε for three series over the scored window: fish heave and pitch (window
   mean removed) and the stroke margin m_t = max(|s_t| − m0, 0) (s = stroke / half stroke). The closed loop —
   skyhook switching, the stop guard, end-stop impacts — is inside J (the secant of the deterministic simulator).
2. **Gauss–Newton step per sea state** (:func:`agents.gn.gauss_newton_steps`): the linearisation of the ARS
   compensator cost ln σ_h + w_p ln σ_θ + w_margin · mean_t m_t², i.e. Σ_e ‖y_e + J Δ‖²/σ_h,e² +
   w_p ‖q_e + J^q Δ‖²/σ_θ,e² + 2 w_margin ‖m_e + J^m Δ‖², for each ridge λ in ``ridges``. The end-stop hit count
   is not differentiable: it enters through the margin series here and through step 3.
3. **Line search on fresh episodes**: skyhook, Θ and Θ + Δ(λ) for every λ on the same waves; per sea state keep the
   candidate with the lowest mean ARS compensator cost (:mod:`agents.ars_compensator`: log σ ratios to skyhook,
   w_hit · hits, w_margin · margin) — no step if none beats the current Θ.

Cheaper iterations: ``columns=K`` perturbs, each iteration, only K of the moved weights, drawn at random without
replacement (:func:`column_subset`: a generator seeded by (training seed, iteration), so a run is reproducible) — a
Gauss–Newton step in a random coordinate subspace (block-coordinate Gauss–Newton), K + 1 Jacobian copies instead of
all moved weights + 1; the line search is unchanged. ``columns`` equal to the number of moved weights (or None) is
the full step.

Shared warm-up (``shared_warmup=True``, ``--shared-warmup``): the Jacobian episodes' first ``discard`` seconds are not
scored, yet each of the K + 1 copies of an episode ran them. With the shared warm-up they run once per episode under
Θ (:func:`warmup_steps` control steps: every row before the scored window) and the state is branched into the
episode's copies (``TowVectorEnv.load_copies``, bit for bit the continuation: tested), which then run the scored
window with their own weights — about a third less Jacobian work at 180 s episodes scored after 60 s. The Jacobian
is then the scored window's sensitivity to the weights *from the state Θ reached at the window's start*: the effect
of a perturbed warm-up on that state (decaying over the system's memory, seconds) is left out
(``scripts/bench_shared_warmup.py`` measures both). The line search is unchanged.

Options: ``feature_set="hq"`` with a ``predictor`` (the init's weights copied by feature name, the predicted ones
starting at 0), and ``free="predicted"`` to move only the predicted features' weights (the Jacobian then has one column
per moved weight); ``feature_set="hs"`` (the skyhook-gated copy of the features, starting at 0) with ``free="gated"``
moves only the gated copy's weights.

The result is an :class:`agents.ars_compensator.ARSCompensatorPolicy` (same features, stop guard and file format,
``meta["method"] = "gauss-newton"``), so ``scripts/evaluate.py`` loads it unchanged. It starts from Θ = 0 (skyhook)
or from a policy file (``init``: its Θ, base table and stop guard are kept).

Wave seeds: Jacobian episodes ``1000·code + j + 10·replicate + 62000 + 200·iteration + 100000·seed``, line-search
episodes the same + 100; iteration < :data:`MAX_ITERATIONS`, replicate < 10 — never an evaluation (+0…400), tuning
(+500), validation (+700), Hover design (+900), final (+20000…), clairvoyant-teacher (+30000), ARS-training
(+40000…, +50000…), probe (+75000, +76000), WinchPayout Gauss–Newton (+80000…) or semi-active teacher-plan (+92000…) seed.
"""
from __future__ import annotations

import math
import time
from pathlib import Path

import numpy as np

from . import ars_compensator as arc
from .common import add_parallel_flag, nearest_key
from .gn import check_settings, first_iteration, gauss_newton_steps, training_entries

__all__ = ["train", "train_seed", "MAX_ITERATIONS", "SEED_OFFSET", "main"]

#: wave seeds of the search: base seed (1000·code + j) + SEED_OFFSET + 200·iteration (+ 100 for the line search)
#: + 10·replicate + 100000·training seed
SEED_OFFSET = 62000
#: 200·iteration + 100 + 10·replicate stays below 10000: a run's seeds stay inside its own block
MAX_ITERATIONS = 49


def train_seed(base_seed: int, iteration: int, seed: int, line_search: bool = False) -> int:
    if not 0 <= int(iteration) < MAX_ITERATIONS:
        raise ValueError(f"iteration must be in 0..{MAX_ITERATIONS - 1} (got {iteration})")
    return int(base_seed) + SEED_OFFSET + 200 * int(iteration) + (100 if line_search else 0) + 100000 * int(seed)


def initial_theta(init, keys, feature_set: str) -> np.ndarray:
    """Θ (len(keys), 2, n_features(feature_set)) to start from: zeros (skyhook), or ``init``'s weights copied by
    feature name (features ``init`` does not have start at 0)."""
    from .common import weights_by_name
    return weights_by_name(None if init is None else init.theta, keys,
                           None if init is None else arc.feature_names(init.feature_set),
                           arc.feature_names(feature_set), (arc.N_ACT,))


def free_mask(feature_set: str, free: str) -> np.ndarray:
    """Which of the (2, n_features) weights the search moves: ``"all"``, or only the features a feature set adds to
    "h" (:func:`agents.ars_compensator.added_features`): ``"predicted"`` (hq), ``"gated"`` (hs, hst, hsf), ``"cable"`` (hst:
    the top-tension and along-cable velocity histories), ``"fish"`` (hsf, hsfo: the fish-gated copy) or ``"outward"``
    (hsfo: the outward-gated copy); the rest stay as they start. A flat boolean mask over the 2 × n_features weights (row-major, as Θ.reshape(-1))."""
    if free == "all":
        cols = np.ones(arc.n_features(feature_set), bool)
    elif free in arc.ADDED_KINDS:
        kind, added = arc.added_features(feature_set, free)
        if kind != free:
            raise ValueError(f"free={free!r} needs a feature set with {free} features "
                             f"({', '.join(sorted(arc.ADDED_KINDS[free]))}; got {feature_set!r})")
        cols = added
    else:
        raise ValueError(f"free must be 'all', {', '.join(repr(k) for k in arc.ADDED_KINDS)} (got {free!r})")
    return np.tile(cols, arc.N_ACT)


def column_subset(n_free: int, columns: int | None, seed: int, iteration: int) -> np.ndarray:
    """Positions (sorted, into the moved weights) of the Jacobian columns of one iteration: all ``n_free`` when
    ``columns`` is None or ≥ ``n_free``, else ``columns`` of them drawn without replacement by a generator seeded by
    (training seed, iteration, 62) — the same draw on every run of that seed and iteration."""
    if columns is None or int(columns) >= n_free:
        return np.arange(n_free)
    rng = np.random.default_rng([int(seed), int(iteration), 62])
    return np.sort(rng.choice(n_free, size=int(columns), replace=False))


def _costs(sh, sp, hits, mg, pitch_weight, hit_weight, margin_weight, fail_penalty=1.0):
    """ARS compensator cost (:mod:`agents.ars_compensator`) of candidate rows 1… of (candidates, episodes) arrays
    against row 0 (skyhook) on the same waves: ln σ_h ratio + w_p ln σ_θ ratio + w_hit · hits + w_margin · margin;
    ``fail_penalty`` for an episode that ended early."""
    with np.errstate(invalid="ignore", divide="ignore"):
        c = (np.log(sh[1:] / sh[0]) + pitch_weight * np.log(sp[1:] / sp[0]) + hit_weight * hits[1:]
             + margin_weight * mg[1:])
    return np.where(np.isfinite(c), c, fail_penalty)


def train(seed: int = 0, iterations: int = 5, minutes: float = 55.0, replicates: int = 1, eps: float = 0.01,
          ridges=(0.01, 0.1, 1.0), pitch_weight: float = 0.5, hit_weight: float = arc.DEFAULT_HIT_WEIGHT,
          margin_weight: float = arc.DEFAULT_MARGIN_WEIGHT, margin_start: float = arc.DEFAULT_MARGIN_START,
          stop_guard: float | None = None, episode_seconds: float = 180.0, discard: float = 60.0, entries=None,
          init: arc.ARSCompensatorPolicy | None = None, progress: bool = True, feature_set: str | None = None,
          predictor=None, free: str = "all", parallel: bool = False, columns: int | None = None,
          shared_warmup: bool = False, log=print) -> arc.ARSCompensatorPolicy:
    """Gauss–Newton search (module docstring) from Θ = 0 (skyhook) or from ``init`` (its weights copied by feature
    name; features it does not have start at 0). Stops after ``iterations`` (continuing a Gauss–Newton ``init``'s
    count, so its wave seeds stay fresh) or when the next iteration would pass ``minutes`` of wall time.
    ``stop_guard``: None = the init's (0 without init). ``entries``: indices into the evaluation (sea state,
    heading) list to train on (default all 12; the other sea states keep ``init``'s weights). ``feature_set``:
    None = the init's ("h" without init); ``predictor``: the causal predictor of a predicted feature set ("hq",
    agents/predictor.py; default ``init``'s). ``free``: "all" weights move, or only the "predicted" (hq) or "gated"
    (hs) features' (:func:`free_mask`; the Jacobian then perturbs only those, which makes an iteration cheaper).
    ``parallel``: step the batches on all numba threads (the same result bit for bit, less wall time). ``columns``:
    None = a Jacobian column per moved weight; K = K of them per iteration, drawn at random (:func:`column_subset`,
    the step moves only those). ``shared_warmup``: the Jacobian episodes' unscored first ``discard`` seconds run once
    per episode under Θ and are branched into the perturbed copies (:func:`warmup_steps`,
    ``arc.rollout_series_shared``; the module docstring)."""
    __import__("towenv")
    from towenv.envs.vector import CompensatorGainsVectorEnv
    from .baselines import load_tuned
    check_settings(iterations, eps, ridges, replicates, episode_seconds, discard, MAX_ITERATIONS)
    for name, v in (("pitch_weight", pitch_weight), ("hit_weight", hit_weight), ("margin_weight", margin_weight)):
        if not (math.isfinite(v) and v >= 0):
            raise ValueError(f"{name} must be a finite number >= 0 (got {v})")
    guard = float(init.stop_guard if init is not None else 0.0) if stop_guard is None else float(stop_guard)
    if not 0.0 <= guard <= 1.0:
        raise ValueError(f"stop_guard must be 0 (off) or in (0, 1] (got {guard})")
    fs = (init.feature_set if init is not None else "h") if feature_set is None else str(feature_set)
    if predictor is None and init is not None and fs in arc.PREDICTED:
        predictor = init.predictor
    arc._check_predictor(fs, predictor, "gn_compensator.train")
    mask = free_mask(fs, free)
    t_start = time.perf_counter()
    first = first_iteration(init, iterations, MAX_ITERATIONS)
    table = dict(init.base_table) if init is not None else dict(load_tuned().get("skyhook") or {})
    if not table:
        raise RuntimeError("no tuned skyhook table (agents/hyperparams/baselines.yml): run python -m agents.tuning")
    ev, idx, keys = training_entries(arc.ENV_ID, table, entries)
    C, NA, NF, R = len(keys), arc.N_ACT, arc.n_features(fs), int(replicates)
    moved_idx = np.flatnonzero(mask)                # the moved weights, as flat indices into Θ.reshape(-1)
    if columns is not None and (isinstance(columns, bool) or not isinstance(columns, (int, np.integer))
                                or not 1 <= columns <= len(moved_idx)):
        raise ValueError(f"columns must be None or an integer in 1..{len(moved_idx)} (the moved weights of "
                         f"free={free!r}; got {columns!r})")
    NW = len(moved_idx) if columns is None else int(columns)      # Jacobian columns per iteration
    theta = initial_theta(init, keys, fs)
    ridges = [float(r) for r in ridges]
    n_ep = len(idx) * R
    n_jac, n_ls = n_ep * (NW + 1), n_ep * (len(ridges) + 2)
    kw = dict(autoreset_mode="NextStep", batch_infos=True, episode_seconds=float(episode_seconds),
              parallel=bool(parallel))
    venv_j = CompensatorGainsVectorEnv(num_envs=n_jac, **kw)
    warm = warmup_steps(venv_j.envs[0].max_steps, venv_j.envs[0].dt, discard) if shared_warmup else 0
    venv_w = CompensatorGainsVectorEnv(num_envs=n_ep, **kw) if warm else None
    venv_l = CompensatorGainsVectorEnv(num_envs=n_ls, **kw)
    scales = dict(init.scales) if init is not None else dict(arc.FEATURE_SCALES)
    batch_j = arc._Batch(venv_j, table, scales, fs, predictor)
    batch_l = arc._Batch(venv_l, table, scales, fs, predictor)
    batch_w = arc._Batch(venv_w, table, scales, fs, predictor) if warm else None
    curve, iterates = [], []
    log(f"[gn_comp] seed {seed}: feature set {fs}, {C} sea states, {NA} x {NF} weights each ({len(moved_idx)} moved: {free})"
        + (f"; {NW} random Jacobian columns of them per iteration" if NW < len(moved_idx) else "")
        + f"; per iteration {n_ep} episodes x ({NW} + 1) "
        + (f"(their first {warm} control steps shared: run once per episode under Θ) " if warm else "")
        + 
        f"for the Jacobian and {n_ep} x ({len(ridges)} ridges + current + skyhook) for the line search, "
        f"{episode_seconds:g} s each; eps={eps} ridges={ridges} pitch_weight={pitch_weight} hit_weight={hit_weight} "
        f"margin_weight={margin_weight} margin_start={margin_start} stop_guard={guard}"
        + (f"; from {init.name} (iteration {first})" if init is not None else ""))
    it, last = first, 0.0
    while it < first + iterations:
        if time.perf_counter() - t_start + last > 60.0 * minutes:
            break
        t0 = time.perf_counter()
        free_idx = moved_idx[column_subset(len(moved_idx), columns, seed, it)]     # this iteration's columns
        ents = [(ev[i][0], ev[i][1]) for _r in range(R) for i in idx]
        reps = [r for r in range(R) for _i in idx]
        code = np.array([keys.index(nearest_key(table, sea)) for sea, _s in ents])
        seas = [sea for sea, _s in ents]
        # 1. Jacobian: copy block 0 runs Θ, block i + 1 runs Θ + ε e_{free_idx[i]} (flat index over the 2 x NF
        #    weights; every weight with free = "all")
        seeds = [train_seed(s + 10 * r, it, seed) for (_sea, s), r in zip(ents, reps)]
        th = np.repeat(theta[code].reshape(n_ep, NA * NF)[None], NW + 1, axis=0)
        for i, f in enumerate(free_idx):
            th[i + 1, :, f] += eps
        if warm:
            H, P, S, t, _hits, ended, _a = arc.rollout_series_shared(venv_w, batch_w, venv_j, batch_j, seas, seeds,
                                                                     th[0].reshape(-1, NA, NF),
                                                                     th.reshape(-1, NA, NF), warm, stop_guard=guard)
        else:
            H, P, S, t, _hits, ended, _a = arc.rollout_series(venv_j, batch_j, seas * (NW + 1), seeds * (NW + 1),
                                                              th.reshape(-1, NA, NF), stop_guard=guard)
        if warm and (t[:warm] >= discard).any():  # cannot happen (warmup_steps): the shared rows must be unscored
            raise RuntimeError(f"shared warm-up: row {int(np.argmax(t >= discard))} is scored but was shared")
        # 2. Gauss–Newton steps per sea state and ridge
        steps, _J = jacobian_steps((H, P, S, t, ended), NW, discard, eps, margin_start, pitch_weight, margin_weight,
                                   code, C, ridges)
        # 3. line search on fresh episodes: skyhook, Θ, Θ + Δ(λ) for every λ, on the same waves
        seeds_l = [train_seed(s + 10 * r, it, seed, line_search=True) for (_sea, s), r in zip(ents, reps)]
        full = np.zeros((len(ridges), C, NA * NF))      # the steps of the moved weights, as full Θ steps
        full[:, :, free_idx] = steps
        steps = full
        flat = theta[code].reshape(n_ep, NA * NF)
        cand = np.concatenate([np.zeros((1, n_ep, NA * NF)), flat[None], flat[None] + steps[:, code]])
        sh, sp, hits, mg = arc.rollout_batch(venv_l, batch_l, seas * len(cand), seeds_l * len(cand),
                                             cand.reshape(-1, NA, NF), discard=discard, margin_start=margin_start,
                                             stop_guard=guard)
        shape = (len(cand), n_ep)
        sh, sp, hits, mg = sh.reshape(shape), sp.reshape(shape), hits.reshape(shape), mg.reshape(shape)
        cost = _costs(sh, sp, hits, mg, pitch_weight, hit_weight, margin_weight)
        picks = []
        for c in range(C):
            m = code == c
            cc = cost[:, m].mean(axis=1)           # current Θ, then one per ridge
            j = int(np.argmin(cc))
            if j > 0:
                theta[c] += steps[j - 1, c].reshape(NA, NF)
            picks.append({"sea_state": keys[c], "cost_current": float(cc[0]), "cost_after": float(cc[j]),
                          "ridge": ridges[j - 1] if j else None,
                          "step_norm": float(np.linalg.norm(steps[j - 1, c])) if j else 0.0})
        iterates.append(theta.copy())           # Θ after this iteration's step (:func:`iterate_policies`)
        ratio_h = float(np.nanmean(sh[1]) / np.nanmean(sh[0]))
        ratio_p = float(np.nanmean(sp[1]) / np.nanmean(sp[0]))
        last = time.perf_counter() - t0
        curve.append({"iteration": it, "heave_ratio": ratio_h, "pitch_ratio": ratio_p, "hits": float(hits[1].sum()),
                      "hits_skyhook": float(hits[0].sum()), "seconds": last, "picks": picks,
                      "failures": int((~np.isfinite(sh)).sum())})
        if progress:
            log(f"[gn_comp] it {it:2d} ({last:4.0f} s, {(time.perf_counter() - t_start) / 60:5.1f} min): Θ before this "
                f"step vs skyhook on {n_ep} fresh episodes: heave {100 * (ratio_h - 1):+6.2f} %, pitch "
                f"{100 * (ratio_p - 1):+5.1f} %, hits {hits[1].sum():g} (skyhook {hits[0].sum():g}); cost per sea "
                "state " + ", ".join(f"{p['cost_current']:+.3f} -> {p['cost_after']:+.3f}"
                                     + (f" (ridge {p['ridge']:g})" if p["ridge"] is not None else " (no step)")
                                     for p in picks))
        it += 1
    steps_per_episode = int(venv_j.envs[0].max_steps)
    venv_j.close()
    venv_l.close()
    if venv_w is not None:
        venv_w.close()
    jac_steps = n_jac * steps_per_episode - (n_jac - n_ep) * warm      # the shared rows run once per episode
    wall = time.perf_counter() - t_start
    meta = {"algo": arc.ALGO, "method": "gauss-newton", "env_id": arc.ENV_ID, "env_kwargs": {},
            "seed": int(seed), "iterations": it - first, "first_iteration": first, "stop_guard": guard,
            "num_timesteps": (it - first) * (jac_steps + n_ls * steps_per_episode), "wall_seconds": wall,
            "parallel": bool(parallel),
            "init_num_timesteps": int(init.meta.get("num_timesteps", 0)) if init is not None else 0,
            "hyperparameters": {"iterations": iterations, "minutes": minutes, "replicates": R, "eps": eps,
                                "ridges": ridges, "pitch_weight": pitch_weight, "hit_weight": hit_weight,
                                "margin_weight": margin_weight, "margin_start": margin_start,
                                "episode_seconds": episode_seconds, "discard": discard, "entries": idx,
                                "init": init.name if init is not None else None, "free": free,
                                "columns": None if columns is None else int(columns),
                                "shared_warmup": bool(shared_warmup), "warmup_steps": int(warm)},
            "feature_set": fs,
            "train_seeds": f"1000*code + j + 10*replicate + {SEED_OFFSET} + 200*iteration (+100 line search) "
                           f"+ 100000*{int(seed)}",
            "curve": curve}
    rest = sorted(set(init.theta) - set(keys)) if init is not None else []
    kept = dict(zip(rest, initial_theta(init, rest, fs))) if rest else {}    # sea states not trained on (``entries``)

    def weights(th):
        return {k: th[c] for c, k in enumerate(keys)} | kept

    pol = arc.ARSCompensatorPolicy(weights(theta), table, scales, meta, name=f"gn_comp_s{seed}", predictor=predictor)
    pol.iterates = [weights(th) for th in iterates]     # Θ after each iteration, for :func:`iterate_policies`
    return pol


def iterate_stem(stem: str, iteration: int) -> str:
    """The name of a run's policy after Gauss–Newton iteration ``iteration``: ``<stem>_it<NN>``."""
    return f"{stem}_it{int(iteration):02d}"


def iterate_policies(policy: arc.ARSCompensatorPolicy, stem: str) -> list:
    """The policies of each iteration of a :func:`train` run: Θ after its k-th step (k = 1 … iterations), named
    ``<stem>_it<NN>`` by its Gauss–Newton iteration number, with the run's metadata cut to those k iterations
    (``iterations``, ``curve``; ``iterate_of`` names the run). The last one's weights equal ``policy``'s."""
    its = getattr(policy, "iterates", None)
    if its is None:
        raise ValueError(f"{policy.name}: no iterates (a policy returned by gn_compensator.train has them)")
    first = int(policy.meta["first_iteration"])
    out = []
    for k, th in enumerate(its, start=1):
        meta = dict(policy.meta) | {"iterations": k, "curve": policy.meta["curve"][:k], "iterate_of": stem}
        meta["num_timesteps"] = policy.meta["num_timesteps"] // len(its) * k
        meta["wall_seconds"] = float(sum(c["seconds"] for c in meta["curve"]))
        out.append(arc.ARSCompensatorPolicy(th, policy.base_table, policy.scales, meta,
                                            name=iterate_stem(stem, first + k - 1), predictor=policy.predictor))
    return out


def jacobian_steps(series, NW: int, discard: float, eps: float, margin_start: float, pitch_weight: float,
                   margin_weight: float, code, n_codes: int, ridges):
    """Steps 1–2 of an iteration from the Jacobian rollout ``series`` = (H, P, S, t, ended) of ``rollout_series``
    (copy block 0 under Θ, block i + 1 with column i perturbed by ``eps``; each block the ``n_ep`` episodes):
    the Gauss–Newton steps (len(ridges), n_codes, NW) and the heave Jacobian J_y (rows t ≥ discard, NW, n_ep)."""
    H, P, S, t, ended = series
    n_ep = H.shape[1] // (NW + 1)
    w = t >= discard
    Y = H[w].reshape(-1, NW + 1, n_ep)
    Q = P[w].reshape(-1, NW + 1, n_ep)
    M = arc.margin_penalty(S[w], margin_start).reshape(-1, NW + 1, n_ep) ** 0.5      # m_t = max(|s| − m0, 0)
    Y = Y - Y.mean(axis=0)
    Q = Q - Q.mean(axis=0)
    y0, q0, m0 = Y[:, 0], Q[:, 0], M[:, 0]
    Jy = (Y[:, 1:] - y0[:, None]) / eps
    Jq = (Q[:, 1:] - q0[:, None]) / eps
    Jm = (M[:, 1:] - m0[:, None]) / eps
    sy, sq = y0.std(axis=0), q0.std(axis=0)
    ok = ~ended.reshape(NW + 1, n_ep).any(axis=0) & (sy > 0) & (sq > 0)
    steps = gauss_newton_steps([(Jy, y0, 1.0 / sy ** 2), (Jq, q0, pitch_weight / sq ** 2),
                                (Jm, m0, np.full(n_ep, 2.0 * margin_weight))], code, ok, n_codes, ridges)
    return steps, Jy


def warmup_steps(max_steps: int, dt: float, discard: float) -> int:
    """Control steps of an episode's shared warm-up: the leading steps whose row (the state after step k, at
    t = (k + 1)·dt) lies before ``discard`` with a margin of 1e-6 s, so that no scored row is shared (the trainer
    checks the rows' recorded times too). ``max_steps`` − 1 at most."""
    k = int(np.sum(np.arange(1, int(max_steps) + 1) * float(dt) < float(discard) - 1e-6))
    return max(0, min(k, int(max_steps) - 1))


def default_export(seed: int) -> Path:
    return Path("runs") / f"gn_CompensatorGains-v0_s{int(seed)}.npz"


def main(argv=None) -> int:
    """``python scripts/train_gn_compensator.py --seed 0 --init agents/trained/ars_CompensatorGains-v0_s0.npz``"""
    import argparse
    ap = argparse.ArgumentParser(description="Gauss-Newton policy search for the linear residual over the skyhook "
                                             "compensator law (towenv/CompensatorGains-v0); agents/gn_compensator.py "
                                             "explains the method.")
    ap.add_argument("--seed", type=int, default=0, help="training seed (the training wave seeds)")
    ap.add_argument("--iterations", type=int, default=5, help=f"1..{MAX_ITERATIONS} (default 5)")
    ap.add_argument("--minutes", type=float, default=55.0, help="wall-clock budget (default 55)")
    ap.add_argument("--replicates", type=int, default=1, help="wave seeds per (sea state, heading) per iteration")
    ap.add_argument("--eps", type=float, default=0.01, help="finite-difference step of a weight")
    ap.add_argument("--ridges", type=float, nargs="+", default=[0.01, 0.1, 1.0],
                    help="ridge weights tried by the line search (relative to the normal matrix's mean diagonal)")
    ap.add_argument("--pitch-weight", type=float, default=0.5, help="weight of ln(σ_pitch ratio) in the cost")
    ap.add_argument("--hit-weight", type=float, default=arc.DEFAULT_HIT_WEIGHT, help="cost per end-stop hit")
    ap.add_argument("--margin-weight", type=float, default=arc.DEFAULT_MARGIN_WEIGHT,
                    help="weight of the stroke-margin term")
    ap.add_argument("--stop-guard", type=float, default=None, help="stop guard (default: the init policy's, else 0)")
    ap.add_argument("--init", default=None, help="start from this ARS/GN compensator policy file")
    ap.add_argument("--features", default=None, choices=arc.FEATURE_SETS,
                    help="feature set (default: the init policy's, else h); hq adds the predicted tow-point motion "
                         "and needs --predictor (or an hq init); hs adds every h feature gated by skyhook's "
                         "switching state; hst adds to hs the top tension and along-cable velocity over the last 2 s; hsf adds to "
                         "hs every h feature gated by the fish's switching state (fish heave rate and stroke "
                         "velocity of one sign); hsfo adds to hsf every h feature gated by the stroke's direction "
                         "(outward, towards the nearer end stop)")
    ap.add_argument("--predictor", default=None, help="predictor file of feature set hq (python -m agents.predictor "
                                                      "--env towenv/CompensatorGains-v0 --out FILE)")
    ap.add_argument("--free", default="all", choices=("all",) + tuple(arc.ADDED_KINDS),
                    help="which weights the search moves: all (default), only the predicted features' (hq), only "
                         "the skyhook-gated copy's (hs, hst, hsf), only the cable features' (hst: top tension and "
                         "along-cable velocity histories), only the fish-gated copy's (hsf, hsfo), or only the "
                         "outward-gated copy's (hsfo)")
    ap.add_argument("--entries", type=int, nargs="+", default=None,
                    help="indices of the evaluation (sea state, heading) entries to train on (default all 12)")
    ap.add_argument("--columns", type=int, default=None,
                    help="Jacobian columns per iteration: K of the moved weights drawn at random each iteration "
                         "(default: all of them)")
    ap.add_argument("--shared-warmup", action="store_true",
                    help="run each Jacobian episode's unscored first --discard seconds once, under the current "
                         "weights, and branch it into the perturbed copies (about a third less Jacobian work)")
    add_parallel_flag(ap)
    ap.add_argument("--export", default=None, help="policy file (default runs/gn_CompensatorGains-v0_s<seed>.npz)")
    ap.add_argument("--save-iterates", action="store_true",
                    help="also write the policy after each iteration's step, beside --export as <stem>_it<NN>.npz "
                         "(NN the Gauss-Newton iteration number; the last equals --export)")
    a = ap.parse_args(argv)
    if not 1 <= a.iterations <= MAX_ITERATIONS:
        ap.error(f"--iterations must be in 1..{MAX_ITERATIONS} (got {a.iterations})")
    if not 1 <= a.replicates <= 10:
        ap.error(f"--replicates must be in 1..10 (got {a.replicates})")
    for name in ("minutes", "eps"):
        v = getattr(a, name)
        if not (math.isfinite(v) and v > 0):
            ap.error(f"--{name} must be a positive number (got {v})")
    for name in ("pitch_weight", "hit_weight", "margin_weight"):
        v = getattr(a, name)
        if not (math.isfinite(v) and v >= 0):
            ap.error(f"--{name.replace('_', '-')} must be a number >= 0 (got {v})")
    if any(not (math.isfinite(r) and r > 0) for r in a.ridges):
        ap.error(f"--ridges must be positive numbers (got {a.ridges})")
    if a.stop_guard is not None and not 0.0 <= a.stop_guard <= 1.0:
        ap.error(f"--stop-guard must be 0 (off) or in (0, 1] (got {a.stop_guard})")
    init = None
    if a.init:
        try:
            init = arc.load_policy(a.init)
        except (OSError, ValueError, KeyError) as e:
            ap.error(f"--init: {e}")
    from .predictor import load_option
    predictor = load_option(ap, a.predictor)
    out = Path(a.export or default_export(a.seed))
    try:
        pol = train(a.seed, a.iterations, a.minutes, a.replicates, a.eps, a.ridges, a.pitch_weight, a.hit_weight,
                    a.margin_weight, stop_guard=a.stop_guard, init=init, entries=a.entries, feature_set=a.features,
                    predictor=predictor, free=a.free, parallel=a.parallel,
                    columns=a.columns, shared_warmup=a.shared_warmup)
    except ValueError as e:
        ap.error(str(e))
    arc.save_policy(pol, out)
    if a.save_iterates:
        for p in iterate_policies(pol, out.stem):
            arc.save_policy(p, out.with_name(p.name + ".npz"))
        print(f"[gn_comp] wrote {len(pol.iterates)} iterates {out.with_name(out.stem + '_itNN.npz')}")
    print(f"[gn_comp] wrote {out} ({pol.meta['iterations']} iterations, {pol.meta['wall_seconds'] / 60:.1f} min)")
    return 0
