"""Benchmark of the Gymnasium environments (towenv.envs): steps/s, reset time, vector-env throughput.

One process, one core (numba kernels warmed up first; SB3/torch imported only for the last comparison). For each
environment id at the default 10 Hz control / 0.05 s physics step (2 sub-steps per control step):

* env steps/s, unwrapped env and ``gym.make`` (with Gymnasium's checker/order wrappers), random actions
  drawn in advance, in a coastal SS4 evaluation sea — median of ``--repeats`` runs of ``--steps`` steps;
* the simulator alone (``Simulator.advance_steps(2)`` per control step, the same sea), for the overhead;
* reset time (µs): ``env.reset()`` (new sea: ``Simulator.set_sea`` + ``reset``) and ``Simulator.reset()``;
* vector env: ``--num-envs`` copies in the ``vector_entry_point`` env, and SB3 ``DummyVecEnv`` (via
  ``make_vec_env``) for comparison — total env-steps/s, ``--vector-steps`` steps of every copy per run.

Runs are long enough to amortise the per-episode costs the way real episodes do: a reset (new sea)
costs ~0.3 ms, and the simulator evaluates the vessel motion in blocks of 2048 physics steps (~100 s).

    python scripts/bench_env.py                  # about a minute
    python scripts/bench_env.py --steps 1000 --repeats 3
"""
from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

# one core: keep BLAS/OpenMP/numba to a single thread (OpenBLAS would otherwise spin a second thread in
# the vessel-motion matrix products, which doubles the CPU time without helping)
for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402


def _median_rate(fn, n, repeats):
    """(median, min, max) of n / time over ``repeats`` runs, by process CPU time (robust to other load
    on a shared machine), plus the median by wall-clock time."""
    cpu, wall = [], []
    for _ in range(repeats):
        c0, w0 = time.process_time(), time.perf_counter()
        fn()
        cpu.append(n / (time.process_time() - c0))
        wall.append(n / (time.perf_counter() - w0))
    return statistics.median(cpu), min(cpu), max(cpu), statistics.median(wall)


def bench_single(env_id, steps, repeats):
    import gymnasium as gym
    made = gym.make(env_id)
    env = made.unwrapped
    acts = np.random.default_rng(0).uniform(-1, 1, (steps,) + env.action_space.shape).astype(np.float32)

    def run(e):
        def f():
            e.reset(seed=0, options={"eval_index": 4})           # coastal SS4, head seas, fixed seed
            for a in acts:
                e.step(a)
        return f

    run(env)()                                                     # warm-up (numba, caches)
    out = {"unwrapped": _median_rate(run(env), steps, repeats), "gym.make": _median_rate(run(made), steps, repeats)}
    sim = env.sim

    def sim_only():
        env.reset(seed=0, options={"eval_index": 4})
        for _ in range(steps):
            sim.advance_steps(env.substeps)
    out["simulator only"] = _median_rate(sim_only, steps, repeats)
    # reset times
    n = 200
    ts = []
    for i in range(n):
        t0 = time.process_time()
        env.reset(seed=i)
        ts.append(time.process_time() - t0)
    out["reset_env_us"] = statistics.median(ts) * 1e6
    ts = []
    for i in range(n):
        env.sim.advance_steps(1)
        t0 = time.perf_counter()
        env.sim.reset()
        ts.append(time.perf_counter() - t0)
    out["reset_sim_us"] = statistics.median(ts) * 1e6
    made.close()
    return out


def bench_vector(env_id, num_envs, steps, repeats):
    import gymnasium as gym
    venv = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
    acts = np.random.default_rng(0).uniform(-1, 1, (steps,) + venv.action_space.shape).astype(np.float32)

    def f():
        venv.reset(seed=0)
        for a in acts:
            venv.step(a)
    f()
    res = {"vector_entry_point": _median_rate(f, steps * num_envs, repeats)}
    venv.close()
    try:
        from stable_baselines3.common.env_util import make_vec_env
    except ImportError:
        return res
    ve = make_vec_env(env_id, n_envs=num_envs, seed=0)

    def g():
        ve.reset()
        for a in acts:
            ve.step(a)
    g()
    res["SB3 DummyVecEnv"] = _median_rate(g, steps * num_envs, repeats)
    ve.close()
    return res


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--steps", type=int, default=2000, help="control steps per run (default 2000 = 200 s)")
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--num-envs", type=int, default=8)
    ap.add_argument("--vector-steps", type=int, default=1000,
                    help="vector steps per run (each copy steps this many times; default 1000)")
    args = ap.parse_args(argv)
    import towenv.envs
    print(f"# towenv environment benchmark — {platform.processor() or platform.machine()}, "
          f"{os.cpu_count()} cores, Python {platform.python_version()}, one process")
    print(f"# 10 Hz control, dt = 0.05 s (2 physics sub-steps), {args.steps} steps per run, median of "
          f"{args.repeats} runs by process CPU time (min–max, and the wall-clock median, in brackets); "
          f"load average at start {os.getloadavg()[0]:.2f}\n")
    rows = []
    for env_id in towenv.envs.ENV_IDS:
        s = bench_single(env_id, args.steps, args.repeats)
        v = bench_vector(env_id, args.num_envs, args.vector_steps, args.repeats)
        rows.append((env_id, s, v))
    fmt = lambda r: f"{r[0]:,.0f} ({r[1]:,.0f}–{r[2]:,.0f}; wall {r[3]:,.0f})"   # noqa: E731
    print("| environment | env steps/s (unwrapped) | env steps/s (gym.make) | simulator only | "
          "reset env (µs) | Simulator.reset (µs) |")
    print("|---|---|---|---|---|---|")
    for env_id, s, _ in rows:
        print(f"| {env_id} | {fmt(s['unwrapped'])} | {fmt(s['gym.make'])} | {fmt(s['simulator only'])} | "
              f"{s['reset_env_us']:,.0f} | {s['reset_sim_us']:.1f} |")
    print(f"\n| environment | vector env ×{args.num_envs} (env-steps/s) | SB3 DummyVecEnv ×{args.num_envs} |")
    print("|---|---|---|")
    for env_id, _, v in rows:
        sb3 = fmt(v["SB3 DummyVecEnv"]) if "SB3 DummyVecEnv" in v else "n/a"
        print(f"| {env_id} | {fmt(v['vector_entry_point'])} | {sb3} |")


if __name__ == "__main__":
    main()
