"""Benchmark (issues 14/15): the wall time of one Gauss–Newton training rollout of the CompensatorGains trainer.

``agents.ars_compensator.rollout_series`` runs one 180 s episode (1800 control steps) in every copy of a batched
``CompensatorGainsVectorEnv`` — the trainer's Jacobian and line-search batches — under a committed policy
(default ``agents/trained/gnsfo_CompensatorGains-v0_s0.npz``), the copies stepped on all numba threads
(``parallel=True``, as ``--parallel`` trains). Prints the wall time of each rollout after a warm-up one, the env-steps
per second, and a checksum of the fish heave (equal checksums = the same trajectories, e.g. across two commits).

    python scripts/bench_training_rollout.py                      # 264 copies, 2 timed rollouts, ~1.5 minutes
    python scripts/bench_training_rollout.py --copies 744 --repeats 1

To compare two versions, run it alternately from each checkout (e.g. ``PYTHONPATH=<other checkout>``).
"""
from __future__ import annotations

import argparse
import statistics
import time
from pathlib import Path

import numpy as np

DEFAULT_POLICY = Path(__file__).resolve().parents[1] / "agents" / "trained" / "gnsfo_CompensatorGains-v0_s0.npz"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--copies", type=int, default=264, help="copies in the batch (default 264)")
    ap.add_argument("--repeats", type=int, default=2, help="timed rollouts after the warm-up one (default 2)")
    ap.add_argument("--policy", default=str(DEFAULT_POLICY), help="CompensatorGains ARS / Gauss-Newton policy file")
    ap.add_argument("--serial", action="store_true", help="step the copies on one thread")
    a = ap.parse_args(argv)
    for name, v in (("--copies", a.copies), ("--repeats", a.repeats)):
        if v < 1:
            ap.error(f"{name} must be at least 1 (got {v})")
    import towenv  # noqa: F401
    from agents import ars_compensator as arc
    from agents.common import nearest_key
    from agents.gn_compensator import train_seed, training_entries
    from towenv.envs.vector import CompensatorGainsVectorEnv
    try:
        pol = arc.load_policy(a.policy)
    except (OSError, ValueError) as exc:
        ap.error(f"--policy {a.policy}: {exc}")
    n = a.copies
    venv = CompensatorGainsVectorEnv(num_envs=n, autoreset_mode="NextStep", batch_infos=True, episode_seconds=180.0,
                                     parallel=not a.serial)
    batch = arc._Batch(venv, pol.base_table, pol.scales, pol.feature_set, pol.predictor)
    ev, idx, _keys = training_entries(arc.ENV_ID, pol.base_table, None)
    ents = [(ev[i][0], ev[i][1]) for i in idx]
    seas = [ents[j % len(ents)][0] for j in range(n)]
    theta = np.array([pol.theta[nearest_key(pol.theta, s)] for s in seas])
    walls, check = [], 0.0
    print(f"# training rollout: {n} copies of CompensatorGains-v0, 180 s episodes, {pol.name} "
          f"({pol.feature_set}), {'one thread' if a.serial else 'all numba threads'}", flush=True)
    for r in range(a.repeats + 1):
        seeds = [train_seed(ents[j % len(ents)][1], r, 5) for j in range(n)]
        t0 = time.perf_counter()
        H, *_ = arc.rollout_series(venv, batch, seas, seeds, theta)
        w = time.perf_counter() - t0
        check = float(np.nansum(H))
        print(f"rollout {r}{' (warm-up)' if r == 0 else ''}: {w:.2f} s wall, checksum {check!r}", flush=True)
        if r:
            walls.append(w)
    med = statistics.median(walls)
    steps = venv.envs[0].max_steps
    print(f"median {med:.2f} s per rollout, {n * steps / med:,.0f} env-steps/s")
    venv.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
