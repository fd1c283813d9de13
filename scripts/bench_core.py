"""Benchmark: CPU per step of the simulator core and of one environment step, for comparing two checkouts.

Times, in this process after a warm-up (process CPU, median of ``--repeats``): ``advance`` of
two_part_tow_1 (Δt 0.05 s, 120 s), ablow_turn_1km (Δt 0.1 s, 300 s) and two_part_coastal_ss4 (Δt 0.05 s,
60 s) in µs per step, and 1000 steps of ``towenv/WinchPayout-v0`` (zero action) in µs per step. It uses the
public API only, so it runs against any checkout: put the checkout first on the path and alternate, e.g. to
compare this tree with a previous release checked out in ../base (issue 16's "no speed loss" check):

    for i in 1 2 3 4; do python scripts/bench_core.py; PYTHONPATH=../base python scripts/bench_core.py; done

Each run prints one JSON line (``src`` says which towenv it timed); take the ratio pair by pair.
"""
from __future__ import annotations

import argparse
import json
import statistics
import time

import numpy as np


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    a = ap.parse_args(argv)
    import towenv
    out = {"src": towenv.__file__}
    for scene, dt, dur in (("two_part_tow_1", 0.05, 120.0), ("ablow_turn_1km", 0.1, 300.0),
                           ("two_part_coastal_ss4", 0.05, 60.0)):
        sim = towenv.make_simulator(scene, dt=dt)
        sim.advance(1.0)
        cpu = []
        for _ in range(a.repeats):
            sim.reset()
            t0 = time.process_time()
            sim.advance(dur)
            cpu.append(time.process_time() - t0)
        out[scene] = statistics.median(cpu) / (dur / dt) * 1e6
    import gymnasium as gym
    import towenv.envs  # noqa: F401  (registers the ids)
    env = gym.make("towenv/WinchPayout-v0")
    env.reset(seed=1)
    act = np.zeros(env.action_space.shape, np.float32)
    for _ in range(50):
        env.step(act)
    cpu = []
    for _ in range(a.repeats):
        env.reset(seed=2)
        t0 = time.process_time()
        for _ in range(1000):
            _, _, term, trunc, _ = env.step(act)
            if term or trunc:
                env.reset(seed=3)
        cpu.append(time.process_time() - t0)
    out["WinchPayout-v0 step"] = statistics.median(cpu) / 1000 * 1e6
    print(json.dumps(out))


if __name__ == "__main__":
    main()
