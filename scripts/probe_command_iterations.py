"""Probe (issue 15): Newton iterations per physics step of an environment under different command signals — where
the physics' extra cost under random actions comes from (docs/environments.md "Where random actions' extra
iterations come from").

Each signal drives one episode of ``--steps`` control steps from the same reset (wave seed ``--seed``); the
simulator's own counters give the mean Newton iterations per physics step. Signals: zero, a constant command, a
constant small payout / gain, uniform random commands every control step (what ``scripts/bench_env.py`` steps with),
the same held for 2 and 5 control steps, an AR(1)-smoothed random command, and small random commands (±0.1).

    python scripts/probe_command_iterations.py                          # both environments, ~1 minute
    python scripts/probe_command_iterations.py --env WinchPayout --sim-overrides "{'cable_jacobian_refresh': 1}"
"""
from __future__ import annotations

import argparse
import ast

import numpy as np

ENVS = {"WinchPayout": "towenv/WinchPayout-v0", "CompensatorGains": "towenv/CompensatorGains-v0"}


def signals(n: int, dim: int, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """The command signals, each (n, dim) in [-1, 1]."""
    a = rng.uniform(-1.0, 1.0, (n, dim))
    smooth = np.zeros_like(a)
    for i in range(1, n):
        smooth[i] = 0.8 * smooth[i - 1] + 0.6 * a[i]
    return {"zero": np.zeros((n, dim)),
            "constant +0.05": np.full((n, dim), 0.05),
            "constant -0.05": np.full((n, dim), -0.05),
            "random every step": rng.uniform(-1.0, 1.0, (n, dim)),
            "random held 2 steps": np.repeat(rng.uniform(-1.0, 1.0, (-(-n // 2), dim)), 2, axis=0)[:n],
            "random held 5 steps": np.repeat(rng.uniform(-1.0, 1.0, (-(-n // 5), dim)), 5, axis=0)[:n],
            "AR(1) 0.8 smoothed random": np.clip(smooth, -1.0, 1.0),
            "small random (±0.1)": 0.1 * rng.uniform(-1.0, 1.0, (n, dim))}


def iterations_per_step(env, actions: np.ndarray, seed: int) -> tuple[float, int]:
    """(mean Newton iterations per physics step, control steps run) of one episode under ``actions``."""
    u = env.unwrapped
    env.reset(seed=seed)
    s0 = u.sim.stats
    n = 0
    for a in actions:
        _, _, terminated, truncated, _ = env.step(a.astype(np.float32))
        n += 1
        if terminated or truncated:
            break
    s1 = u.sim.stats
    return (s1["iterations"] - s0["iterations"]) / max(s1["steps"] - s0["steps"], 1), n


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--env", choices=sorted(ENVS) + ["both"], default="both")
    ap.add_argument("--steps", type=int, default=1000, help="control steps per signal (default 1000)")
    ap.add_argument("--seed", type=int, default=11, help="reset seed of every episode (default 11)")
    ap.add_argument("--sim-overrides", default="{}", help="solver settings for the environments' simulators, a Python "
                                                          "dict literal (e.g. \"{'cable_jacobian_refresh': 1}\")")
    a = ap.parse_args(argv)
    if a.steps < 1:
        ap.error(f"--steps must be at least 1 (got {a.steps})")
    try:
        overrides = ast.literal_eval(a.sim_overrides)
        if not isinstance(overrides, dict):
            raise ValueError("not a dict")
    except (ValueError, SyntaxError) as exc:
        ap.error(f"--sim-overrides must be a Python dict literal (got {a.sim_overrides!r}: {exc})")
    import gymnasium as gym
    import towenv.envs  # noqa: F401  (registers the ids)
    names = sorted(ENVS) if a.env == "both" else [a.env]
    print(f"# Newton iterations per physics step, {a.steps} control steps per signal, reset seed {a.seed}, "
          f"sim_overrides {overrides}")
    for name in names:
        env = gym.make(ENVS[name], sim_overrides=overrides)
        dim = env.action_space.shape[0]
        for label, actions in signals(a.steps, dim, np.random.default_rng(5)).items():
            its, n = iterations_per_step(env, actions, a.seed)
            print(f"{name:17s} {label:27s} {its:6.3f} iterations per physics step ({n} control steps)", flush=True)
        env.close()
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
