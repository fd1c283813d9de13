"""Benchmark (issue 15): a single environment step under a classical baseline's actions against random actions,
each as a multiple of a Gymnasium ``Pendulum-v1`` step in alternating runs, with the Newton iterations per physics
step of each.

``scripts/bench_env.py`` steps with random actions — a new, unrelated command every 0.1 s — which cost the solver
3.5–3.6 Newton iterations per physics step against ~2.5 under a fixed command (its "physics under the episode's
commands" bound). A controller's actions are smoother. Here each environment first runs one episode of evaluation
sea 4 under its classical baseline (``skyhook`` for CompensatorGains-v0, ``along_cable`` for WinchPayout-v0; the
policy is not timed), its actions are recorded, and that sequence is replayed (the same trajectory, bit for bit)
alternating with the same number of random actions and of Pendulum-v1 steps; the per-pair CPU-time ratios are
reported as median (min–max).

    python scripts/bench_env_actions.py                 # ~1 minute
    python scripts/bench_env_actions.py --steps 1000 --pairs 5
"""
from __future__ import annotations

import argparse
import os
import statistics
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

BASELINES = {"towenv/CompensatorGains-v0": "skyhook", "towenv/WinchPayout-v0": "along_cable"}


def baseline_actions(made, name, steps):
    """The actions of baseline ``name`` over (at most) ``steps`` steps of evaluation sea 4, as one array."""
    from agents.baselines import make_baseline
    env = made.unwrapped
    b = make_baseline(name, made)
    obs, _ = env.reset(seed=0, options={"eval_index": 4})
    acts = []
    for i in range(steps):
        a, _ = b.predict(obs, episode_start=np.array([i == 0]))
        acts.append(np.asarray(a, np.float32).reshape(env.action_space.shape))
        obs, _, term, trunc, _ = env.step(acts[-1])
        if term or trunc:
            break
    return np.array(acts)


def cpu_per_step(env, acts, **reset):
    env.reset(seed=0, **reset)
    c0 = time.process_time()
    for a in acts:
        env.step(a)
    return (time.process_time() - c0) / len(acts)


def iterations(env, acts):
    """Newton iterations per physics step of one replay of ``acts``."""
    from towenv.core import layout as L
    env.reset(seed=0, options={"eval_index": 4})
    for a in acts:
        env.step(a)
    c = env.sim.kernel_data().counters
    return float(c[L.N_ITERATIONS]) / max(float(c[L.N_STEPS]), 1.0)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--steps", type=int, default=2000, help="control steps per run (default 2000)")
    ap.add_argument("--pairs", type=int, default=8, help="alternating rounds (default 8)")
    a = ap.parse_args(argv)
    if a.steps < 1 or a.pairs < 1:
        ap.error(f"--steps and --pairs must be ≥ 1 (got --steps {a.steps}, --pairs {a.pairs})")
    import gymnasium as gym
    import numba
    import towenv.envs  # noqa: F401  (registers the ids)
    numba.set_num_threads(1)
    pend = gym.make("Pendulum-v1").unwrapped
    print(f"# env step under a baseline's actions vs random actions, multiples of a Pendulum-v1 step in {a.pairs} "
          f"alternating rounds (CPU time; median, min–max); load average at start {os.getloadavg()[0]:.2f}\n")
    print("| environment | baseline (steps) | baseline's actions | random actions | Newton iterations per physics step "
          "(baseline / random) | µs per step (baseline / random / Pendulum-v1) |")
    print("|---|---|---|---|---|---|")
    for env_id, name in BASELINES.items():
        made = gym.make(env_id)
        env = made.unwrapped
        acts_b = baseline_actions(made, name, a.steps)
        n = len(acts_b)
        acts_r = np.random.default_rng(0).uniform(-1, 1, (n,) + env.action_space.shape).astype(np.float32)
        pacts = np.random.default_rng(0).uniform(-2, 2, (n, 1)).astype(np.float32)
        cpu_per_step(env, acts_b, options={"eval_index": 4})            # warm-up
        rb, rr, tb, tr, tp = [], [], [], [], []
        for _ in range(a.pairs):
            tp.append(cpu_per_step(pend, pacts))
            tb.append(cpu_per_step(env, acts_b, options={"eval_index": 4}))
            tr.append(cpu_per_step(env, acts_r, options={"eval_index": 4}))
            rb.append(tb[-1] / tp[-1])
            rr.append(tr[-1] / tp[-1])
        med = statistics.median
        print(f"| {env_id} | `{name}` ({n}) | {med(rb):.2f}× ({min(rb):.2f}–{max(rb):.2f}) | {med(rr):.2f}× "
              f"({min(rr):.2f}–{max(rr):.2f}) | {iterations(env, acts_b):.2f} / {iterations(env, acts_r):.2f} | "
              f"{1e6 * med(tb):.1f} / {1e6 * med(tr):.1f} / {1e6 * med(tp):.1f} |")
        made.close()


if __name__ == "__main__":
    main()
