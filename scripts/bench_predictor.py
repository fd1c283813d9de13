"""Benchmark: Newton iterations per Houbolt step with each ``solver.predictor`` (``quadratic``, the predictor before
2026-12-06, and ``adaptive``, the default since), and how far apart the two runs end.

    python scripts/bench_predictor.py [--seconds 60]

Scenes at Δt = 0.05 s for ``--seconds`` each (two_part_tow_1 as shipped and in a coastal SS4 sea, the 1 km turn at
Δt = 0.1 s, the sea scene, the series multi-tow, the Hover deep tow), then both environments for 1500 control
steps under a classical baseline (smooth actions: ``along_cable`` / ``skyhook``) and under uniformly random actions
(a new, unrelated action every 0.1 s), the simulator's ``solver.predictor`` set through ``sim_overrides``. Prints
per case the iterations per step of each predictor, their ratio, and for the scenes the largest differences of the
final node positions, tensions and body angles. Iterations, not time: ``scripts/bench_core.py`` times the steps
(docs/architecture.md "The adaptive Newton predictor" has both).
"""
from __future__ import annotations

import argparse

import numpy as np

SEA = {"sea": {"code": 4, "convention": "coastal", "spectrum": "jonswap", "heading_deg": 165.0, "seed": 13},
       "vessel.model": "coastal_survey", "vessel.excitation": None, "vessel.speed": 3.0}
SCENES = [("two_part_tow_1", {}, 0.05), ("two_part_tow_1 in SS4", SEA, 0.05), ("ablow_turn_1km", {}, 0.1),
          ("two_part_coastal_ss4", {}, 0.05), ("series_multitow", {}, 0.05), ("hover_deep_tow", {}, 0.05)]


ENV_CASES = (("towenv/WinchPayout-v0", "along_cable"), ("towenv/WinchPayout-v0", "random"),
             ("towenv/CompensatorGains-v0", "skyhook"), ("towenv/CompensatorGains-v0", "random"))


def final_state_gap(a, b):
    """"max |dr| (m), |dT| (N), |d angle| (rad)" between two simulators' final time levels, and their step cuts."""
    dang = float(np.max(np.abs(a.hist_ang[0] - b.hist_ang[0]))) if a.hist_ang.shape[1] else 0.0
    return (f"{np.max(np.abs(a.hist_r[0] - b.hist_r[0])):.2g}, {np.max(np.abs(a.tens_hist[0] - b.tens_hist[0])):.2g}, "
            f"{dang:.2g}  (step cuts {a.stats['step_cuts']} / {b.stats['step_cuts']})")


def _scene_run(name, ov, dt, predictor, seconds):
    from towenv.core.simulator import Simulator, load
    sim = Simulator(load(name.split()[0]).with_overrides({**ov, "solver.dt": dt, "solver.predictor": predictor}))
    sim.advance(seconds)
    return sim


def _env_run(env_id, policy, predictor, steps=1500):
    import gymnasium as gym

    import towenv.envs  # noqa: F401  (registers the ids)
    from agents.baselines import make_baseline
    env = gym.make(env_id, sim_overrides={"predictor": predictor})
    obs, _ = env.reset(seed=5)
    u = env.unwrapped
    rng = np.random.default_rng(0)
    pol = None if policy == "random" else make_baseline(policy, env)
    its = n = 0
    start = True
    for _ in range(steps):
        if pol is None:
            a = rng.uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32)
        else:
            a, _ = pol.predict(obs, episode_start=start)
        start = False
        obs, _, term, trunc, _ = env.step(a)
        if term or trunc:
            s = u.sim.stats
            its += s["mean_iterations"] * s["steps"]
            n += s["steps"]
            obs, _ = env.reset()
            start = True
    s = u.sim.stats
    its += s["mean_iterations"] * s["steps"]
    n += s["steps"]
    return its / n


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="simulated time per scene (default 60)")
    ap.add_argument("--no-envs", action="store_true", help="scenes only")
    a = ap.parse_args(argv)
    print(f"{'case':34s} {'quadratic':>10s} {'adaptive':>10s} {'ratio':>6s}   final state: max |dr| (m), |dT| (N), "
          "|d angle| (rad)")
    for name, ov, dt in SCENES:
        q = _scene_run(name, ov, dt, "quadratic", a.seconds)
        p = _scene_run(name, ov, dt, "adaptive", a.seconds)
        iq, ip = q.stats["mean_iterations"], p.stats["mean_iterations"]
        print(f"{name + f' (dt {dt:g} s)':34s} {iq:10.3f} {ip:10.3f} {ip / iq:6.3f}   {final_state_gap(q, p)}")
    if a.no_envs:
        return
    for env_id, policy in ENV_CASES:
        iq = _env_run(env_id, policy, "quadratic")
        ip = _env_run(env_id, policy, "adaptive")
        print(f"{env_id.split('/')[1] + ', ' + policy:34s} {iq:10.3f} {ip:10.3f} {ip / iq:6.3f}")


if __name__ == "__main__":
    main()
