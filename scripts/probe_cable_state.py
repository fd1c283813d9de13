"""How much of the fish heave does a linear map from the sensors' recent history explain, under skyhook?

Probe behind feature set ``hst`` (agents/ars_compensator.py, docs/agents.md): for each sea state of
``towenv/CompensatorGains-v0``, the skyhook baseline runs the four evaluation (sea state, heading) entries with probe
wave seeds (base seed + 75500: never an evaluation, tuning, training or final seed) for 240 s; the fish heave about its
running mean (``fish_heave_dev``) over t ≥ 60 s is fitted by ridge least squares on 10 s (100 control steps) of the
history of a channel set, and scored by leave-one-episode-out R² (mean over the four folds)::

    python scripts/probe_cable_state.py          # ~1 min on one core

Channel sets: the tow point's vertical velocity (what feature set ``h`` sees of the excitation), + the velocity along
the top cable, + the top tension. A fit, not a controller: it says what the channels carry about the fish's state.
"""
from __future__ import annotations

import argparse

import numpy as np

SETS = (("vert", ("tow_vel_z",)), ("along", ("tow_vel_along",)), ("vert+along", ("tow_vel_z", "tow_vel_along")),
        ("vert+along+tension", ("tow_vel_z", "tow_vel_along", "top_tension")))
CHANNELS = ("tow_vel_z", "tow_vel_along", "top_tension", "fish_heave_dev")
SEED_OFFSET = 75500


def record(seconds: float = 240.0):
    """{code: [episode arrays {channel: (T,)}]} under skyhook, four entries per sea state."""
    import gymnasium as gym

    import towenv  # noqa: F401
    from agents.baselines import make_baseline
    from agents.common import ObsReader
    env = gym.make("towenv/CompensatorGains-v0", episode_seconds=float(seconds))
    reader, base = ObsReader(env), make_baseline("skyhook", env)
    out: dict[int, list] = {}
    for sea, seed in env.unwrapped.eval_sea_states():
        obs, _ = env.reset(options={"sea_state": sea, "sea_seed": int(seed) + SEED_OFFSET})
        base.reset()
        rows = []
        for _ in range(env.unwrapped.max_steps):
            rows.append([float(np.ravel(reader(obs, c))[0]) for c in CHANNELS])
            obs, *_ = env.step(base.act(obs))
        a = np.array(rows)
        out.setdefault(int(seed) // 1000, []).append({c: a[:, i] for i, c in enumerate(CHANNELS)})
    env.close()
    return out


def loo_r2(episodes, channels, lags: int = 100, start: int = 600, ridge: float = 1e-3) -> float:
    """Leave-one-episode-out R² of fish_heave_dev[t] on channels[t − lags + 1 … t], t ≥ ``start`` steps."""
    def lagged(x):
        return np.stack([x[lags - 1 - k:len(x) - k] for k in range(lags)], axis=1)
    X = [np.concatenate([lagged(e[c]) for c in channels], axis=1)[start - lags + 1:] for e in episodes]
    y = [e["fish_heave_dev"][start:] for e in episodes]
    r2 = []
    for k in range(len(episodes)):
        A = np.concatenate([np.c_[X[j], np.ones(len(X[j]))] for j in range(len(X)) if j != k])
        b = np.concatenate([y[j] for j in range(len(y)) if j != k])
        w = np.linalg.solve(A.T @ A + ridge * np.eye(A.shape[1]), A.T @ b)
        p = np.c_[X[k], np.ones(len(X[k]))] @ w
        r2.append(1.0 - np.var(y[k] - p) / np.var(y[k]))
    return float(np.mean(r2))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=240.0, help="episode length (s; scored from 60 s)")
    a = ap.parse_args(argv)
    if not a.seconds >= 120.0:
        ap.error(f"--seconds must be >= 120 (got {a.seconds})")
    data = record(a.seconds)
    print("leave-one-episode-out R² of the fish heave (about its running mean) on 10 s of history, under skyhook:")
    for code, eps in sorted(data.items()):
        print(f"  code {code}: " + ", ".join(f"{name} {loo_r2(eps, ch):.3f}" for name, ch in SETS))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
