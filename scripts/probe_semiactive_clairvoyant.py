"""A clairvoyant *semi-active* reference for CompensatorGains, probed on a few episodes: how far below skyhook can a
(k, b) schedule go when it knows the episode's future?

The only computed bound of the compensator goal is ``clairvoyant_active`` — a stroke trajectory with an ideal
position actuator, a relaxation no semi-active law can reach (docs/agents.md). This probe builds the feasible
counterpart: the skyhook law plus an **open-loop correction planned with perfect foresight** of the episode,

    a(t) = clip(a_skyhook(obs(t)) + u_j, −1, 1)        for t in block j (``--block`` seconds; u = 0 before
                                                       ``discard − 10 s``), a = (log-stiffness, log-damping)

so every action is a (k, b) inside the environment's ranges: a semi-active controller with clairvoyance. u is
optimised on the episode itself (the same sea state and wave seed; the simulator is deterministic) by Gauss–Newton
on finite-difference trajectory Jacobians (``agents/gn_compensator.py``'s method with one episode and the block
corrections as the weights): residuals fish heave (window mean removed) and the stroke margin max(|s| − 0.85, 0)
(weight ``--margin-weight``), ridge steps λ = 0.1 … 1000 (``--ridges``), each tried on the episode; the best of (current,
candidates) by ln σ_h + 0.3·(end-stop hits) + margin term is kept. A found schedule is *attainable* by a
semi-active device with foresight — a lower estimate of what clairvoyance allows, not an upper bound (a local
search over a coarse parametrisation).

    python scripts/probe_semiactive_clairvoyant.py --entries 0 4 8       # one eval episode per sea state

``--seed-set teacher --replicate r`` plans on wave seeds ``1000·code + j + 92000 + 10·r`` (``TEACHER_SEED_OFFSET``;
never an evaluation, final, tuning or training seed of any other set, tested) and ``--save-plans DIR`` writes every
plan as ``DIR/plan_<seed>.npz`` (corrections, sea state, seed, block layout, σ before and after) for
``scripts/probe_semiactive_imitation.py``, which fits a causal policy to them.
"""
from __future__ import annotations

import argparse
import math
import time

import numpy as np

#: wave seeds of the teacher plans: base seed (1000·code + j) + 92000 + 10·replicate (replicate 0..9)
TEACHER_SEED_OFFSET = 92000
MAX_REPLICATES = 10


def teacher_seed(base_seed: int, replicate: int) -> int:
    if not 0 <= int(replicate) < MAX_REPLICATES:
        raise ValueError(f"replicate {replicate} outside 0..{MAX_REPLICATES - 1} (seed-set disjointness)")
    return int(base_seed) + TEACHER_SEED_OFFSET + 10 * int(replicate)


def save_plan(path, U, sea, seed, k0, block, discard, sky, plan, theta_base=None):
    """Write one plan atomically: U (NB, 2) block corrections from control step k0 in blocks of ``block`` steps, on
    top of skyhook + the base policy's residual ``theta_base`` (2, F; zeros: skyhook alone)."""
    from agents.ars_compensator import N_ACT, N_FEATURES
    theta_base = np.zeros((N_ACT, N_FEATURES)) if theta_base is None else np.asarray(theta_base, float)
    import dataclasses
    import json
    import os
    from pathlib import Path
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    tmp = path.with_suffix(".tmp.npz")
    np.savez(tmp, U=np.asarray(U, float), k0=int(k0), block=int(block), discard=float(discard), seed=int(seed),
             sea=json.dumps(dataclasses.asdict(sea)), sigma_skyhook=float(sky), sigma_plan=float(plan),
             theta_base=theta_base)
    os.replace(tmp, path)
    return path


def load_plan(path):
    import json

    from agents.ars_compensator import N_ACT, N_FEATURES
    from towenv.sea import SeaState
    with np.load(path) as z:
        d = {k: z[k] for k in z.files}
    return dict(U=d["U"], k0=int(d["k0"]), block=int(d["block"]), discard=float(d["discard"]), seed=int(d["seed"]),
                sea=SeaState(**json.loads(str(d["sea"]))), sigma_skyhook=float(d["sigma_skyhook"]),
                sigma_plan=float(d["sigma_plan"]),
                theta_base=d.get("theta_base", np.zeros((N_ACT, N_FEATURES))))   # files without it: skyhook base


def run_plan(venv, batch, sea, seed, U, k0, block, margin_start, theta=None):
    """Every copy i runs (sea, seed) with the block corrections U[i] (NB, 2) on top of skyhook (+ the linear
    residual ``theta`` (2, F) of a base policy, if given); returns heave, pitch, stroke (T, n), time (T,), hits (n,),
    ended (n,)."""
    from agents import ars_compensator as arc
    from agents.common import reset_copies
    n = venv.num_envs
    obs = reset_copies(venv, [sea] * n, [seed] * n)
    batch.set_seas([sea] * n)
    T = venv.envs[0].max_steps
    H, P, S = np.zeros((T, n)), np.zeros((T, n)), np.zeros((T, n))
    t = np.zeros(T)
    hits = np.zeros(n)
    ended = np.zeros(n, bool)
    th = None if theta is None else np.repeat(np.asarray(theta, float)[None], n, axis=0)
    for k in range(T):
        j = (k - k0) // block
        u = U[:, j] if 0 <= k - k0 and j < U.shape[1] else 0.0
        base = batch.base_action(obs)
        if th is not None:
            base = base + arc._residual(th, batch.features(obs, k == 0))
        a = np.clip(base + u, -1.0, 1.0).astype(np.float32)
        obs, _r, term, trunc, infos = venv.step(a)
        H[k], P[k] = infos["fish_heave"], infos["fish_pitch"]
        S[k] = batch.reader.batch(obs, "comp_stroke")
        t[k] = infos["t"][0]
        hits += np.where(ended, 0, infos["end_stop_hits"])
        if k < T - 1:
            ended |= term | trunc
    return H, P, S, t, hits, ended


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--entries", type=int, nargs="+", default=[0, 4, 8], help="eval_sea_states() indices")
    ap.add_argument("--seed-set", choices=("eval", "final", "teacher"), default="eval",
                    help="eval (+0), final (+20000) or teacher (+92000 + 10*replicate) wave seeds")
    ap.add_argument("--replicate", type=int, default=0, help="teacher seed set: replicate 0..9")
    ap.add_argument("--base-policy", default=None,
                    help="plan on top of this ARS compensator policy (skyhook + its linear residual; no stop guard) "
                         "instead of skyhook alone")
    ap.add_argument("--save-plans", default=None, help="directory to write every plan to (plan_<seed>.npz)")
    ap.add_argument("--iterations", type=int, default=6)
    ap.add_argument("--block", type=float, default=1.0, help="length of a correction block (s)")
    ap.add_argument("--episode-seconds", type=float, default=180.0)
    ap.add_argument("--discard", type=float, default=60.0)
    ap.add_argument("--eps", type=float, default=0.02, help="finite-difference step of a block correction")
    ap.add_argument("--margin-weight", type=float, default=1000.0)
    ap.add_argument("--ridges", type=float, nargs="+", default=[0.1, 1.0, 10.0, 100.0, 1000.0],
                    help="ridge weights of the candidate steps (relative to the normal matrix's mean diagonal)")
    ap.add_argument("--verbose", action="store_true", help="print Jacobian and step norms and every candidate")
    a = ap.parse_args(argv)
    if not 0 <= a.replicate < MAX_REPLICATES:
        ap.error(f"--replicate must be in 0..{MAX_REPLICATES - 1}")
    if a.iterations < 1 or not a.block > 0 or not a.episode_seconds > a.discard + 10 or not a.eps > 0:
        ap.error("need --iterations >= 1, --block > 0, --episode-seconds > discard + 10, --eps > 0")
    if any(not (math.isfinite(r) and r > 0) for r in a.ridges):
        ap.error(f"--ridges must be positive numbers (got {a.ridges})")
    import gymnasium as gym

    import towenv  # noqa: F401
    from agents import ars_compensator as arc
    from agents.baselines import load_tuned, make_baseline
    from agents.gn import gauss_newton_steps
    from agents.metrics import episode_metrics, rollout
    from towenv.envs.vector import CompensatorGainsVectorEnv
    base_pol = None
    if a.base_policy:
        try:
            base_pol = arc.load_policy(a.base_policy)
        except ValueError as exc:
            ap.error(f"--base-policy: {exc}")
        if base_pol.stop_guard:
            ap.error(f"--base-policy: {a.base_policy} has a stop guard ({base_pol.stop_guard:g}); the probe plans "
                     "on linear residuals only")
    env = gym.make(arc.ENV_ID, episode_seconds=a.episode_seconds)
    ev = env.unwrapped.eval_sea_states()
    if any(not 0 <= e < len(ev) for e in a.entries):
        ap.error(f"--entries must be in 0..{len(ev) - 1}")
    dt = env.unwrapped.dt
    block = max(1, int(round(a.block / dt)))
    k0 = int(round((a.discard - 10.0) / dt))
    T = env.unwrapped.max_steps
    NB = -(-(T - k0) // block)
    NW = 2 * NB
    table = dict(load_tuned()["skyhook"])
    ridges = tuple(a.ridges)
    kw = dict(autoreset_mode="NextStep", batch_infos=True, episode_seconds=float(a.episode_seconds))
    venv_j = CompensatorGainsVectorEnv(num_envs=NW + 1, **kw)
    venv_l = CompensatorGainsVectorEnv(num_envs=len(ridges) + 1, **kw)
    batch_j = arc._Batch(venv_j, table, dict(arc.FEATURE_SCALES))
    batch_l = arc._Batch(venv_l, table, dict(arc.FEATURE_SCALES))
    print(f"[semiactive] {len(a.entries)} episodes of {a.episode_seconds:g} s, scored from {a.discard:g} s; "
          f"{NB} blocks of {block * dt:g} s x 2 gains = {NW} corrections; {a.iterations} iterations")
    ref = "skyhook" if base_pol is None else "base policy"
    for e in a.entries:
        sea = ev[e][0]
        seed = (teacher_seed(ev[e][1], a.replicate) if a.seed_set == "teacher"
                else ev[e][1] + (20000 if a.seed_set == "final" else 0))
        t0 = time.perf_counter()
        bp = episode_metrics(rollout(env, make_baseline("best_passive", env), sea, seed), a.discard)
        U = np.zeros((1, NB, 2))
        th_b = None
        if base_pol is not None:
            from agents.common import nearest_key
            th_b = base_pol.theta[nearest_key(base_pol.theta, sea)]

        def score(H, P, S, t, hits, ended):
            w = t >= a.discard
            sh = H[w].std(axis=0)
            sp = np.degrees(P[w].std(axis=0))
            mg = arc.margin_penalty(S[w]).mean(axis=0)
            c = np.log(sh) + 0.3 * hits + a.margin_weight * mg
            return sh, sp, np.where(ended, np.inf, c)

        H, P, S, t, hits, ended = run_plan(venv_l, batch_l, sea, seed, np.zeros((len(ridges) + 1, NB, 2)), k0, block, 0.85,
                                           th_b)
        sh0, sp0, c0 = score(H, P, S, t, hits, ended)
        sky = (sh0[0], sp0[0], hits[0])
        cur = (sh0[0], sp0[0], hits[0], c0[0])
        hist = [sh0[0]]
        for it in range(a.iterations):
            Ucop = np.repeat(U, NW + 1, axis=0)
            flat = Ucop.reshape(NW + 1, NW)
            flat[1:] += a.eps * np.eye(NW)
            H, P, S, t, hits, ended = run_plan(venv_j, batch_j, sea, seed, flat.reshape(NW + 1, NB, 2), k0, block,
                                               0.85, th_b)
            w = t >= a.discard
            Y = H[w] - H[w].mean(axis=0)
            M = np.sqrt(arc.margin_penalty(S[w]))
            Jy = ((Y[:, 1:] - Y[:, :1]) / a.eps)[:, :, None]
            Jm = ((M[:, 1:] - M[:, :1]) / a.eps)[:, :, None]
            y0, m0 = Y[:, :1], M[:, :1]
            steps = gauss_newton_steps([(Jy, y0, np.array([1.0 / y0.std() ** 2])),
                                        (Jm, m0, np.array([2.0 * a.margin_weight]))], np.zeros(1, int),
                                       np.ones(1, bool), 1, ridges)[:, 0]
            cand = np.concatenate([U.reshape(1, NW), U.reshape(1, NW) + steps]).reshape(len(ridges) + 1, NB, 2)
            H, P, S, t, hits, ended = run_plan(venv_l, batch_l, sea, seed, cand, k0, block, 0.85, th_b)
            sh, sp, c = score(H, P, S, t, hits, ended)
            if a.verbose:
                print(f"  |Jy| {np.linalg.norm(Jy):.3g} |Jm| {np.linalg.norm(Jm):.3g} steps {np.linalg.norm(steps, axis=1).round(3)} "
                      f"σ {sh.round(4)} hits {hits} cost {c.round(4)}")
            j = int(np.argmin(c))
            if j > 0:
                U = cand[j:j + 1].copy()
            cur = (sh[j], sp[j], hits[j], c[j])
            hist.append(sh[j])
            print(f"[semiactive] entry {e} it {it}: σ_h {sh[j]:.4f} m ({100 * (sh[j] / sky[0] - 1):+.1f} % vs {ref}), "
                  f"hits {hits[j]:g}, pick {'current' if j == 0 else f'ridge {ridges[j - 1]:g}'} "
                  f"[{time.perf_counter() - t0:.0f} s]", flush=True)
        print(f"[semiactive] entry {e} ({sea.label}, wave seed {seed}): significant heave best_passive "
              f"{bp['sig_heave']:.3f} m, {ref} {2 * sky[0]:.3f} m "
              f"({sky[2]:g} hits), clairvoyant semi-active {2 * cur[0]:.3f} m ({cur[2]:g} hits): "
              f"{100 * (1 - cur[0] / sky[0]):.1f} % below {ref}, pitch σ {cur[1]:.2f}° vs {ref} {sky[1]:.2f}°; "
              f"|u| max {np.abs(U).max():.2f}", flush=True)
        if a.save_plans:
            save_plan(f"{a.save_plans}/plan_{seed}.npz", U[0], sea, seed, k0, block, a.discard, sky[0], cur[0], th_b)
    venv_j.close()
    venv_l.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
