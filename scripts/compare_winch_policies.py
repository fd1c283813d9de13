"""Compare WinchPayout linear-residual policy files (ARS / Gauss-Newton, any feature set) against the along-cable law
on the evaluation seed set (the 12 entries with wave seeds +0 and +100 — the selection set, never the final one) in
one batched rollout; prints RMS heave against along_cable pooled and per sea-state code, and pitch. The batched
rollout equals the single-environment policy to round-off (tests/agents/test_ars.py).

    python scripts/compare_winch_policies.py agents/trained/gn_WinchPayout-v0_s0.npz runs/gn3/probe_v3_s0.npz
"""
import argparse

import numpy as np


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policies", nargs="+", help="ARS/GN WinchPayout policy files (.npz)")
    ap.add_argument("--replicates", type=int, default=2, help="wave-seed replicates per entry, +0, +100, ... (1..5)")
    ap.add_argument("--episode-seconds", type=float, default=None, help="episode length (default: the environment's)")
    a = ap.parse_args(argv)
    if a.episode_seconds is not None and not a.episode_seconds > 61.0:
        ap.error(f"--episode-seconds must exceed 61 (the score starts at 60 s; got {a.episode_seconds})")
    if not 1 <= a.replicates <= 5:
        ap.error(f"--replicates must be in 1..5 (the evaluation set; got {a.replicates})")
    import gymnasium as gym

    import towenv  # noqa: F401
    from agents import ars
    from towenv.envs.vector import WinchPayoutVectorEnv
    try:
        pols = [ars.load_ars_policy(f) for f in a.policies]
    except ValueError as e:
        ap.error(str(e))
    if any(p.base_table != pols[0].base_table for p in pols):
        ap.error("the policies sit on different along-cable gain tables")
    env = gym.make(ars.ENV_ID)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    ents = [(sea, s + 100 * r) for r in range(a.replicates) for sea, s in ev]
    fs = max((p.feature_set for p in pols), key=ars.n_features)   # the widest set holds every policy's features
    names = ars.feature_names(fs)
    if any(not set(ars.feature_names(p.feature_set)) <= set(names) for p in pols):
        ap.error("the policies' feature sets do not nest")
    th = [np.zeros((len(ents), len(names)))] + [ars.theta_rows(p, [sea for sea, _s in ents], names) for p in pols]
    n = len(ents) * (len(pols) + 1)
    kw = {} if a.episode_seconds is None else {"episode_seconds": float(a.episode_seconds)}
    venv = WinchPayoutVectorEnv(num_envs=n, autoreset_mode="NextStep", batch_infos=True, **kw)
    from agents.predictor import shared_predictor
    try:
        predictor = shared_predictor(pols)
    except ValueError as e:
        ap.error(str(e))
    batch = ars._Batch(venv, pols[0].base_table, dict(ars.FEATURE_SCALES), fs, predictor)
    sh, sp = ars.rollout_batch(venv, batch, [s for s, _ in ents] * (len(pols) + 1),
                               [s for _, s in ents] * (len(pols) + 1), np.concatenate(th))
    venv.close()
    sh = sh.reshape(len(pols) + 1, -1)
    sp = sp.reshape(len(pols) + 1, -1)
    codes = np.array([s // 1000 % 10 for _, s in ents])
    print(f"{len(ents)} evaluation-set episodes; RMS heave against along_cable (ratio of means), pooled and per code")
    for i, f in enumerate(a.policies, start=1):
        per = " ".join(f"code {c}: {100 * (sh[i][codes == c].mean() / sh[0][codes == c].mean() - 1):+6.2f} %"
                       for c in sorted(set(codes)))
        print(f"{f}: heave {100 * (sh[i].mean() / sh[0].mean() - 1):+6.2f} % ({per}); pitch "
              f"{100 * (sp[i].mean() / sp[0].mean() - 1):+5.2f} %")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
