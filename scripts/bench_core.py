"""Benchmark: time per step of the simulator core and of one environment step, for comparing two checkouts.

Times, in this process after a warm-up: ``advance_steps`` of two_part_tow_1 (Δt 0.05 s), ablow_turn_1km
(Δt 0.1 s) and two_part_coastal_ss4 (Δt 0.05 s) in µs per step, and ``towenv/WinchPayout-v0`` steps (zero
action) in µs per step. This host alternates between a fast and a slow state lasting ~0.1–3 s (single
timings spread ±30 %), so each figure is a low percentile (``--percentile``, default 5) of many short chunks
(a few ms each): the fast state's time. It uses the public API only, so it runs against any checkout: put
the checkout first on the path and alternate, or better run both at once on the two cores and swap, e.g.
against a previous release checked out in ../base (issue 16's "no speed loss" check):

    for i in 1 2 3 4; do
      taskset -c 0 python scripts/bench_core.py & PYTHONPATH=../base taskset -c 1 python scripts/bench_core.py; wait
      PYTHONPATH=../base taskset -c 0 python scripts/bench_core.py & taskset -c 1 python scripts/bench_core.py; wait
    done

Each run prints one JSON line (``src`` says which towenv it timed); compare the fastest runs of each checkout
(docs/architecture.md shows the latest table).
"""
from __future__ import annotations

import argparse
import json
import time

import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=5, help="passes over each scene's chunks (default 5)")
    ap.add_argument("--percentile", type=float, default=5.0)
    a = ap.parse_args(argv)
    import towenv
    out = {"src": towenv.__file__}
    for scene, dt, chunk in (("two_part_tow_1", 0.05, 200), ("ablow_turn_1km", 0.1, 100),
                             ("two_part_coastal_ss4", 0.05, 200)):
        sim = towenv.make_simulator(scene, dt=dt)
        sim.advance(1.0)
        per_step = []
        for _ in range(a.repeats):
            sim.reset()
            for _ in range(60):
                t0 = time.perf_counter()
                sim.advance_steps(chunk)
                per_step.append((time.perf_counter() - t0) / chunk * 1e6)
        out[scene] = float(np.percentile(per_step, a.percentile))
    import gymnasium as gym
    import towenv.envs  # noqa: F401  (registers the ids)
    env = gym.make("towenv/WinchPayout-v0")
    env.reset(seed=1)
    act = np.zeros(env.action_space.shape, np.float32)
    for _ in range(50):
        env.step(act)
    per_step = []
    env.reset(seed=2)
    for _ in range(60 * a.repeats):
        t0 = time.perf_counter()
        for _ in range(20):
            _, _, term, trunc, _ = env.step(act)
            if term or trunc:
                env.reset(seed=3)
        per_step.append((time.perf_counter() - t0) / 20 * 1e6)
    out["WinchPayout-v0 step"] = float(np.percentile(per_step, a.percentile))
    print(json.dumps(out))


if __name__ == "__main__":
    main()
