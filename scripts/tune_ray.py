#!/usr/bin/env python
"""Optional Ray Tune sweep (extra ``ray``: ``pip install "towenv[ray]"``) over seeds × sea states ×
hyperparameters, with SB3 as the only RL implementation.

Each trial runs ``scripts/train.py``'s ``main`` in-process (one CPU, its own run folder under
``--log-dir``) with the trial's seed, WMO sea-state codes (``--env-kwargs sea_codes:...``) and
hyperparameter overrides (``--hyperparams``), then reports the best validation reward of its
EvalCallback and the exported policy path. The search space is a grid (``tune.grid_search``) over the
values given on the command line; pass ``--num-samples`` > 1 to repeat the grid.

    python scripts/tune_ray.py --algo ppo --env towenv/WinchPayout-v0 --seeds 0 1 2 \\
        --sea-codes 3 4 5 345 --param learning_rate 1e-4 3e-4 --param gamma 0.99 0.995 \\
        --n-timesteps 500000 --cpus 2
    python scripts/tune_ray.py --dry-run ...        # print the trial list; does not need ray

``--sea-codes 345`` means "train on codes 3, 4 and 5"; a single digit trains on one code.
Results: Ray's experiment folder (``--storage``, default ``<log-dir>/ray``) and ``<log-dir>/tune_results.json``.
"""
from __future__ import annotations

import argparse
import itertools
import json
import os
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent
if str(REPO) not in sys.path:
    sys.path.insert(0, str(REPO))


def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("--algo", default="ppo")
    p.add_argument("--env", default="towenv/WinchPayout-v0")
    p.add_argument("--conf", default=None)
    p.add_argument("--seeds", nargs="*", type=int, default=[0])
    p.add_argument("--sea-codes", nargs="*", default=["345"])
    p.add_argument("--param", nargs="+", action="append", default=[], metavar=("NAME", "VALUE"),
                   help="hyperparameter NAME with grid VALUES (Python literals); repeatable")
    p.add_argument("--n-timesteps", type=int, default=200_000)
    p.add_argument("--max-minutes", type=float, default=None, help="per trial")
    p.add_argument("--eval-freq", type=int, default=50_000)
    p.add_argument("--log-dir", default="runs/tune")
    p.add_argument("--storage", default=None)
    p.add_argument("--cpus", type=int, default=None, help="CPUs Ray may use (default: all)")
    p.add_argument("--num-samples", type=int, default=1)
    p.add_argument("--dry-run", action="store_true")
    return p.parse_args(argv)


def trial_argv(cfg: dict, args) -> list[str]:
    name = f"{args.algo}_{args.env.split('/')[-1]}_c{cfg['sea_codes']}_s{cfg['seed']}"
    hp = []
    for k, v in sorted(cfg.get("hyperparams", {}).items()):
        hp.append(f"{k}:{v!r}")
        name += f"_{k}{v}"
    argv = ["--algo", args.algo, "--env", args.env, "--seed", str(cfg["seed"]), "--n-timesteps", str(args.n_timesteps),
            "--log-dir", str(Path(args.log_dir).resolve()), "--name", name, "--eval-freq", str(args.eval_freq),
            "--no-progress-bar", "--env-kwargs", f"sea_codes:{tuple(int(c) for c in str(cfg['sea_codes']))!r}"]
    if hp:
        argv += ["--hyperparams", *hp]
    if args.conf:
        argv += ["--conf", args.conf]
    if args.max_minutes:
        argv += ["--max-minutes", str(args.max_minutes)]
    return argv


def grid(args) -> list[dict]:
    import ast
    names = [p[0] for p in args.param]
    values = [[ast.literal_eval(v) for v in p[1:]] for p in args.param]
    out = []
    for seed, codes in itertools.product(args.seeds, args.sea_codes):
        for combo in itertools.product(*values) if values else [()]:
            out.append({"seed": seed, "sea_codes": codes, "hyperparams": dict(zip(names, combo))})
    return out


def run_trial(cfg: dict, args) -> dict:
    import importlib.util
    spec = importlib.util.spec_from_file_location("towenv_train", REPO / "scripts" / "train.py")
    train = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(train)
    argv = trial_argv(cfg, args)
    train.main(argv)
    run = Path(args.log_dir).resolve() / argv[argv.index("--name") + 1]
    info = json.loads((run / "run_info.json").read_text())
    best = None
    ev = run / "eval" / "evaluations.npz"
    if ev.exists():
        import numpy as np
        d = np.load(ev)
        best = float(d["results"].mean(axis=1).max())
    return {"best_validation_reward": best, "num_timesteps": info["num_timesteps"], "policy": info["exported"],
            "wall_seconds": info["wall_seconds"]}


def main(argv=None):
    args = parse_args(argv)
    trials = grid(args)
    if args.dry_run:
        for cfg in trials:
            print("python scripts/train.py " + " ".join(trial_argv(cfg, args)))
        return 0
    try:
        import ray
        from ray import tune
    except ImportError:
        sys.exit('tune_ray.py needs Ray Tune: pip install "towenv[ray]"  (or use --dry-run for the trial list)')
    os.environ.setdefault("OMP_NUM_THREADS", "1")
    ray.init(num_cpus=args.cpus, ignore_reinit_error=True)

    def trainable(config):
        res = run_trial(config, args)
        report = getattr(tune, "report", None)
        if report is None:                      # older Ray: ray.train.report
            from ray import train as _train
            report = _train.report
        report({k: (v if v is not None else float("-inf")) for k, v in res.items() if k != "policy"}
               | {"policy": res["policy"]})

    space = {"seed": tune.grid_search(args.seeds), "sea_codes": tune.grid_search(args.sea_codes),
             "hyperparams": tune.grid_search([t["hyperparams"] for t in grid(argparse.Namespace(
                 seeds=[0], sea_codes=["3"], param=args.param))])}
    tuner = tune.Tuner(tune.with_resources(trainable, {"cpu": 1}), param_space=space,
                       tune_config=tune.TuneConfig(metric="best_validation_reward", mode="max",
                                                   num_samples=args.num_samples),
                       run_config=_run_config(args))
    results = tuner.fit()
    rows = []
    for r in results:
        rows.append({"config": r.config, "metrics": {k: r.metrics.get(k) for k in
                                                     ("best_validation_reward", "num_timesteps", "policy")}})
    out = Path(args.log_dir) / "tune_results.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(json.dumps(rows, indent=1, default=str))
    best = results.get_best_result()
    print(f"[tune] best: {best.config} -> {best.metrics.get('best_validation_reward')} ({out})")
    return 0


def _run_config(args):
    storage = str(Path(args.storage or Path(args.log_dir) / "ray").resolve())
    try:
        from ray.tune import RunConfig
    except ImportError:
        from ray.train import RunConfig
    return RunConfig(name="towenv_sweep", storage_path=storage)


if __name__ == "__main__":
    sys.exit(main())
