"""Benchmark: reused rigid-body load derivatives (``solver.body_derivative_refresh``) or reused free-node Newton
matrices (``--setting cable_jacobian_refresh``): time and Newton iterations per Houbolt step with the derivatives /
matrices computed every step (1, the kernel before the setting) and every N steps (default 10), and how far apart
the runs end.

    python scripts/bench_body_derivatives.py [--refresh 10 20] [--seconds 60] [--no-envs]
    python scripts/bench_body_derivatives.py --setting cable_jacobian_refresh --refresh 4 10 20

Scenes as in ``scripts/bench_predictor.py`` (two_part_tow_1 as shipped and in a coastal SS4 sea, the 1 km turn at
Δt = 0.1 s, the sea scene, the series multi-tow, the Hover deep tow; Δt = 0.05 s otherwise), then both environments
for 1500 control steps under a classical baseline and under uniformly random actions (``sim_overrides``); with
``--setting cable_jacobian_refresh`` also the MoorDyn cross-check deck (``towenv.peer.decks.shared_deck``: 20
segments, 2 m/s, 1 m heave at 8 s; the speed/accuracy chart's binding point). Time: the
settings of one case alternate in this process, chunk by chunk (``--chunk`` steps of ``advance_steps``, or of
``env.step``), and each figure is the 5th percentile of the chunks' time per step — this host alternates between a
fast and a slow state (docs/architecture.md), so a low percentile of many short chunks is the fast state's time and
the ratio is measured in one run. Prints per case µs per step and iterations per step for each setting and their
ratios to refresh 1, and for the scenes the largest differences of the final node positions, tensions and body
angles against refresh 1.
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from bench_predictor import ENV_CASES, SCENES, final_state_gap  # noqa: E402  (same cases)

SETTINGS = ("body_derivative_refresh", "cable_jacobian_refresh")
DECK = "MoorDyn deck (20 seg)"


def _sim(name, ov, dt, setting, refresh):
    from towenv.core.simulator import Simulator, load
    if name == DECK:
        from towenv.peer.decks import shared_deck
        scene = shared_deck(segments=20)
    else:
        scene = load(name.split()[0])
    return Simulator(scene.with_overrides({**ov, "solver.dt": dt, "solver." + setting: refresh}))


def _scene_case(name, ov, dt, setting, settings, seconds, chunk, passes):
    sims = {n: _sim(name, ov, dt, setting, n) for n in settings}
    steps = int(round(seconds / dt))
    for sim in sims.values():               # compile and warm up
        sim.advance_steps(chunk)
    per = {n: [] for n in settings}
    for p in range(passes):
        for sim in sims.values():
            sim.reset()
        done = 0
        while done < steps:
            # the settings' order alternates from one round of chunks to the next (a chunk that follows another
            # setting's may start with colder caches: measured ~5 % on identical computations in a fixed order)
            order = list(sims.items())
            for n, sim in (order if (done // chunk) % 2 == 0 else order[::-1]):
                t0 = time.perf_counter()
                sim.advance_steps(chunk)
                per[n].append((time.perf_counter() - t0) / chunk * 1e6)
            done += chunk
    return {n: (float(np.percentile(per[n], 5)), sims[n].stats["mean_iterations"], sims[n]) for n in settings}


def _env_case(env_id, policy, setting, settings, steps, chunk):
    import gymnasium as gym

    import towenv.envs  # noqa: F401  (registers the ids)
    from agents.baselines import make_baseline
    envs, pols, obs, starts, rngs = {}, {}, {}, {}, {}
    for n in settings:
        envs[n] = gym.make(env_id, sim_overrides={setting: n})
        obs[n], _ = envs[n].reset(seed=5)
        pols[n] = None if policy == "random" else make_baseline(policy, envs[n])
        starts[n] = True
        rngs[n] = np.random.default_rng(0)
    per = {n: [] for n in settings}
    its = {n: [0.0, 0] for n in settings}

    def tally(n):
        s = envs[n].unwrapped.sim.stats
        its[n][0] += s["mean_iterations"] * s["steps"]
        its[n][1] += s["steps"]

    for k in range(0, steps, chunk):
        for n in (settings if (k // chunk) % 2 == 0 else settings[::-1]):     # alternating order, as above
            env = envs[n]
            t0 = time.perf_counter()
            for _ in range(chunk):
                if pols[n] is None:
                    a = rngs[n].uniform(-1.0, 1.0, env.action_space.shape).astype(np.float32)
                else:
                    a, _ = pols[n].predict(obs[n], episode_start=starts[n])
                starts[n] = False
                obs[n], _, term, trunc, _ = env.step(a)
                if term or trunc:
                    tally(n)
                    obs[n], _ = env.reset()
                    starts[n] = True
            if k > 0:                       # the first chunk warms up
                per[n].append((time.perf_counter() - t0) / chunk * 1e6)
    for n in settings:
        tally(n)
    return {n: (float(np.percentile(per[n], 5)), its[n][0] / max(its[n][1], 1)) for n in settings}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--setting", choices=SETTINGS, default=SETTINGS[0],
                    help="the solver setting compared (default body_derivative_refresh)")
    ap.add_argument("--refresh", type=int, nargs="+", default=[10], help="refresh intervals against 1 (default 10)")
    ap.add_argument("--seconds", type=float, default=60.0, help="simulated time per scene pass (default 60)")
    ap.add_argument("--passes", type=int, default=3, help="passes over each scene (default 3)")
    ap.add_argument("--chunk", type=int, default=50, help="steps per timed chunk (default 50)")
    ap.add_argument("--no-envs", action="store_true", help="scenes only")
    a = ap.parse_args(argv)
    if any(n < 1 for n in a.refresh):
        ap.error("--refresh: each interval must be ≥ 1")
    settings = [1] + [n for n in a.refresh if n != 1]
    head = "  ".join(f"{'N=' + str(n):>17s}" for n in settings)
    print(f"{a.setting}: {'case':34s} {head}   (µs/step, iterations/step; ratio to N=1)")
    scenes = SCENES + ([(DECK, {}, 0.05)] if a.setting == "cable_jacobian_refresh" else [])
    for name, ov, dt in scenes:
        r = _scene_case(name, ov, dt, a.setting, settings, a.seconds, a.chunk, a.passes)
        t1, i1, s1 = r[1]
        cells = []
        for n in settings:
            t, i, _ = r[n]
            cells.append(f"{t:6.2f} {i:5.3f}" + (f" ({t / t1:.3f}/{i / i1:.3f})" if n != 1 else " " * 14))
        print(f"{name + f' (dt {dt:g} s)':34s} " + "  ".join(cells), flush=True)
        for n in settings[1:]:
            print(f"{'':34s} N={n} final state vs N=1, max |dr| (m), |dT| (N), |d angle| (rad): "
                  f"{final_state_gap(s1, r[n][2])}")
    if a.no_envs:
        return
    for env_id, policy in ENV_CASES:
        r = _env_case(env_id, policy, a.setting, settings, 1500, 25)
        t1, i1 = r[1]
        cells = [f"{t:6.2f} {i:5.3f}" + (f" ({t / t1:.3f}/{i / i1:.3f})" if n != 1 else " " * 14)
                 for n, (t, i) in r.items()]
        print(f"{env_id.split('/')[1] + ', ' + policy + ' (env step)':34s} " + "  ".join(cells), flush=True)


if __name__ == "__main__":
    main()
