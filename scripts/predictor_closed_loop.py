"""How well a v2q policy's predictor predicts the coming along-cable motion *under that policy* (closed loop).

The predictor (agents/predictor.py) is fitted on episodes under the along-cable law; a v2q policy uses it under its
own payout, which changes the cable angle and so the along-cable projection. This runs the policy on codes 4-5
(evaluation entries 4-11) with predictor-fit wave seeds it was not fitted on (replicates 7 and 8) and prints the R²
of its predicted features against the motion that followed, at +1 s and +2 s:

    python scripts/predictor_closed_loop.py agents/trained/gnq_WinchPayout-v0_s2.npz      # ~30 s
"""
import argparse
import sys

import numpy as np


def closed_loop_r2(policy_file, replicates=(7, 8), episode_seconds=None, discard=60.0):
    """{code: {channel: (R² at +1 s, R² at +2 s)}} of the policy's predicted features over t ≥ discard."""
    import gymnasium as gym

    import towenv  # noqa: F401
    from agents import ars
    from agents.common import reset_copies
    from agents.predictor import LEADS, predictor_seed
    from towenv.envs.vector import WinchPayoutVectorEnv
    pol = ars.load_ars_policy(policy_file)
    if pol.predictor is None:
        raise ValueError(f"{policy_file}: feature set {pol.feature_set!r} has no predictor (need v2q)")
    env = gym.make(ars.ENV_ID)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    ents = [(ev[i][0], predictor_seed(ev[i][1], r)) for r in replicates for i in range(4, 12)]
    codes = np.array([4 if i < 8 else 5 for _r in replicates for i in range(4, 12)])   # entries 4-7: code 4, 8-11: code 5
    seas = [e[0] for e in ents]
    kw = {} if episode_seconds is None else {"episode_seconds": float(episode_seconds)}
    venv = WinchPayoutVectorEnv(num_envs=len(ents), autoreset_mode="NextStep", batch_infos=True, **kw)
    batch = ars._Batch(venv, pol.base_table, dict(ars.FEATURE_SCALES), pol.feature_set, pol.predictor)
    obs = reset_copies(venv, seas, [e[1] for e in ents])
    batch.set_seas(seas)
    names = ars.feature_names(pol.feature_set)
    theta = ars.theta_rows(pol, seas, names)
    i0 = names.index(f"{ars.HISTORY_CHANNELS[0]}@+{LEADS[0] / 10:.1f}s(pred)")
    T = venv.envs[0].max_steps
    F = np.zeros((T, len(ents), 3 * len(LEADS)))
    X = np.zeros((T, len(ents), 3))
    for k in range(T):
        phi = batch.features(obs, k == 0)
        F[k] = phi[:, i0:i0 + 3 * len(LEADS)]
        X[k] = np.stack([batch.ch(obs, c) / ars.FEATURE_SCALES[c] for c in ars.HISTORY_CHANNELS], axis=1)
        a = np.clip(batch.base_action(obs) + np.einsum("nf,nf->n", theta, phi), -1.0, 1.0)
        obs, *_ = venv.step(a.astype(np.float32)[:, None])
    venv.close()
    t = np.arange(int(round(10 * discard)), T - max(LEADS))
    out = {}
    for c in (4, 5):
        m = codes == c
        out[c] = {}
        for j, ch in enumerate(ars.HISTORY_CHANNELS):
            r = []
            for lead in (10, 20):
                pred = F[t][:, m, len(LEADS) * j + LEADS.index(lead)]
                act = X[t + lead][:, m, j]
                r.append(float(1 - ((act - pred) ** 2).mean() / act.var()))
            out[c][ch] = tuple(r)
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policy", help="a v2q policy file")
    ap.add_argument("--episode-seconds", type=float, default=None, help="episode length (default: the environment's)")
    a = ap.parse_args(argv)
    if a.episode_seconds is not None and not a.episode_seconds > 63.0:
        ap.error(f"--episode-seconds must exceed 63 (scored from 60 s, 2 s leads; got {a.episode_seconds})")
    try:
        res = closed_loop_r2(a.policy, episode_seconds=a.episode_seconds)
    except ValueError as exc:
        ap.error(str(exc))
    for c, row in res.items():
        print(f"code {c}, under {a.policy} (closed loop), R² at +1 / +2 s: "
              + "; ".join(f"{ch} {r1:.3f} / {r2:.3f}" for ch, (r1, r2) in row.items()), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
