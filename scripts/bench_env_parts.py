"""Benchmark (issue 15): three per-step costs around the environments' compiled physics, in µs of CPU, timed
in isolation (best of 3 × N calls) — the figures the README quotes for this release's cuts. It uses only
interfaces that the previous release also has, so the same command against an older checkout gives the
"before" figures (``PYTHONPATH=<old checkout> python scripts/bench_env_parts.py``):

* the batch kernel's call with no copy stepped (``nsteps = -1``: argument handling only), through numba's
  dispatcher, and through the compiled entry point the stepper now uses (where the stepper has one);
* one tow-point refill: ``TowPointBuffer.block`` of one aligned 128-step block with its mean track;
* the batched vector env's per-step ``info`` (``TowVectorEnv._batched_infos``) at N = 1.

    python scripts/bench_env_parts.py
"""
from __future__ import annotations

import time

import numpy as np


def _best(f, n, repeats=3):
    best = float("inf")
    for _ in range(repeats):
        c0 = time.process_time()
        for _ in range(n):
            f()
        best = min(best, (time.process_time() - c0) / n * 1e6)
    return best


def main():
    import gymnasium as gym
    import towenv
    import towenv.envs  # noqa: F401
    from towenv.core.tow_point import BLOCK, TowPointBuffer
    from towenv.envs import stepper as ST

    print(f"# towenv {towenv.__file__}")
    env = gym.make("towenv/WinchPayout-v0").unwrapped
    env.reset(seed=0)
    for _ in range(5):
        env.step(np.zeros(1))
    st = env._rows.stepper
    items, gathers = st._lists()
    ns = np.full(st.num_copies, -1, np.int64)
    args = (items, gathers, ns, 1, st._dt, st._blk, st._mblk, st._base, st._end, st._count, env.ACT_KIND, st.U,
            st.refs, st._res, st.M)
    kern = ST._step_batch
    print(f"batch kernel call, no copy stepped, dispatcher: {_best(lambda: kern(*args), 20000):.2f} µs")
    entry = getattr(ST, "_entry_point", None)
    if entry is not None:
        ep = entry(kern, args, items, gathers)[3]
        print(f"batch kernel call, no copy stepped, entry point: {_best(lambda: ep(*args), 20000):.2f} µs")
    tp = TowPointBuffer(env.sim)
    k = iter(range(10 ** 6))
    print(f"tow-point refill, one {BLOCK}-step block with its mean track: "
          f"{_best(lambda: tp.block(next(k) * BLOCK, BLOCK, mean=True), 200):.0f} µs")
    venv = gym.make_vec("towenv/WinchPayout-v0", num_envs=1, vectorization_mode="vector_entry_point")
    venv.reset(seed=0)
    res, idx, _, _ = venv._step_arrays(np.zeros((1, 1), np.float32))
    print(f"batched env info at N = 1: {_best(lambda: venv._batched_infos(res, idx), 5000):.1f} µs")


if __name__ == "__main__":
    main()
