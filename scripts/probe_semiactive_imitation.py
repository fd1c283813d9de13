"""Can a causal policy learn what the clairvoyant semi-active plans do? A supervised probe for CompensatorGains.

``scripts/probe_semiactive_clairvoyant.py --seed-set teacher --save-plans DIR`` plans skyhook + open-loop (k, b)
corrections with perfect foresight on teacher wave seeds (``1000·code + j + 92000 + 10·replicate``, disjoint from
every other seed set). This probe

1. replays every plan (the simulator is deterministic: the replay reproduces the plan's σ, checked) and records
   the ARS compensator features φ(t) (``agents/ars_compensator.py``: 2 s of MRU history, stroke, fish sensors)
   and the correction the plan actually applied, c(t) = clip(a_skyhook + Θ_b φ + u_j) − a_skyhook, for t ≥ the
   plan's start (Θ_b: the residual of the plan's ``--base-policy``, 0 for plans on skyhook alone — planning on top
   of an imitation policy and fitting again is DAgger-like: the teacher corrects the learner's own states);
2. fits, per sea state, the linear residual Θ (2 × 45, the ARS policy class) by ridge regression of c on φ
   (λ relative to the mean diagonal of φᵀφ, ``--ridges``) and reports how much of the plans' corrections the
   causal features explain (R² on the teacher plans, and leave-one-episode-out R², which picks λ);
3. runs skyhook + Θφ on the evaluation entries (wave seeds +0; not the final set) for every λ in one batched
   rollout, against skyhook (Θ = 0), and prints σ of fish heave, significant heave, end-stop hits and pitch.

With ``--out FILE`` the λ picked by leave-one-episode-out R² is written as an ARS compensator policy file
(``scripts/evaluate.py`` evaluates it like any ARS policy).

    python scripts/probe_semiactive_imitation.py --plans runs/teacher/plans
"""
from __future__ import annotations

import argparse
import glob
import math
import sys
from pathlib import Path

import numpy as np


def _probe_module():
    here = str(Path(__file__).resolve().parent)
    if here not in sys.path:
        sys.path.insert(0, here)
    import probe_semiactive_clairvoyant as p
    return p


def replay(plans, episode_seconds: float):
    """Replay every plan in one batched run; returns (φ (T, n, F), c (T, n, 2), mask (T, n) of t ≥ the plan's start,
    σ of fish heave over t ≥ discard per plan)."""
    from agents import ars_compensator as arc
    from agents.baselines import load_tuned
    from agents.common import reset_copies
    from towenv.envs.vector import CompensatorGainsVectorEnv
    n = len(plans)
    venv = CompensatorGainsVectorEnv(num_envs=n, autoreset_mode="NextStep", batch_infos=True,
                                     episode_seconds=float(episode_seconds))
    batch = arc._Batch(venv, dict(load_tuned()["skyhook"]), dict(arc.FEATURE_SCALES))
    seas = [p["sea"] for p in plans]
    obs = reset_copies(venv, seas, [p["seed"] for p in plans])
    batch.set_seas(seas)
    T = venv.envs[0].max_steps
    F = arc.N_FEATURES
    Phi, C = np.zeros((T, n, F)), np.zeros((T, n, 2))
    M = np.zeros((T, n), bool)
    H, t = np.zeros((T, n)), np.zeros(T)
    th_b = np.array([p["theta_base"] for p in plans])
    for k in range(T):
        Phi[k] = batch.features(obs, k == 0)
        base = batch.base_action(obs)
        with_base = base + arc._residual(th_b, Phi[k])
        u = np.zeros((n, 2))
        for i, p in enumerate(plans):
            j = (k - p["k0"]) // p["block"]
            if 0 <= k - p["k0"] and j < p["U"].shape[0]:
                u[i] = p["U"][j]
                M[k, i] = True
        a = np.clip(with_base + u, -1.0, 1.0).astype(np.float32)
        C[k] = a - base
        obs, _r, _term, _trunc, infos = venv.step(a)
        H[k], t[k] = infos["fish_heave"], infos["t"][0]
    venv.close()
    w = t >= plans[0]["discard"]
    return Phi, C, M, H[w].std(axis=0)


def ridge_fit(X, Y, lam: float):
    """argmin ||Y − X Θᵀ||² + λ·mean(diag XᵀX)·||Θ||² -> Θ (2, F)."""
    A = X.T @ X
    A = A + lam * np.mean(np.diag(A)) * np.eye(A.shape[0])
    return np.linalg.solve(A, X.T @ Y).T


def r2(X, Y, theta):
    res = Y - X @ theta.T
    return 1.0 - (res ** 2).sum() / ((Y - Y.mean(axis=0)) ** 2).sum()


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--plans", default="runs/teacher/plans", help="directory of plan_<seed>.npz files")
    ap.add_argument("--ridges", type=float, nargs="+", default=[0.001, 0.01, 0.1, 1.0])
    ap.add_argument("--entries", type=int, nargs="+", default=None, help="evaluation entries (default all)")
    ap.add_argument("--out", default=None, help="write the policy of the λ picked by leave-one-episode-out R²")
    a = ap.parse_args(argv)
    if any(not (math.isfinite(r) and r > 0) for r in a.ridges):
        ap.error(f"--ridges must be positive numbers (got {a.ridges})")
    files = sorted(glob.glob(str(Path(a.plans) / "plan_*.npz")))
    if not files:
        ap.error(f"--plans: no plan_*.npz in {a.plans}")
    import gymnasium as gym

    import towenv  # noqa: F401
    from agents import ars_compensator as arc
    from agents.baselines import load_tuned
    from agents.common import sea_key
    probe = _probe_module()
    plans = [probe.load_plan(f) for f in files]
    T_s = None
    for p in plans:
        if (p["k0"], p["block"], p["discard"]) != (plans[0]["k0"], plans[0]["block"], plans[0]["discard"]):
            ap.error("--plans: the plans differ in start, block or discard; use plans of one probe setting")
    env = gym.make(arc.ENV_ID)
    ev = env.unwrapped.eval_sea_states()
    dt = env.unwrapped.dt
    env.close()
    T_s = (plans[0]["k0"] + plans[0]["block"] * plans[0]["U"].shape[0]) * dt
    T_s = round(T_s, 6)
    entries = list(range(len(ev))) if a.entries is None else a.entries
    if any(not 0 <= e < len(ev) for e in entries):
        ap.error(f"--entries must be in 0..{len(ev) - 1}")
    print(f"[imitation] {len(plans)} teacher plans ({T_s:g} s episodes); replaying", flush=True)
    Phi, C, M, sig = replay(plans, T_s)
    dev = np.abs(sig / np.array([p["sigma_plan"] for p in plans]) - 1)
    print(f"[imitation] replay reproduces the plans' σ to {dev.max():.1e} (relative)")
    if dev.max() > 1e-9:
        print("[imitation] WARNING: the replay differs from the plans (physics changed since planning?)")
    keys = sorted({sea_key(p["sea"]) for p in plans})
    theta = {lam: {} for lam in a.ridges}
    cv = {lam: [] for lam in a.ridges}
    for key in keys:
        idx = [i for i, p in enumerate(plans) if sea_key(p["sea"]) == key]
        Xs = [Phi[M[:, i], i] for i in idx]
        Ys = [C[M[:, i], i] for i in idx]
        X, Y = np.concatenate(Xs), np.concatenate(Ys)
        line = []
        for lam in a.ridges:
            th = ridge_fit(X, Y, lam)
            theta[lam][key] = th
            # leave one episode out
            num = den = 0.0
            for m in range(len(idx)):
                Xt = np.concatenate([Xs[q] for q in range(len(idx)) if q != m])
                Yt = np.concatenate([Ys[q] for q in range(len(idx)) if q != m])
                tm = ridge_fit(Xt, Yt, lam)
                num += ((Ys[m] - Xs[m] @ tm.T) ** 2).sum()
                den += ((Ys[m] - Yt.mean(axis=0)) ** 2).sum()
            cv[lam].append((num, den))
            line.append(f"λ {lam:g}: R² {r2(X, Y, th):.3f} (held-out {1 - num / den:.3f})")
        print(f"[imitation] {key} ({len(idx)} plans, {len(X)} steps, |c| RMS {np.sqrt((Y ** 2).mean()):.3f}): "
              + "; ".join(line), flush=True)
    cv_r2 = {lam: 1 - sum(n for n, _ in v) / sum(d for _, d in v) for lam, v in cv.items()}
    pick = max(a.ridges, key=lambda lam: cv_r2[lam])
    print(f"[imitation] λ picked by leave-one-episode-out R²: {pick:g} (R² {cv_r2[pick]:.3f})")

    # evaluation: skyhook (Θ = 0) and every λ, one batched rollout
    table, _ev, venv, batch = arc._setup(180.0, len(entries) * (len(a.ridges) + 1), dict(arc.FEATURE_SCALES))
    seas = [ev[e][0] for e in entries]
    seeds = [ev[e][1] for e in entries]
    th_all = [np.zeros((len(entries), 2, arc.N_FEATURES))]
    for lam in a.ridges:
        th_all.append(np.array([theta[lam][min(theta[lam], key=lambda k: _dist(k, s))] for s in seas]))
    sh, sp, hits, _mg = arc.rollout_batch(venv, batch, seas * (len(a.ridges) + 1), seeds * (len(a.ridges) + 1),
                                          np.concatenate(th_all), discard=60.0)
    venv.close()
    n = len(entries)
    codes = np.array([ev[e][1] // 1000 for e in entries])
    sky = sh[:n]
    print(f"[imitation] evaluation set ({n} entries, wave seeds +0, 180 s, scored from 60 s): σ heave pooled "
          "(RMS over entries) and per code, vs skyhook")
    rows = [("skyhook", None)] + [(f"imitation λ {lam:g}{' (picked)' if lam == pick else ''}", i + 1)
                                  for i, lam in enumerate(a.ridges)]
    for name, j in rows:
        s = sh[(j or 0) * n:((j or 0) + 1) * n]
        h = hits[(j or 0) * n:((j or 0) + 1) * n]
        p_ = sp[(j or 0) * n:((j or 0) + 1) * n]
        pooled = math.sqrt(np.nanmean(s ** 2)) / math.sqrt(np.mean(sky ** 2)) - 1
        per = []
        for c in sorted(set(codes)):
            m = codes == c
            per.append(f"code {c} {100 * (math.sqrt(np.nanmean(s[m] ** 2) / np.mean(sky[m] ** 2)) - 1):+.1f} %")
        print(f"  {name:28s} pooled {100 * pooled:+.1f} %, {', '.join(per)}; hits {h.sum():g}; "
              f"pitch σ {np.nanmean(p_):.2f}° (skyhook {np.nanmean(sp[:n]):.2f}°)", flush=True)
    if a.out:
        pol = arc.ARSCompensatorPolicy(theta[pick], dict(load_tuned()["skyhook"]), dict(arc.FEATURE_SCALES),
                                       meta={"trainer": "probe_semiactive_imitation", "ridge": pick,
                                             "plans": [p["seed"] for p in plans],
                                             "teacher_seeds": "1000*code + j + 92000 + 10*replicate"},
                                       name=Path(a.out).stem)
        print(f"[imitation] wrote {arc.save_policy(pol, a.out)}")
    return 0


def _dist(key, sea):
    from agents.common import parse_key
    h, t = parse_key(key)
    return math.log(h / float(sea.hs)) ** 2 + math.log(t / float(sea.tp)) ** 2


if __name__ == "__main__":
    raise SystemExit(main())
