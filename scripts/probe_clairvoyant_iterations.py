"""Where the clairvoyant winch's advantage comes from: preview of the tow-point motion, or the model of the fish.

For chosen evaluation-set entries of WinchPayout-v0 (wave seed +0, never the final set) this plans the clairvoyant
winch (agents/clairvoyant.py) and prints, on the same episode, RMS fish heave with no control, with the planner's
first plan (perfect-preview tracking of the future along-cable displacement within the winch limits, a QP: what
an ideal wave/motion predictor would give a cancelling controller), after the iterative-learning steps on the
simulator (the reference the goal uses), and under the causal `along_cable` law. No cache: every plan is made
again (~3-10 min per entry on a free core).

    python scripts/probe_clairvoyant_iterations.py 0 1 4 5 8 9

``main`` returns the rows (entry, label, heading, σ none, σ preview plan, σ learned plan, σ along_cable).
"""
import argparse
import sys


def main(argv=None) -> list:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("entries", nargs="*", type=int, default=[0, 1, 4, 5, 8, 9],
                    help="evaluation-set entry indices (0..11; default: 0 1 4 5 8 9, headings 180° and 160° of codes 3-5)")
    ap.add_argument("--iterations", type=int, default=8, help="learning iterations (the reference uses 8)")
    ap.add_argument("--episode-seconds", type=float, default=None, help="episode length (default: the environment's)")
    ap.add_argument("--verbose", action="store_true", help="print every line-search step")
    a = ap.parse_args(argv)
    if not 1 <= a.iterations <= 30:
        ap.error(f"--iterations must be in 1..30; got {a.iterations}")
    if a.episode_seconds is not None and not 100.0 <= a.episode_seconds <= 3600.0:
        ap.error(f"--episode-seconds must be in 100..3600 (the score starts at 60 s or half the episode; got {a.episode_seconds})")
    import gymnasium as gym
    import numpy as np

    import towenv  # noqa: F401
    from agents.baselines import load_tuned, make_baseline
    from agents.clairvoyant import identify_fir, plan_episode
    from agents.metrics import default_discard, episode_metrics, rollout
    kw = {} if a.episode_seconds is None else {"episode_seconds": a.episode_seconds}
    env = gym.make("towenv/WinchPayout-v0", **kw)
    u = env.unwrapped
    ev = u.eval_sea_states()
    bad = [e for e in a.entries if not 0 <= e < len(ev)]
    if bad:
        ap.error(f"entries must be in 0..{len(ev) - 1}; got {bad}")
    planner = gym.make("towenv/WinchPayout-v0", **kw).unwrapped
    h, _ = identify_fir(planner, "winch", 60.0)
    along = make_baseline("along_cable", env, load_tuned())
    discard = default_discard(u.episode_seconds)
    rows = []
    print("entry  sea state                          none    preview-QP   learned   along_cable   (RMS fish heave, m)")
    for e in a.entries:
        sea, seed = ev[e]
        r = plan_episode(planner, sea, seed, "winch", h, iterations=a.iterations, verbose=a.verbose)
        m = episode_metrics(rollout(env, along, sea, seed), discard=discard)
        row = (e, sea.label, sea.heading_deg, r.free_sigma, r.history[0], r.sigma, m["rms_heave"])
        rows.append(row)
        print(f"{e:5d}  {sea.label[:24]:24s} {sea.heading_deg:5.0f}°  {row[3]:.4f}  {row[4]:.4f} ({1 - row[4] / row[3]:4.0%})"
              f"  {row[5]:.4f} ({1 - row[5] / row[3]:4.0%})  {row[6]:.4f} ({1 - row[6] / row[3]:4.0%})  [{r.seconds:.0f} s]",
              flush=True)
    f = np.array([r[3:] for r in rows])
    cr = 1.0 - f[:, 1:].mean(0) / f[:, 0].mean()          # the reports' pooled CR: 1 - mean(σ)/mean(σ_none)
    print(f"pooled compensation ratio (1 - mean σ / mean σ_none): preview-QP {cr[0]:.1%}, learned {cr[1]:.1%}, along_cable {cr[2]:.1%}")
    return rows


if __name__ == "__main__":
    main()
    sys.exit(0)
