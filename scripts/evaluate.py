#!/usr/bin/env python
"""Evaluate a policy and every baseline on the evaluation sea states; write a report.

POLICY is a policy zip written by scripts/train.py (algorithm and environment from its metadata), any
SB3 zip (give --algo and --env), or a baseline name (then --env is needed). Every controller runs the
same episodes: ``env.unwrapped.eval_sea_states()`` (12 = WMO codes 3-5 × 4 headings, fixed wave seeds),
optionally with extra wave seeds per entry (--replicates). Writes ``<out-dir>/<name>/report.md``,
``summary.png``, ``psd.png``, ``timeseries.png``, ``metrics.csv``, ``summary.json`` (+ ``report.html``).

Examples::

    python scripts/evaluate.py agents/trained/ppo_WinchPayout-v0.zip
    python scripts/evaluate.py agents/trained/ppo_CompensatorGains-v0.zip \\
        --also agents/trained/sac_CompensatorGains-v0.zip --replicates 2 --html
    python scripts/evaluate.py pd_ff --env towenv/WinchPayout-v0 --name winch_baselines
    python scripts/evaluate.py run/final.zip --episodes 0 4 --env-kwargs episode_seconds:40   # quick look
"""
from __future__ import annotations

import argparse
import os
import shlex
import sys
from pathlib import Path

for _v in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "NUMBA_NUM_THREADS"):
    os.environ.setdefault(_v, "1")

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))

#: keywords of a policy's training environment that are not carried to the evaluation environment
TRAINING_ONLY = ("reward_weights", "reward_fn", "episode_seconds", "sea_generator", "render_mode")


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("policy", help="policy zip, or a baseline name")
    p.add_argument("--also", nargs="*", default=[], help="more policy zips in the same report")
    p.add_argument("--algo", default=None, help="algorithm of a zip without towenv metadata (ppo, sac, ...)")
    p.add_argument("--env", default=None, help="environment id (default: from the zip's metadata)")
    p.add_argument("--baselines", nargs="*", default=None, help="baselines to include (default: all of the env)")
    p.add_argument("--env-kwargs", nargs="*", default=None, metavar="KEY:VALUE",
                   help="evaluation environment keywords (Python literals), e.g. episode_seconds:60")
    p.add_argument("--episodes", nargs="*", type=int, default=None,
                   help="indices into eval_sea_states() to use (default all)")
    p.add_argument("--replicates", type=int, default=1, help="wave seeds per evaluation entry (seed + 100 r)")
    p.add_argument("--discard", type=float, default=None, help="start-up window (s; default min(60, T/2))")
    p.add_argument("--name", default=None, help="report name (default: the policy's file stem)")
    p.add_argument("--out-dir", default=str(REPO / "docs" / "reports"))
    p.add_argument("--html", action="store_true", help="also write report.html")
    p.add_argument("--no-plots", action="store_true")
    p.add_argument("--boot", type=int, default=2000, help="bootstrap resamples")
    p.add_argument("--tuned", default=None, help="tuned-baseline YAML (default agents/hyperparams/baselines.yml)")
    return p.parse_args(argv)


def main(argv=None):
    args = parse_args(argv)
    import torch
    torch.set_num_threads(1)
    from agents.baselines import BASELINES, load_tuned
    from agents.evaluation import run_evaluation
    from agents.report import write_report
    from agents.zoo import load_policy, parse_env_kwargs

    trained = []
    env_id = args.env
    base_kwargs: dict = {}
    baselines = args.baselines
    for i, spec in enumerate([args.policy] + list(args.also)):
        if spec in BASELINES and i == 0:
            if env_id is None:
                kind = BASELINES[spec][0]
                env_id = "towenv/CompensatorGains-v0" if kind == "compensator" else "towenv/WinchPayout-v0"
            continue
        path = Path(spec)
        if not path.exists():
            sys.exit(f"evaluate: {spec!r} is neither a file nor a baseline name ({', '.join(BASELINES)})")
        pol = load_policy(path, algo=args.algo)
        meta = pol.meta
        eid = meta.get("env_id") or env_id
        if eid is None:
            sys.exit(f"evaluate: {spec}: no environment id in the zip; pass --env")
        if env_id is None:
            env_id = eid
        elif eid != env_id:
            sys.exit(f"evaluate: {spec} was trained on {eid}, not {env_id}")
        if i == 0:
            base_kwargs = {k: v for k, v in (meta.get("env_kwargs") or {}).items() if k not in TRAINING_ONLY}
        meta = dict(meta)
        meta["env_kwargs"] = {k: v for k, v in (meta.get("env_kwargs") or {}).items() if k not in TRAINING_ONLY}
        name = path.stem
        if any(n == name for n, *_ in trained):
            name = f"{name}_{i}"
        trained.append((name, pol, meta))
    base_kwargs.update(parse_env_kwargs(args.env_kwargs))
    tuned = load_tuned(args.tuned) if args.tuned else None
    res = run_evaluation(env_id, trained, baselines=baselines, env_kwargs=base_kwargs, replicates=args.replicates,
                         indices=args.episodes, discard=args.discard, n_boot=args.boot, tuned=tuned)
    name = args.name or (Path(args.policy).stem if trained else f"baselines_{env_id.split('/')[-1]}")
    out = Path(args.out_dir) / name
    cmd = "python scripts/evaluate.py " + " ".join(shlex.quote(a) for a in (argv if argv is not None else sys.argv[1:]))
    title = f"Evaluation report: {name}"
    md = write_report(res, out, title, command=cmd, html_too=args.html, plots=not args.no_plots)
    print(f"[evaluate] wrote {md}", flush=True)
    for g in res.goals:
        v = g["value"]
        val = f"{v[0]:.0f}" if g.get("count") else f"{100 * v[0]:.1f} % [{100 * v[1]:.1f}, {100 * v[2]:.1f}]"
        print(f"[evaluate] {g['policy']}: {g['criterion']}: {val} -> {'MET' if g['met'] else 'not met'}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
