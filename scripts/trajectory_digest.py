"""Bit-for-bit comparison of two checkouts (or two builds) of the kernels: record, then compare.

Records, in this process, the final Houbolt state of ten embedded scenes (positions of the last three time
levels, body angles, tensions, tow-point reaction, solver counters) and the observations and rewards of
1500 random-action steps of each environment, into one ``.npz``. A change meant to leave the arithmetic alone
(a refactor, a compiler setting) must give the same file on the same machine:

    PYTHONPATH=../base python scripts/trajectory_digest.py /tmp/base.npz     # the checkout before the change
    python scripts/trajectory_digest.py /tmp/new.npz
    python scripts/trajectory_digest.py --compare /tmp/base.npz /tmp/new.npz   # exit 1 if any array differs

(numba compiles for the host CPU: files from different machines may differ in the last bits.)

``--solver KEY=VALUE`` (repeatable) sets a solver setting for every scene and environment (``make_simulator``'s
keywords, the environments' ``sim_overrides``), e.g. the settings a change added, at the values that reproduce the
code before it — the adaptive predictor and the reused body derivatives of 2026-12-06 against 314f390:

    PYTHONPATH=../314f390 python scripts/trajectory_digest.py /tmp/base.npz
    python scripts/trajectory_digest.py /tmp/new.npz --solver predictor=quadratic --solver body_derivative_refresh=1

(and ``--solver cable_jacobian_refresh=1`` for the reused node Newton matrices, also of 2026-12-06, against 98772f2;
with all three the head reproduces 314f390).
"""
from __future__ import annotations

import argparse
import ast
import sys

import numpy as np

#: (scene, Δt or None for the scene's own, simulated seconds)
SCENES = (("two_part_tow_1", 0.05, 60.0), ("two_part_coastal_ss4", 0.05, 120.0), ("ablow_turn_1km", 0.1, 60.0),
          ("series_multitow", 0.05, 30.0), ("parallel_multitow", 0.05, 30.0), ("hover_deep_tow", None, 60.0),
          ("srivastava_towed_array", None, 20.0), ("two_part_turn", None, 60.0), ("conventional_tow", 0.1, 60.0),
          ("two_part_tow_2", None, 60.0))
ENVS = ("towenv/WinchPayout-v0", "towenv/CompensatorGains-v0")
ENV_STEPS = 1500


def record(path, solver=None):
    import towenv
    solver = dict(solver or {})
    out = {}
    for scene, dt, seconds in SCENES:
        sim = towenv.make_simulator(scene, dt=dt, **solver) if dt else towenv.make_simulator(scene, **solver)
        sim.advance(seconds)
        for key in ("hist_r", "hist_ang", "tens_hist", "top_react", "counters"):
            out[f"{scene}::{key}"] = np.array(getattr(sim, key))
        print(f"{scene}: {sim.stats['steps']} steps", flush=True)
    import gymnasium as gym
    import towenv.envs  # noqa: F401  (registers the ids)
    for env_id in ENVS:
        env = gym.make(env_id, **({"sim_overrides": solver} if solver else {})).unwrapped
        rng = np.random.default_rng(3)
        obs, _ = env.reset(seed=7)
        observations, rewards = [obs], []
        for k in range(ENV_STEPS):
            obs, reward, terminated, truncated, _ = env.step(rng.uniform(-1.0, 1.0, env.action_space.shape))
            observations.append(obs)
            rewards.append(reward)
            if terminated or truncated:
                obs, _ = env.reset(seed=k)
                observations.append(obs)
        out[f"{env_id}::obs"] = np.array(observations)
        out[f"{env_id}::rewards"] = np.array(rewards)
        print(f"{env_id}: {ENV_STEPS} steps", flush=True)
    from towenv.atomic import atomic_savez
    path = atomic_savez(path, out)
    print(f"wrote {path} ({len(out)} arrays)")


def compare(a_path, b_path) -> int:
    a, b = np.load(a_path), np.load(b_path)
    keys = sorted(set(a.files) | set(b.files))
    differ = 0
    for k in keys:
        if k not in a.files or k not in b.files:
            print(f"only in one file: {k}")
            differ += 1
        elif a[k].shape != b[k].shape:
            print(f"{k}: shapes {a[k].shape} and {b[k].shape}")
            differ += 1
        elif not np.array_equal(a[k], b[k]):
            print(f"{k}: largest difference {np.max(np.abs(a[k] - b[k])):.3g}")
            differ += 1
    print(f"{len(keys)} arrays compared, {differ} differ" + (" (bit for bit identical)" if not differ else ""))
    return 1 if differ else 0


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("out", nargs="?", help="the .npz to write")
    ap.add_argument("--compare", nargs=2, metavar=("A", "B"), help="compare two recorded files instead")
    ap.add_argument("--solver", action="append", default=[], metavar="KEY=VALUE",
                    help="a solver setting for every run (repeatable), e.g. body_derivative_refresh=1")
    a = ap.parse_args(argv)
    solver = {}
    for item in a.solver:
        key, sep, value = item.partition("=")
        if not sep or not key:
            ap.error(f"--solver: expected KEY=VALUE (got {item!r})")
        try:
            solver[key] = ast.literal_eval(value)
        except (ValueError, SyntaxError):
            solver[key] = value                     # a bare word: a string setting (predictor=quadratic)
    if a.compare:
        return compare(*a.compare)
    if not a.out:
        ap.error("give the .npz to write, or --compare A B")
    record(a.out, solver)
    return 0


if __name__ == "__main__":
    sys.exit(main())
