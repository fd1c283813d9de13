#!/usr/bin/env python
"""Soak test (the long version of the smoke tests): run the towenv environments for a long time.

Steps one or both environments with random actions (or a baseline controller) through many episodes in
random sea states (the environments' own training distribution), and checks that

* every observation and reward is finite and inside the observation space;
* episodes end only by truncation, termination (cable parted, fish below the floor) or a flagged
  solver failure (``info["solver_failure"]``), and those are counted;
* the process memory does not grow without bound (RSS at the start and end, and its growth);
* throughput (env steps/s) stays steady (first vs last quarter).

Writes a JSON summary (``--out``) and exits 1 on a non-finite value or an out-of-space observation.

    python scripts/soak_env.py --minutes 30                       # both envs, random actions
    python scripts/soak_env.py --env towenv/WinchPayout-v0 --policy pd_ff --minutes 10
    python scripts/soak_env.py --minutes 0.2 --episode-seconds 20 # a quick look
"""
from __future__ import annotations

import argparse
import json
import math
import os
import resource
import sys
import time
from pathlib import Path

# one thread per process (set before numpy/numba load their pools). Loaded into a process that has already loaded
# numba (a test), NUMBA_NUM_THREADS is left alone: numba re-reads its configuration at every compilation and refuses
# a thread count that differs from the pool it launched (agents/train.py does the same)
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    if _v != "NUMBA_NUM_THREADS" or "numba" not in sys.modules:
        os.environ.setdefault(_v, "1")



def _rss_mb() -> float:
    try:
        with open("/proc/self/status") as f:
            for ln in f:
                if ln.startswith("VmRSS:"):
                    return float(ln.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def soak(env_id: str, seconds: float, policy: str, seed: int, episode_seconds: float | None, action_hold: int):
    import gymnasium as gym
    import numpy as np
    import towenv.envs  # noqa: F401
    kw = {} if episode_seconds is None else {"episode_seconds": episode_seconds}
    env = gym.make(env_id, **kw)
    space = env.observation_space
    rng = np.random.default_rng(seed)
    pol = None
    if policy != "random":
        from agents.baselines import make_baseline
        pol = make_baseline(policy, env)
    stats = {"env_id": env_id, "policy": policy, "episodes": 0, "steps": 0, "terminated": 0, "truncated": 0,
             "solver_failures": 0, "nonfinite": 0, "out_of_space": 0, "end_stop_hits": 0, "slack_steps": 0,
             "terminations": {}, "failures": [], "rss_mb_start": round(_rss_mb(), 1)}
    t0 = time.time()
    quarter = []
    obs, info = env.reset(seed=seed)
    start = True
    a = env.action_space.sample()
    k = 0
    while time.time() - t0 < seconds:
        if pol is not None:
            a, _ = pol.predict(obs, episode_start=np.array([start]))
        elif k % max(1, action_hold) == 0:
            a = rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32)
        start = False
        obs, r, term, trunc, info = env.step(a)
        k += 1
        stats["steps"] += 1
        if not (np.all(np.isfinite(obs)) and math.isfinite(r)):
            stats["nonfinite"] += 1
        elif not space.contains(obs):
            stats["out_of_space"] += 1
        stats["end_stop_hits"] += int(info.get("end_stop_hits", 0))
        stats["slack_steps"] += int(bool(info.get("slack", False)))
        if term or trunc:
            stats["episodes"] += 1
            if term:
                stats["terminated"] += 1
                why = str(info.get("termination", "?")).split(":")[0]
                stats["terminations"][why] = stats["terminations"].get(why, 0) + 1
            else:
                stats["truncated"] += 1
            if info.get("solver_failure"):
                stats["solver_failures"] += 1
                if len(stats["failures"]) < 20:
                    stats["failures"].append(info.get("failure"))
            obs, info = env.reset()
            start = True
        if k % 2000 == 0:
            quarter.append((time.time() - t0, k))
    wall = time.time() - t0
    stats["wall_seconds"] = round(wall, 1)
    stats["steps_per_second"] = round(stats["steps"] / max(wall, 1e-9), 1)
    if len(quarter) >= 8:
        n = len(quarter) // 4
        first = (quarter[n][1] - quarter[0][1]) / max(quarter[n][0] - quarter[0][0], 1e-9)
        last = (quarter[-1][1] - quarter[-1 - n][1]) / max(quarter[-1][0] - quarter[-1 - n][0], 1e-9)
        stats["steps_per_second_first_quarter"] = round(first, 1)
        stats["steps_per_second_last_quarter"] = round(last, 1)
    stats["rss_mb_end"] = round(_rss_mb(), 1)
    stats["rss_growth_mb"] = round(stats["rss_mb_end"] - stats["rss_mb_start"], 1)
    env.close()
    return stats


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("--env", nargs="*", default=["towenv/CompensatorGains-v0", "towenv/WinchPayout-v0"])
    p.add_argument("--minutes", type=float, default=30.0, help="wall-clock minutes per environment")
    p.add_argument("--policy", default="random", help="random, or a baseline name (agents.baselines)")
    p.add_argument("--action-hold", type=int, default=1, help="random action held for N steps")
    p.add_argument("--episode-seconds", type=float, default=None)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--out", default=None, help="JSON summary path")
    args = p.parse_args(argv)
    results = []
    ok = True
    for eid in args.env:
        s = soak(eid, args.minutes * 60.0, args.policy, args.seed, args.episode_seconds, args.action_hold)
        results.append(s)
        print(json.dumps(s, indent=1), flush=True)
        ok = ok and s["nonfinite"] == 0 and s["out_of_space"] == 0
    if args.out:
        Path(args.out).write_text(json.dumps(results, indent=1))
    print("[soak] " + ("OK" if ok else "FAILED: non-finite or out-of-space observations"), flush=True)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
