"""Benchmark and fidelity check (issue 14): the Gauss–Newton compensator search's Jacobian rollout with and without
the shared warm-up (``agents/gn_compensator.py --shared-warmup``).

One Jacobian rollout of the trainer — the 24 training episodes (12 sea-state entries x 2 replicates, 180 s each, scored
after 60 s) x (K random columns + 1), a committed policy's weights, the column draw and wave seeds of a training
block no committed run used (training seed 7, iteration 0) — run alternately as plain episodes
(``rollout_series``: every copy from t = 0) and with the unscored first 60 s run once per episode under Θ and
branched into the copies (``rollout_series_shared``). Prints the wall time of each (median of the pairs and
their ratio), the relative difference of the heave Jacobians over the scored window (and after its first 15 s), and
per sea state and ridge the cosine and norm ratio of the two Gauss–Newton steps — what the shared warm-up changes
in an iteration's step; and, as the yardstick, the same comparison for plain episodes with another finite-difference
step (``--noise-eps``, default 0.012 against the trainer's 0.01): the finite-difference Jacobian's own spread.

    python scripts/bench_shared_warmup.py                        # 744 copies, 2 pairs, both cores, ~5 minutes
    python scripts/bench_shared_warmup.py --columns 10 --pairs 1
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

DEFAULT_POLICY = Path(__file__).resolve().parents[1] / "agents" / "trained" / "gnspfr_CompensatorGains-v0_s0.npz"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--policy", default=str(DEFAULT_POLICY), help="CompensatorGains ARS / Gauss-Newton policy file "
                                                                 "(default: gnspfr seed 0, feature set hsfo)")
    ap.add_argument("--free", default="outward", help="which weights the columns are drawn from (default outward)")
    ap.add_argument("--columns", type=int, default=30, help="random Jacobian columns (default 30)")
    ap.add_argument("--replicates", type=int, default=2, help="wave seeds per entry (default 2)")
    ap.add_argument("--pairs", type=int, default=2, help="alternating plain/shared pairs (default 2)")
    ap.add_argument("--serial", action="store_true", help="step the copies on one thread")
    ap.add_argument("--noise-eps", type=float, default=0.012,
                    help="also run plain episodes with this finite-difference step (0: skip) and print the same "
                         "comparison against the plain ones: the finite-difference Jacobian's own spread, against "
                         "which the shared warm-up's difference reads (default 0.012)")
    a = ap.parse_args(argv)
    for name, v in (("--columns", a.columns), ("--replicates", a.replicates), ("--pairs", a.pairs)):
        if v < 1:
            ap.error(f"{name} must be at least 1 (got {v})")
    import towenv  # noqa: F401
    from agents import ars_compensator as arc
    from agents import gn_compensator as gnc
    from agents.common import nearest_key
    from agents.gn import training_entries
    from towenv.envs.vector import CompensatorGainsVectorEnv
    try:
        pol = arc.load_policy(a.policy)
        mask = gnc.free_mask(pol.feature_set, a.free)
    except (OSError, ValueError, KeyError) as exc:
        ap.error(f"--policy / --free: {exc}")
    moved = np.flatnonzero(mask)
    if not 1 <= a.columns <= len(moved):
        ap.error(f"--columns must be in 1..{len(moved)} for --free {a.free} (got {a.columns})")
    ev, idx, keys = training_entries(arc.ENV_ID, pol.base_table, None)
    R = a.replicates
    ents = [(ev[i][0], ev[i][1]) for _r in range(R) for i in idx]
    reps = [r for r in range(R) for _i in idx]
    seas = [s for s, _ in ents]
    seeds = [gnc.train_seed(s + 10 * r, 0, 7) for (_sea, s), r in zip(ents, reps)]
    code = np.array([keys.index(nearest_key(pol.base_table, s)) for s in seas])
    NA, NF, n_ep, NW = arc.N_ACT, arc.n_features(pol.feature_set), len(ents), a.columns
    free_idx = moved[gnc.column_subset(len(moved), NW, 7, 0)]
    theta = gnc.initial_theta(pol, keys, pol.feature_set)
    th = np.repeat(theta[code].reshape(n_ep, NA * NF)[None], NW + 1, axis=0)
    eps, discard, ridges = 0.01, 60.0, [0.01, 0.1, 1.0, 10.0, 100.0]
    th2 = th.copy()
    for i, f in enumerate(free_idx):
        th[i + 1, :, f] += eps
        th2[i + 1, :, f] += a.noise_eps
    kw = dict(autoreset_mode="NextStep", batch_infos=True, episode_seconds=180.0, parallel=not a.serial)
    venv = CompensatorGainsVectorEnv(num_envs=n_ep * (NW + 1), **kw)
    venv_w = CompensatorGainsVectorEnv(num_envs=n_ep, **kw)
    batch = arc._Batch(venv, pol.base_table, pol.scales, pol.feature_set, pol.predictor)
    batch_w = arc._Batch(venv_w, pol.base_table, pol.scales, pol.feature_set, pol.predictor)
    warm = gnc.warmup_steps(venv.envs[0].max_steps, venv.envs[0].dt, discard)
    print(f"# Jacobian rollout: {n_ep} episodes x ({NW} columns of {pol.name}'s {a.free} weights + 1) = "
          f"{n_ep * (NW + 1)} copies of 180 s, scored after {discard:g} s; shared warm-up {warm} control steps; "
          f"{'one thread' if a.serial else 'all numba threads'}", flush=True)

    tiny = CompensatorGainsVectorEnv(num_envs=1, **kw)          # load (or compile) the kernels outside the timings
    tiny.reset(seed=0)
    tiny.step(np.zeros((1, NA), np.float32))
    tiny.close()

    def plain():
        return arc.rollout_series(venv, batch, seas * (NW + 1), seeds * (NW + 1), th.reshape(-1, NA, NF),
                                  stop_guard=pol.stop_guard)

    def shared():
        return arc.rollout_series_shared(venv_w, batch_w, venv, batch, seas, seeds, th[0].reshape(-1, NA, NF),
                                         th.reshape(-1, NA, NF), warm, stop_guard=pol.stop_guard)

    walls = {"plain": [], "shared": []}
    out = {}
    for p in range(a.pairs):
        for name in (("plain", "shared") if p % 2 == 0 else ("shared", "plain")):
            t0 = time.perf_counter()
            out[name] = (plain if name == "plain" else shared)()
            walls[name].append(time.perf_counter() - t0)
            print(f"pair {p} {name}: {walls[name][-1]:.1f} s", flush=True)
    ratios = [s / q for s, q in zip(walls["shared"], walls["plain"])]
    print(f"wall per Jacobian rollout: plain {statistics.median(walls['plain']):.1f} s, shared "
          f"{statistics.median(walls['shared']):.1f} s; shared/plain median {statistics.median(ratios):.3f} "
          f"(pairs {min(ratios):.3f}-{max(ratios):.3f})")
    if a.noise_eps > 0:
        out["plain, eps2"] = arc.rollout_series(venv, batch, seas * (NW + 1), seeds * (NW + 1),
                                                th2.reshape(-1, NA, NF), stop_guard=pol.stop_guard)
    res = {}
    for name, e in (("plain", eps), ("shared", eps), ("plain, eps2", a.noise_eps)):
        if name not in out:
            continue
        H, P, S, t, _hits, ended, _a = out[name]
        res[name] = gnc.jacobian_steps((H, P, S, t, ended), NW, discard, e, arc.DEFAULT_MARGIN_START, 0.5,
                                       arc.DEFAULT_MARGIN_WEIGHT, code, len(keys), ridges)
    t = out["plain"][3]
    tw = t[t >= discard]
    late = tw >= discard + 15.0
    Jp = res["plain"][1]
    others = [n for n in ("shared", "plain, eps2") if n in res]
    for name in others:
        J = res[name][1]
        rel = np.linalg.norm(J - Jp) / np.linalg.norm(Jp)
        rel_late = np.linalg.norm(J[late] - Jp[late]) / np.linalg.norm(Jp[late])
        print(f"heave Jacobian, {name} vs plain (eps {eps:g}): relative difference {rel:.3f} over the scored window, "
              f"{rel_late:.3f} after its first 15 s")
    print("Gauss-Newton steps against the plain ones: cosine and norm ratio per sea state and ridge")
    print("| sea state | ridge | " + " | ".join(f"{n}: cosine | {n}: norm ratio" for n in others) + " |")
    print("|---|---|" + "---|---|" * len(others))
    for c, k in enumerate(keys):
        for j, lam in enumerate(ridges):
            sp = res["plain"][0][j, c]
            cells = []
            for name in others:
                ss = res[name][0][j, c]
                cells.append(f"{float(sp @ ss / (np.linalg.norm(sp) * np.linalg.norm(ss))):.3f} | "
                             f"{np.linalg.norm(ss) / np.linalg.norm(sp):.3f}")
            print(f"| {k} | {lam:g} | " + " | ".join(cells) + " |")
    venv.close()
    venv_w.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())
