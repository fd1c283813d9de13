"""How much of an ``hq`` or ``hs`` compensator policy's residual comes from its added features (issue 14 probe).

For each policy file (feature set hq or hs, ``agents/ars_compensator.py``), runs the evaluation entries 0, 1, 4, 5, 8,
9 (two headings of each coastal code 3 / 4 / 5, evaluation wave seeds) on one batched environment, exactly as the
policy acts (skyhook + Θ·φ, clipped, stop guard), and splits the residual Θ·φ into the added features' part (hq: the
predicted features; hs: the skyhook-gated copy) and the rest; prints the RMS of each per sea state over t ≥
``discard`` in action units (log-stiffness, log-damping):

    python scripts/probe_residual_split.py agents/trained/gnq_CompensatorGains-v0_s{0,1,2}.npz
    python scripts/probe_residual_split.py agents/trained/gns_CompensatorGains-v0_s{0,1,2}.npz
"""
from __future__ import annotations

import argparse

import numpy as np

ENTRIES = (0, 1, 4, 5, 8, 9)


def residual_split(policy, episode_seconds=None, discard: float = 60.0) -> dict:
    """{WMO code: (RMS of the added features' part (2,), RMS of the other part (2,))} for one hq or hs policy (a file,
    or a loaded :class:`agents.ars_compensator.ARSCompensatorPolicy`)."""
    import gymnasium as gym

    import towenv  # noqa: F401  (registers the ids)
    from towenv.envs.vector import CompensatorGainsVectorEnv
    from agents import ars_compensator as arc
    from agents.common import nearest_key, reset_copies
    pol = policy if isinstance(policy, arc.ARSCompensatorPolicy) else arc.load_policy(policy)
    kind, pm = arc.added_features(pol.feature_set)
    if not kind:
        raise ValueError(f"{pol.name}: feature set {pol.feature_set!r} has no added features (need hq or hs)")
    ev = gym.make(arc.ENV_ID).unwrapped.eval_sea_states()
    ents = [ev[i] for i in ENTRIES]
    kw = {} if episode_seconds is None else {"episode_seconds": float(episode_seconds)}
    venv = CompensatorGainsVectorEnv(num_envs=len(ents), autoreset_mode="NextStep", batch_infos=True, **kw)
    batch = arc._Batch(venv, pol.base_table, pol.scales, pol.feature_set, pol.predictor)
    seas = [e[0] for e in ents]
    obs = reset_copies(venv, seas, [e[1] for e in ents])
    batch.set_seas(seas)
    th = np.array([pol.theta[nearest_key(pol.theta, s)] for s in seas])
    rp_all, rr_all = [], []
    for k in range(venv.envs[0].max_steps):
        phi = batch.features(obs, k == 0)
        rp = (th[:, :, pm] * phi[:, None, pm]).sum(axis=2)
        rr = (th[:, :, ~pm] * phi[:, None, ~pm]).sum(axis=2)
        a = np.clip(batch.base_action(obs) + rp + rr, -1.0, 1.0)
        a = arc._apply_guard(a, batch.reader, obs, pol.stop_guard).astype(np.float32)
        obs, _r, _te, _tr, info = venv.step(a)
        if info["t"][0] >= discard:
            rp_all.append(rp)
            rr_all.append(rr)
    venv.close()
    rp_all, rr_all = np.array(rp_all), np.array(rr_all)
    out = {}
    for code in sorted({e[1] // 1000 for e in ents}):
        c = [i for i, e in enumerate(ents) if e[1] // 1000 == code]
        out[code] = (np.sqrt((rp_all[:, c] ** 2).mean(axis=(0, 1))), np.sqrt((rr_all[:, c] ** 2).mean(axis=(0, 1))))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("policies", nargs="+", help="hq or hs compensator policy files (.npz)")
    ap.add_argument("--episode-seconds", type=float, default=None, help="episode length (default: the environment's)")
    ap.add_argument("--discard", type=float, default=60.0, help="start-up window left out (s)")
    a = ap.parse_args(argv)
    from agents import ars_compensator as arc
    for f in a.policies:
        try:
            pol = arc.load_policy(f)
            res = residual_split(pol, a.episode_seconds, a.discard)
        except (OSError, ValueError) as exc:
            ap.error(str(exc))
        part = arc.added_features(pol.feature_set)[0]
        for code, (p, r) in res.items():
            print(f"{f}: code {code}: RMS residual (log-stiffness, log-damping): {part} part "
                  f"{p[0]:.3f} / {p[1]:.3f}, other features {r[0]:.3f} / {r[1]:.3f}", flush=True)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
