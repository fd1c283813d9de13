"""What perfect preview of the tow point's motion is worth to the linear residual winch policy (issue 14, codes 4-5).

The committed WinchPayout policies (Gauss-Newton search, agents/gn.py) are linear in 2 s of the MRU's along-cable
history plus instant channels (feature set v2). This probe gives the same class **perfect preview**: the tow point's
future along-cable velocity, acceleration and displacement 0.2, 0.4, ..., 2.0 s ahead (30 more features, feature set
"v2p", defined here only), read from a run of the same episode (sea state, wave seed) under the along-cable law — the
ideal, non-causal version of the policy class. It then continues the Gauss-Newton search from a committed policy with
v2 (control) and with v2p on the same training waves and compares both on the evaluation set:

    python scripts/probe_preview_bound.py train v2  --export runs/preview/v2_s0.npz    # ~15-30 min on one core
    python scripts/probe_preview_bound.py train v2p --export runs/preview/v2p_s0.npz   # ~25-45 min on one core
    python scripts/probe_preview_bound.py evaluate agents/trained/gn4_WinchPayout-v0_s0.npz runs/preview/v2_s0.npz runs/preview/v2p_s0.npz

Training: entries 4-11 of the evaluation list (codes 4 and 5, the sea states where the goal is missed), ``--replicates``
wave seeds per entry (default 1), the Gauss-Newton training seeds of ``--seed`` continuing the initial policy's iteration count (never an
evaluation or final seed). Evaluation: the same entries with wave seeds +0 and +100 (the selection set), RMS fish heave
and pitch σ against ``along_cable`` per code, in one batched rollout (v2 policies run with zero preview weights).

**Causal preview: feature set "v2q"** (``agents/ars.py``, ``agents/predictor.py``): the same 30 features *predicted*
from the past (a linear predictor per sea state from 10 s of the MRU's motion, stored in the policy file) instead of
read from the future; the paired arm of the preview probe:

    python scripts/probe_preview_bound.py train v2q --predictor agents/trained/predictor_WinchPayout-v0.npz --replicates 3 --export runs/preview/v2q_s0_r3.npz
    python scripts/probe_preview_bound.py evaluate agents/trained/gn4_WinchPayout-v0_s0.npz runs/preview/v2q_s0_r3.npz

The preview feature sets ("v2p", and "v2pq" = v2q + preview, which evaluates both kinds of policy in one batch) are
registered at run time by patching ``agents.ars`` (its feature names, batch class and rollout) in this process only;
nothing here changes the committed policies or their loader.
"""
import argparse
import contextlib
import sys

import numpy as np

#: preview leads in control steps (0.2 ... 2.0 s ahead)
LEADS = tuple(range(2, 21, 2))
ENTRIES = tuple(range(4, 12))


@contextlib.contextmanager
def preview_feature_set():
    """Inside the block, feature set "v2p" exists in agents.ars: v2's features, then the 30 preview features, then
    the constant; the batch reads the preview from a recorded along-cable run of each (sea state, wave seed); and
    "v2pq": v2q's features (with its predictor) and then the preview ones. Everything patched is restored on exit.
    Yields the patched module."""
    from agents import ars
    from agents.common import reset_copies
    saved = (ars.feature_names, ars._Batch, ars.rollout_series)
    for fs in ("v2p", "v2pq"):
        ars.FEATURE_SETS[fs] = ars.FEATURE_SETS["v2"]
        ars.LONG_HISTORY[fs] = ()
    ars.PREDICTED = ars.PREDICTED | {"v2pq"}
    plain_predicted = ars.PREDICTED - {"v2pq"}
    plain_names, plain_batch, plain_rollout = ars.feature_names, ars._Batch, ars.rollout_series

    def feature_names(fs="v1"):
        names = plain_names(fs)
        if fs in ("v2p", "v2pq"):
            names = names[:-1] + [f"{c}@+{lead / 10:.1f}s" for c in ars.HISTORY_CHANNELS for lead in LEADS] + ["const"]
        return names

    cache = {}

    class PreviewBatch(plain_batch):
        def __init__(self, venv, table, scales, fs="v1", predictor=None):
            super().__init__(venv, table, scales, {"v2p": "v2", "v2pq": "v2q"}.get(fs, fs), predictor)
            self.preview_on = fs in ("v2p", "v2pq")

        def features(self, obs, first):
            phi = super().features(obs, first)
            if not self.preview_on:
                return phi
            self.k = 0 if first else self.k + 1
            f = self.fut[np.minimum(self.k + np.array(LEADS), self.fut.shape[0] - 1)]     # (leads, n, 3)
            pv = np.transpose(f, (1, 2, 0)).reshape(f.shape[1], -1)
            return np.concatenate([phi[:, :-1], pv, phi[:, -1:]], axis=1)

    def record(venv, batch, seas, seeds):
        """(T, n, 3) scaled along-cable channels of every copy's episode under along_cable (cached per episode)."""
        from towenv.envs.vector import WinchPayoutVectorEnv
        keys = [(repr(s), int(sd)) for s, sd in zip(seas, seeds)]
        todo = sorted({k for k in keys if k not in cache})
        if todo:
            first = {k: i for i, k in reversed(list(enumerate(keys)))}
            rv = WinchPayoutVectorEnv(num_envs=len(todo), autoreset_mode="NextStep", batch_infos=True,
                                      episode_seconds=float(venv.envs[0].episode_seconds))
            rs = [seas[first[k]] for k in todo]
            obs = reset_copies(rv, rs, [k[1] for k in todo])
            rb = plain_batch(rv, batch.table, batch.scales, "v2")
            rb.set_seas(rs)
            T = rv.envs[0].max_steps
            R = np.zeros((T, len(todo), 3))
            for k in range(T):
                R[k] = np.stack([rb.ch(obs, c) / rb.scales[c] for c in ars.HISTORY_CHANNELS], axis=1)
                obs, *_ = rv.step(rb.base_action(obs).astype(np.float32)[:, None])
            rv.close()
            for j, key in enumerate(todo):
                cache[key] = R[:, j].copy()
        return np.stack([cache[k] for k in keys], axis=1)

    def rollout_series(venv, batch, seas, seeds, theta):
        if getattr(batch, "preview_on", False):
            batch.fut = record(venv, batch, seas, seeds)
        return plain_rollout(venv, batch, seas, seeds, theta)

    ars.feature_names, ars._Batch, ars.rollout_series = feature_names, PreviewBatch, rollout_series
    try:
        yield ars
    finally:
        ars.feature_names, ars._Batch, ars.rollout_series = saved
        for fs in ("v2p", "v2pq"):
            del ars.FEATURE_SETS[fs], ars.LONG_HISTORY[fs]
        ars.PREDICTED = plain_predicted


def evaluate(ars, files, replicates=2, episode_seconds=None):
    """Rows (file, {code: (heave change, pitch change) against along_cable}); ``ars`` the patched module."""
    import gymnasium as gym

    import towenv  # noqa: F401
    from towenv.envs.vector import WinchPayoutVectorEnv
    pols = [ars.load_ars_policy(f) for f in files]
    from agents.predictor import shared_predictor
    predictor = shared_predictor(pols)
    fs = "v2pq" if predictor is not None else "v2p"
    env = gym.make(ars.ENV_ID)
    ev = env.unwrapped.eval_sea_states()
    env.close()
    ents = [(ev[i][0], ev[i][1] + 100 * r, i) for r in range(replicates) for i in ENTRIES]
    names = ars.feature_names(fs)
    th = [np.zeros((len(ents), len(names)))] + [ars.theta_rows(p, [e[0] for e in ents], names) for p in pols]
    k = len(pols) + 1
    kw = {} if episode_seconds is None else {"episode_seconds": float(episode_seconds)}
    venv = WinchPayoutVectorEnv(num_envs=len(ents) * k, autoreset_mode="NextStep", batch_infos=True, **kw)
    batch = ars._Batch(venv, pols[0].base_table, dict(ars.FEATURE_SCALES), fs, predictor)
    sh, sp = ars.rollout_batch(venv, batch, [e[0] for e in ents] * k, [e[1] for e in ents] * k, np.concatenate(th))
    venv.close()
    sh, sp = sh.reshape(k, -1), sp.reshape(k, -1)
    codes = np.array([int(round(ev[i][0].hs > 2.5)) + 4 for _sea, _s, i in ents])    # code 4: Hs 1.88 m, code 5: 3.25 m
    print(f"evaluation set, entries {ENTRIES[0]}-{ENTRIES[-1]} x wave seeds +0..+{100 * (replicates - 1)}: RMS fish heave "
          f"and pitch σ against along_cable (ratio of the per-code means)")
    print(f"  along_cable: code 4 {sh[0][codes == 4].mean():.4f} m, code 5 {sh[0][codes == 5].mean():.4f} m")
    rows = []
    for j, f in enumerate(files):
        r = {c: (sh[j + 1][codes == c].mean() / sh[0][codes == c].mean() - 1,
                 sp[j + 1][codes == c].mean() / sp[0][codes == c].mean() - 1) for c in (4, 5)}
        rows.append((f, r))
        print(f"  {f}: " + "; ".join(f"code {c}: heave {100 * r[c][0]:+.1f} %, pitch {100 * r[c][1]:+.1f} %"
                                     for c in (4, 5)), flush=True)
    return rows


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="cmd", required=True)
    t = sub.add_parser("train", help="continue the Gauss-Newton search with feature set v2 or v2p (preview)")
    t.add_argument("features", choices=("v2", "v2p", "v2q"))
    t.add_argument("--predictor", default=None, help="predictor file of feature set v2q (python -m agents.predictor)")
    t.add_argument("--init", default="agents/trained/gn4_WinchPayout-v0_s0.npz", help="policy to start from")
    t.add_argument("--seed", type=int, default=0, help="training seed (its Gauss-Newton training wave seeds)")
    t.add_argument("--iterations", type=int, default=8, help="Gauss-Newton iterations (1..17 after gn4)")
    t.add_argument("--replicates", type=int, default=1, help="wave seeds per entry per iteration (1..10)")
    t.add_argument("--export", required=True, help="policy file to write")
    e = sub.add_parser("evaluate", help="compare policy files (v1, v2, v2p or v2q; not v3) on the evaluation set, codes 4-5")
    e.add_argument("policies", nargs="+")
    e.add_argument("--replicates", type=int, default=2, help="wave seeds +0, +100, ... per entry (1..5)")
    e.add_argument("--episode-seconds", type=float, default=None, help="episode length (default: the environment's)")
    a = ap.parse_args(argv)
    if a.cmd == "evaluate" and not 1 <= a.replicates <= 5:
        ap.error(f"--replicates must be in 1..5 (the evaluation set; got {a.replicates})")
    if a.cmd == "evaluate" and a.episode_seconds is not None and not a.episode_seconds > 61.0:
        ap.error(f"--episode-seconds must exceed 61 (the score starts at 60 s; got {a.episode_seconds})")
    from agents import gn
    with preview_feature_set() as ars:
        try:
            if a.cmd == "evaluate":
                evaluate(ars, a.policies, a.replicates, a.episode_seconds)
                return 0
            init = ars.load_ars_policy(a.init)
            predictor = None
            if a.features == "v2q":
                from agents.predictor import Predictor
                if a.predictor is None:
                    ap.error("feature set v2q needs --predictor FILE (python -m agents.predictor --out FILE)")
                predictor = Predictor.load(a.predictor)
            pol = gn.train(seed=a.seed, iterations=a.iterations, minutes=600, replicates=a.replicates,
                           ridges=(0.01, 0.1, 1, 10, 100), feature_set=a.features, entries=list(ENTRIES), init=init,
                           predictor=predictor)
        except (OSError, ValueError, KeyError) as exc:
            ap.error(str(exc))
        ars.save_policy(pol, a.export)
    print(f"wrote {a.export}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
