"""Benchmark (issue 15): three per-step costs around the environments' compiled physics, in µs of CPU, timed
in isolation (best of 3 × N calls) — the figures the README quotes for this release's cuts. It uses only
interfaces that the previous release also has, so the same command against an older checkout gives the
"before" figures (``PYTHONPATH=<old checkout> python scripts/bench_env_parts.py``):

* the batch kernel's call with no copy stepped (``nsteps = -1``: argument handling only), through numba's
  dispatcher, and through the compiled entry point the stepper now uses (where the stepper has one);
* one tow-point refill: ``TowPointBuffer.block`` of one aligned 128-step block with its mean track;
* the batched vector env's per-step ``info`` (``TowVectorEnv._batched_infos``) at N = 1.
* the layers of one WinchPayout-v0 env step (zero action), each timed on its own, so that the difference between
  two rows is the Python of that layer: the ``gym.make`` env (Gymnasium's wrappers), ``TowEnv.step``,
  ``base.step_copies`` (action map, observation/reward/flags, result), ``BatchStepper.step`` (the compiled physics
  of one control step with its per-call costs) and the single env's ``StepResult.info``; then ``TowEnv.step`` through
  ``step_copies`` against the prepared path that the standard pieces take since 2026-12-05
  (``TowEnv._step_planned``), alternating runs, both environments. The env and step_copies
  rows include an episode reset every 3000 steps; the step_copies and stepper rows step on past the episode's end
  (the physics does not care).

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
    _layers()


def _layers():
    import gymnasium as gym
    from towenv.envs import base as B
    wrapped = gym.make("towenv/WinchPayout-v0")
    wrapped.reset(seed=0)
    env = wrapped.unwrapped
    a = np.zeros(wrapped.action_space.shape, np.float32)

    def step_wrapped():
        _o, _r, te, tr, _i = wrapped.step(a)
        if te or tr:
            wrapped.reset(seed=1)

    def step_env():
        _o, _r, te, tr, _i = env.step(a)
        if te or tr:
            wrapped.reset(seed=1)

    step_wrapped()
    rows, idx = env._rows, np.array([env._row])
    res = B.step_copies([env], rows, idx)
    st = rows.stepper
    n = 2000
    print("one WinchPayout-v0 step by layer (µs of CPU; the difference between two rows is that layer's Python):")
    for name, f in (("gym.make env (wrappers + TowEnv.step)", step_wrapped), ("TowEnv.step", step_env),
                    ("base.step_copies", lambda: B.step_copies([env], rows, idx)),
                    ("BatchStepper.step (physics + per-call compiled costs)",
                     lambda: st.step(env.substeps, env.ACT_KIND, None)),
                    ("StepResult.info (inside TowEnv.step's general path)", lambda: res.info(0))):
        print(f"  {name}: {_best(f, n):.1f}")
    if hasattr(B, "_StepPlan"):
        _prepared_vs_general()


def _prepared_vs_general(pairs=21, steps=1000):
    """Since 2026-12-05 ``TowEnv.step`` takes a prepared path with the standard pieces (``TowEnv._step_planned``);
    the general path (``step_copies`` + ``StepResult.info``) is what custom pieces take. Both envs, the same
    random actions and episode, alternating runs of ``steps`` steps by process CPU time; median of the per-pair
    ratios (the figure that holds when the host's speed drifts)."""
    import statistics

    import gymnasium as gym
    from towenv.envs import base as B
    print(f"TowEnv.step, prepared path vs the general path ({pairs} alternating pairs of {steps} steps, µs of CPU):")
    for env_id in ("towenv/WinchPayout-v0", "towenv/CompensatorGains-v0"):
        env = gym.make(env_id).unwrapped
        acts = np.random.default_rng(0).uniform(-1, 1, (steps,) + env.action_space.shape).astype(np.float32)

        def run(general):
            env.reset(seed=0, options={"eval_index": 4})
            if general:
                plan = B._StepPlan.__new__(B._StepPlan)
                plan.rows, plan.row, plan.observer, plan.reward_fn = env._rows, env._row, env.observer, env.reward_fn
                plan.limits, plan.fast = env._limits, False
                env._plan = plan
            c0 = time.process_time()
            for a in acts:
                env.step(a)
            return (time.process_time() - c0) / steps * 1e6

        run(False), run(True)                          # warm-up
        fast, slow = [], []
        for k in range(pairs):
            order = (False, True) if k % 2 else (True, False)
            for g in order:
                (slow if g else fast).append(run(g))
        ratios = [f / g for f, g in zip(fast, slow)]
        print(f"  {env_id}: prepared {statistics.median(fast):.1f}, general {statistics.median(slow):.1f}; "
              f"prepared/general median {statistics.median(ratios):.3f} (pairs {min(ratios):.3f}-{max(ratios):.3f})")

if __name__ == "__main__":
    main()
