"""How far the WinchPayout linear residual class goes when fitted on the very episodes it is scored on (issue 14,
codes 4-5): an in-sample bound of the policy class, not a result.

The committed WinchPayout policies (Gauss-Newton search, ``agents/gn.py``, feature set v2q) miss the goal "CR ≥ 0.9 ×
the clairvoyant's in every sea state" in codes 4-5. Is that the class (a linear residual on 2 s of MRU history,
instant channels and the predicted along-cable motion) or the search (fresh wave seeds every iteration, so it must
generalise)? This probe continues the Gauss-Newton search from a committed policy with every Jacobian and
line-search episode drawn from the **evaluation set itself** (entries 4-11, wave seeds +0 and +100: the episodes it
is then scored on), so the search fits those 16 episodes — the ideal, in-sample version of the class's training. If
it reaches 0.9 × the clairvoyant's CR on the same episodes, the class can and the generalising search is what
misses; if it stays below, that is a lower estimate of the class's in-sample optimum (the search may not have
converged), evidence against the class but not a proof.

    python scripts/probe_class_bound.py --init agents/trained/gnqp2_WinchPayout-v0_s1.npz --iterations 3 --export runs/class_bound/fit300_s1.npz
    python scripts/evaluate.py runs/class_bound/fit300_s1.npz --also agents/trained/gnqp2_WinchPayout-v0_s1.npz --episodes 4 5 6 7 8 9 10 11 --replicates 2 --seed-set eval --baselines fixed_winch along_cable clairvoyant --no-plots --name class_bound --out-dir runs/class_bound

``--features v2qa`` fits the richer class (v2q + hinges of the predicted along-cable acceleration) from the same
start, its extra weights at 0: does a nonlinearity aimed at the winch's acceleration limit raise the class's optimum?

The fitted file is a probe artefact (``meta["probe"]`` says so): it has seen the evaluation set and must never be
committed or reported as a policy. The search's settings are the committed ``gnqp2`` continuation's (three
replicates → here the evaluation set's two, ridges 0.01-100, pitch weight 0.1, codes 4-5, feature set v2q with the
init's predictor).
"""
import argparse
import sys
from pathlib import Path

#: entries of the evaluation list fitted and scored (codes 4 and 5)
ENTRIES = tuple(range(4, 12))
#: wave-seed replicates of the evaluation set used (+0, +100)
REPLICATES = 2
#: the evaluation's episode length (the environment's default): fitted episodes of this length are the scored ones
EPISODE_SECONDS = 300.0


def eval_seed(search_base_seed: int) -> int:
    """The evaluation-set wave seed that replaces the search's episode seed: the search asks for base ``1000·code + j
    + 10·replicate`` (j < 10, replicate < 10); the evaluation set's replicate r of that entry is ``1000·code + j +
    100·r`` (agents/evaluate.py), for the Jacobian and the line search alike (in-sample)."""
    b = int(search_base_seed)
    r = (b // 10) % 10
    if not 0 <= r < REPLICATES:
        raise ValueError(f"replicate {r} outside the evaluation set's {REPLICATES}")
    return b - 10 * r + 100 * r


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--init", required=True, help="committed WinchPayout GN policy (v2q) to start from")
    ap.add_argument("--iterations", type=int, default=3, help="Gauss-Newton iterations (1..10, default 3)")
    ap.add_argument("--pitch-weight", type=float, default=0.1, help="weight of ln(σ_pitch ratio) (default 0.1)")
    ap.add_argument("--minutes", type=float, default=60.0, help="wall-clock budget (default 60)")
    ap.add_argument("--episode-seconds", type=float, default=EPISODE_SECONDS,
                    help=f"length of the fitted episodes (default {EPISODE_SECONDS:g} s: the evaluation's, so the fit "
                         "sees the whole scored window; the search's own default, 180 s, fits only its first 120 s)")
    ap.add_argument("--features", choices=("v2q", "v2qa"), default="v2q",
                    help="policy class fitted: v2q (the committed policies', default) or the richer v2qa (v2q + hinges "
                         "of the predicted along-cable acceleration, agents/ars.py; its extra weights start at 0)")
    ap.add_argument("--export", required=True, help="where the fitted probe file goes (e.g. runs/class_bound/...)")
    a = ap.parse_args(argv)
    if not 1 <= a.iterations <= 10:
        ap.error(f"--iterations must be in 1..10 (got {a.iterations})")
    if not a.pitch_weight >= 0 or not a.minutes > 0 or not a.episode_seconds > 61.0:
        ap.error("need --pitch-weight >= 0, --minutes > 0 and --episode-seconds > 61 (scored after 60 s)")
    import agents
    from agents import ars, gn
    out = Path(a.export)
    if any(out.resolve().is_relative_to(d) for d in (Path(__file__).resolve().parent.parent / "agents",
                                                      Path(agents.__file__).resolve().parent)):
        ap.error("--export: a probe file has seen the evaluation set; keep it out of agents/ (e.g. runs/class_bound/)")
    try:
        init = ars.load_ars_policy(a.init)
    except (OSError, ValueError) as e:
        ap.error(f"--init: {e}")
    if init.feature_set not in ("v2q", a.features):
        ap.error(f"--init: feature set {init.feature_set}, this probe continues a v2q or {a.features} policy")
    pol = gn.train(seed=int(init.meta.get("seed", 0)), iterations=a.iterations, minutes=a.minutes,
                   replicates=REPLICATES, ridges=(0.01, 0.1, 1.0, 10.0, 100.0), pitch_weight=a.pitch_weight,
                   feature_set=a.features, entries=list(ENTRIES), init=init, episode_seconds=a.episode_seconds,
                   wave_seed=lambda base, it, seed, line_search=False: eval_seed(base))   # all from the eval set
    pol.meta["probe"] = ("in-sample class bound (scripts/probe_class_bound.py): fitted on the evaluation set's "
                         "entries 4-11, wave seeds +0 and +100 — not a policy")
    pol.meta["train_seeds"] = f"the evaluation set's own seeds (in-sample), {a.episode_seconds:g} s episodes"
    pol.name = f"{out.stem}"
    out.parent.mkdir(parents=True, exist_ok=True)
    ars.save_policy(pol, out)
    print(f"[class bound] wrote {out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
