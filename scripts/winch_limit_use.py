"""How often the WinchPayout winch's limits bind under a controller: the fraction of the scored window (t ≥ 60 s) in
which the winch runs at its speed limit (|v| ≥ 0.99 v_max) or changes speed at its acceleration limit
(|Δv/Δt| ≥ 0.99 a_max between control steps), from the observed winch speed, per evaluation-set episode.

    python scripts/winch_limit_use.py agents/trained/gnqp2_WinchPayout-v0_s1.npz --entries 4 8 9 --replicates 2

(the figure behind feature set v2qa, docs/agents.md: the acceleration limit binds 27–34 % of the time in codes 4–5
under the v2q policy, the speed limit ≤ 0.2 %; under the hinged `gnqa` policy 40–43 %, `gnr` 43–46 %). The controller
is a policy file (ARS/GN linear residual) or a baseline name.
"""
import argparse
import sys

import numpy as np

DISCARD = 60.0


def limit_use(env, policy, sea, seed):
    """(speed-limit fraction, acceleration-limit fraction) of the scored window of one episode."""
    from agents.common import ObsReader
    u = env.unwrapped
    obs, _ = env.reset(seed=int(seed), options={"sea_state": sea, "sea_seed": int(seed)})
    policy.reset(env) if getattr(policy, "bind_env", None) else policy.reset()
    reader = ObsReader(env)
    v, t = [], []
    done, k = False, 0
    while not done:
        a, _ = policy.predict(obs, episode_start=np.array([k == 0]))
        obs, _r, term, trunc, info = env.step(a)
        v.append(float(np.ravel(reader(obs, "winch_speed"))[0]) * u.winch_max_speed)
        t.append(float(info["t"]))
        done, k = term or trunc, k + 1
    v, t = np.array(v), np.array(t)
    w = t >= DISCARD
    acc = np.diff(v) / np.diff(t)
    return (float(np.mean(np.abs(v[w]) >= 0.99 * u.winch_max_speed)),
            float(np.mean(np.abs(acc[w[1:]]) >= 0.99 * u.winch_max_acceleration)))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("controller", help="WinchPayout ARS/GN policy file (.npz) or a baseline name (e.g. along_cable)")
    ap.add_argument("--entries", type=int, nargs="+", default=[4, 8, 9], help="evaluation-list entries (0..11)")
    ap.add_argument("--replicates", type=int, default=2, help="wave seeds per entry, +0, +100, … (1..5)")
    a = ap.parse_args(argv)
    if not 1 <= a.replicates <= 5:
        ap.error(f"--replicates must be in 1..5 (got {a.replicates})")
    if any(not 0 <= e < 12 for e in a.entries):
        ap.error(f"--entries must be in 0..11 (got {a.entries})")
    from agents import ars
    from agents.baselines import make_baseline
    from agents.evaluation import eval_episodes, make_eval_env
    env = make_eval_env(ars.ENV_ID)
    if a.controller.endswith(".npz"):
        try:
            pol = ars.load_ars_policy(a.controller)
        except (OSError, ValueError) as e:
            ap.error(str(e))
        env = make_eval_env(pol.meta["env_id"], pol.meta.get("env_kwargs", {}))
        pol.bind_env(env)
    else:
        try:
            pol = make_baseline(a.controller, env)
        except (KeyError, ValueError) as e:
            ap.error(str(e))
    for _key, label, sea, seed in eval_episodes(env, a.replicates, a.entries):
        sp, ac = limit_use(env, pol, sea, seed)
        print(f"{label}, wave seed {seed}: speed limit {100 * sp:.1f} %, acceleration limit {100 * ac:.1f} % of the "
              f"scored time")
    return 0


if __name__ == "__main__":
    sys.exit(main())
