"""Benchmark (issue 15): the environments' tow-point refill a span of blocks at a time against one block at a time.

``towenv.envs.stepper.BatchStepper`` refills a copy's tow-point buffer ``SPAN_BLOCKS`` aligned 128-step blocks at a
time (``TowPointBuffer.span``: the blocks' exact anchors in one vectorised call, bit for bit the block-by-block
values). Setting ``SPAN_BLOCKS = 1`` restores the previous refill (one block per call). This script builds two
copies of each environment, one per setting, and steps them alternately with the same random actions (process CPU
time; the module's setting is switched before each run), single environments and a batched vector env, and prints
the per-pair ratio new/old as median and interquartile range.

    python scripts/bench_span.py                    # ~3 minutes
    python scripts/bench_span.py --pairs 9 --steps 800 --num-envs 32
"""
from __future__ import annotations

import argparse
import os
import time

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

import numpy as np  # noqa: E402

ENVS = ("towenv/CompensatorGains-v0", "towenv/WinchPayout-v0")


def _set_span(blocks: int) -> None:
    from towenv.envs import stepper as ST
    ST.SPAN_BLOCKS = blocks
    ST.SPAN = blocks * ST.BLOCK


def _make(env_id: str, num_envs: int | None, blocks: int):
    """A single env (``num_envs`` None) or a batched vector env built and reset under ``blocks``."""
    import gymnasium as gym
    import towenv.envs  # noqa: F401  (registers the ids)
    _set_span(blocks)
    if num_envs is None:
        env = gym.make(env_id).unwrapped
    else:
        env = gym.make_vec(env_id, num_envs=num_envs, vectorization_mode="vector_entry_point")
    env.reset(seed=1)
    return env


def _run(env, blocks: int, steps: int, seed: int, batched: bool) -> float:
    """CPU µs per env-step of ``steps`` random steps under ``blocks``."""
    _set_span(blocks)
    rng = np.random.default_rng(seed)
    shape = env.action_space.shape
    acts = rng.uniform(-1.0, 1.0, (steps,) + shape).astype(np.float32)
    n = env.num_envs if batched else 1
    c = time.process_time()
    for a in acts:
        out = env.step(a)
        if not batched and (out[2] or out[3]):
            env.reset()
    return (time.process_time() - c) / steps / n * 1e6


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=21, help="alternating pairs per case (default 21)")
    ap.add_argument("--steps", type=int, default=1500, help="single-env steps per run (default 1500; the batched "
                    "env runs steps / 25 of its steps)")
    ap.add_argument("--num-envs", type=int, default=64, help="copies of the batched env (default 64)")
    ap.add_argument("--blocks", type=int, default=None, help="the span compared with one block (default: the "
                    "stepper's SPAN_BLOCKS)")
    a = ap.parse_args(argv)
    for name, v, lo in (("--pairs", a.pairs, 1), ("--steps", a.steps, 25), ("--num-envs", a.num_envs, 1)):
        if v < lo:
            ap.error(f"{name} must be at least {lo} (got {v})")
    from towenv.envs import stepper as ST
    new = ST.SPAN_BLOCKS if a.blocks is None else a.blocks
    if not 2 <= new <= 64:
        ap.error(f"--blocks must be in 2..64: the span compared with one block (got {new})")
    print(f"# tow-point refill: {new} blocks per refill against 1; {a.pairs} alternating pairs, random actions, "
          f"process CPU time, load average at start {os.getloadavg()[0]:.2f}")
    print("| environment | mode | new / old per env-step: median (IQR) | last pair, µs per env-step (old → new) |")
    print("|---|---|---|---|")
    for env_id in ENVS:
        for batched in (False, True):
            envs = {b: _make(env_id, a.num_envs if batched else None, b) for b in (1, new)}
            steps = max(1, a.steps // 25) if batched else a.steps
            ratios, last = [], None
            for p in range(a.pairs):
                order = (1, new) if p % 2 == 0 else (new, 1)
                t = {b: _run(envs[b], b, steps, p, batched) for b in order}
                ratios.append(t[new] / t[1])
                last = t
            for e in envs.values():
                e.close()
            q1, med, q3 = np.percentile(ratios, [25, 50, 75])
            mode = f"batched N = {a.num_envs}" if batched else "single"
            print(f"| {env_id} | {mode} | {med:.3f} ({q1:.3f}–{q3:.3f}) | {last[1]:.1f} → {last[new]:.1f} |",
                  flush=True)
    _set_span(new)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
