"""Would a coarser physics step make compensator training cheaper without changing what it optimises? (issue 14
probe for the one-hour recipe).

Runs skyhook and the given CompensatorGains policies (ARS / Gauss–Newton class, ``agents/ars_compensator.py``) on
the same 24 episodes (the 12 evaluation (sea state, heading) entries × 2 replicates, 180 s each, scored after 60 s —
the Gauss–Newton trainer's episodes) at the environment's default physics step (0.05 s, two sub-steps per 10 Hz
control step) and at ``--dt`` (default 0.1 s, one sub-step), on the batched environment, and prints the wall time of
each batch and every policy's heave σ below skyhook per physics step, pooled and per sea state, with the
correlation of the per-episode log σ ratios. A training model is faithful if the policies' gains over skyhook
agree between the two steps.

Wave seeds: the Jacobian seeds of ``agents.gn_compensator`` training seed ``--seed`` (default 7), iteration 0 —
a block no committed run trained on (training seeds 0–5 and the pilot's 9) and no evaluation, tuning or final seed.

    python scripts/probe_training_dt.py agents/trained/gnspfr_CompensatorGains-v0_s0.npz agents/trained/gnspfr_CompensatorGains-v0_s1.npz agents/trained/gnsp_CompensatorGains-v0_s0.npz agents/trained/gnsfo_CompensatorGains-v0_s0.npz
"""
from __future__ import annotations

import argparse
import sys
import time

import numpy as np


def probe(paths, dt: float = 0.1, seed: int = 7, replicates: int = 2, episode_seconds: float = 180.0,
          discard: float = 60.0, parallel: bool = True, log=print) -> dict:
    """{physics step: (wall seconds, heave σ (controllers, episodes), sea-state code per episode)} for skyhook
    (row 0) and the policies in ``paths`` (rows 1…), all on one feature set's batch (the policies' own weights
    copied by feature name)."""
    import towenv  # noqa: F401
    from agents import ars_compensator as arc
    from agents.common import nearest_key
    from agents.gn import training_entries
    from agents.gn_compensator import initial_theta, train_seed
    from towenv.envs.vector import CompensatorGainsVectorEnv
    pols = [arc.load_policy(p) for p in paths]
    if not pols:
        raise ValueError("give at least one policy file")
    fs = max((p.feature_set for p in pols), key=arc.n_features)
    if any(not set(arc.feature_names(p.feature_set)) <= set(arc.feature_names(fs)) for p in pols):
        raise ValueError("the policies' feature sets must nest (one holds every other's features)")
    table, guard = pols[0].base_table, pols[0].stop_guard
    if any(p.base_table != table or p.stop_guard != guard or p.scales != pols[0].scales for p in pols):
        raise ValueError("the policies must share skyhook's table, the stop guard and the feature scales")
    ev, idx, keys = training_entries(arc.ENV_ID, table, None)
    ents = [(ev[i][0], ev[i][1], r) for r in range(replicates) for i in idx]
    code = np.array([keys.index(nearest_key(table, sea)) for sea, _s, _r in ents])
    seas = [sea for sea, _s, _r in ents]
    seeds = [train_seed(s + 10 * r, 0, seed) for _sea, s, r in ents]
    n = len(ents)
    thetas = [np.zeros((n, arc.N_ACT, arc.n_features(fs)))] + [initial_theta(p, keys, fs)[code] for p in pols]
    cand = np.concatenate(thetas)
    k = len(thetas)
    out = {}
    for step in (None, float(dt)):
        venv = CompensatorGainsVectorEnv(num_envs=len(cand), autoreset_mode="NextStep", batch_infos=True,
                                         episode_seconds=float(episode_seconds), parallel=bool(parallel),
                                         **({} if step is None else {"dt": step}))
        phys = float(venv.envs[0].physics_dt)
        batch = arc._Batch(venv, table, dict(pols[0].scales), fs, None)
        t0 = time.perf_counter()
        sh, _sp, _hits, _mg = arc.rollout_batch(venv, batch, seas * k, seeds * k, cand, discard=discard,
                                                margin_start=arc.DEFAULT_MARGIN_START, stop_guard=guard)
        out[phys] = (time.perf_counter() - t0, sh.reshape(k, n), code)
        venv.close()
        log(f"physics step {phys:g} s: {out[phys][0]:.1f} s wall for {k} x {n} episodes of {episode_seconds:g} s")
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policies", nargs="+", help="CompensatorGains ARS / Gauss-Newton policy files (.npz)")
    ap.add_argument("--dt", type=float, default=0.1, help="the coarser physics step (s; default 0.1)")
    ap.add_argument("--seed", type=int, default=7, help="gn_compensator training seed whose wave seeds to use")
    a = ap.parse_args(argv)
    if not 0.05 < a.dt <= 0.1:
        ap.error(f"--dt must be in (0.05, 0.1] s: coarser than the default, at most one 10 Hz control period "
                 f"(got {a.dt})")
    if not 6 <= a.seed <= 8:
        ap.error(f"--seed must be 6, 7 or 8 (training blocks no committed run used; got {a.seed})")
    try:
        res = probe(a.policies, a.dt, a.seed)
    except (OSError, ValueError, KeyError) as exc:
        ap.error(str(exc))
    (d0, (w0, h0, code)), (d1, (w1, h1, _)) = sorted(res.items())
    print(f"\ncost: {w1 / w0:.2f}x the wall time at {d1:g} s against {d0:g} s")
    names = ["skyhook"] + [a_.rsplit("/", 1)[-1].removesuffix(".npz") for a_ in a.policies]
    codes = sorted(set(code.tolist()))
    print(f"| controller | heave σ at {d0:g} s / {d1:g} s (cm) | below skyhook at {d0:g} s / {d1:g} s | per sea "
          "state (same) | per-episode log σ ratio: correlation, mean shift |")
    print("|---|---|---|---|---|")
    for j, nm in enumerate(names):
        row = f"| {nm} | {100 * h0[j].mean():.2f} / {100 * h1[j].mean():.2f} |"
        if j == 0:
            print(row + " – | – | – |")
            continue
        red = lambda h, m: 100 * (1 - h[j][m].mean() / h[0][m].mean())      # noqa: E731
        allm = np.ones(len(code), bool)
        per = ", ".join(f"{red(h0, code == c):+.1f} / {red(h1, code == c):+.1f}" for c in codes)
        r0, r1 = np.log(h0[j] / h0[0]), np.log(h1[j] / h1[0])
        print(row + f" {red(h0, allm):+.1f} / {red(h1, allm):+.1f} % | {per} | {np.corrcoef(r0, r1)[0, 1]:.2f}, "
                    f"{np.mean(r1 - r0):+.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
