#!/usr/bin/env python
"""Optional Ray Tune sweep (extras ``rl`` and ``ray``: ``pip install "towenv[rl,ray]"``) over seeds × sea
states × hyperparameters, with SB3 as the only RL implementation.

Each trial runs ``scripts/train.py``'s ``main`` in-process on one CPU of a Ray worker, in its own run folder
``<log-dir>/<trial name>/`` (the usual train.py folder: best_policy.zip, final.zip, eval/, run_info.json),
with the trial's seed, WMO sea-state codes (``--env-kwargs sea_codes:...``) and hyperparameter overrides
(``--hyperparams``), then reports the best validation reward of its EvalCallback and the exported policy path.
The search space is the grid of the values given on the command line; ``--num-samples N`` runs the grid N
times (folders ``..._r1``, ``..._r2``: the same seeds, so identical results, a determinism check; use
``--seeds`` for independent runs). Relative paths (``--log-dir``, ``--storage``, ``--conf``) are relative to
the directory the command is run from.

    python scripts/tune_ray.py --algo ppo --env towenv/WinchPayout-v0 --seeds 0 1 2 \\
        --sea-codes 3 4 5 345 --param learning_rate 1e-4 3e-4 --param gamma 0.99 0.995 \\
        --n-timesteps 500000 --cpus 2
    python scripts/tune_ray.py --dry-run ...        # print the trial list; does not need ray
    python scripts/tune_ray.py --seeds 0 1 --sea-codes 3 --n-timesteps 2048 --eval-freq 2048 --n-envs 2 \\
        --eval-episodes 1 --env-kwargs episode_seconds:20.0 --param n_steps 256 --param batch_size 128 \\
        --cpus 2                                     # a small real sweep (~30 s on 2 cores)

``--sea-codes 345`` means "train on codes 3, 4 and 5"; a single digit trains on one code.
Ray: by default a new local Ray instance with ``--cpus`` CPUs (default all) is started and stopped;
``--address auto`` (the cluster started by ``ray start`` on this machine), ``--address HOST:6379``, or the
``RAY_ADDRESS`` environment variable, use an existing cluster (then ``--cpus`` caps the number of concurrent
trials); Ray Client addresses (``ray://HOST:10001``) are passed on to Ray but untested. Every node needs towenv[rl] and this
checkout at the same path, and ``--log-dir`` on a filesystem that all nodes share (docs/agents.md).
Results: one line per trial as it starts and ends, Ray's experiment folder (``--storage``, default
``<log-dir>/ray``) and ``<log-dir>/tune_results.json``. Exit status 1 if a trial failed, 2 if an extra is
missing.
"""
from __future__ import annotations

import argparse
import itertools
import json
import math
import os
import re
import sys
import time
from pathlib import Path

from towenv.atomic import atomic_write
from towenv.extras import RL_COMMAND_MODULES, missing_modules



def parse_args(argv=None):
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter,
                                epilog=__doc__.split("\n\n", 1)[1])
    p.add_argument("--algo", default="ppo")
    p.add_argument("--env", default="towenv/WinchPayout-v0")
    p.add_argument("--conf", default=None, help="hyperparameter YAML (train.py's default: agents/hyperparams/<algo>.yml)")
    p.add_argument("--seeds", nargs="*", type=int, default=[0])
    p.add_argument("--sea-codes", nargs="*", default=["345"])
    p.add_argument("--param", nargs="+", action="append", default=[], metavar=("NAME", "VALUE"),
                   help="hyperparameter NAME with grid VALUES (Python literals); repeatable; one value = a fixed override")
    p.add_argument("--env-kwargs", nargs="*", default=[], metavar="KEY:VALUE",
                   help="further environment keywords for every trial (Python literals; not sea_codes)")
    p.add_argument("--n-timesteps", type=int, default=200_000)
    p.add_argument("--n-envs", type=int, default=None, help="override the YAML's n_envs")
    p.add_argument("--max-minutes", type=float, default=None, help="per trial")
    p.add_argument("--eval-freq", type=int, default=50_000)
    p.add_argument("--eval-episodes", type=int, default=None, help="validation episodes (train.py's default: 6)")
    p.add_argument("--log-dir", default="runs/tune")
    p.add_argument("--storage", default=None, help="Ray's experiment folder (default <log-dir>/ray)")
    p.add_argument("--address", default=None,
                   help="existing Ray cluster: auto, HOST:PORT or ray://HOST:10001 (default: $RAY_ADDRESS, else a "
                        "new local Ray instance)")
    p.add_argument("--cpus", type=int, default=None,
                   help="CPUs of the local Ray instance (default: all); on a cluster, the most concurrent trials")
    p.add_argument("--num-samples", type=int, default=1, help="run the grid this many times (same seeds)")
    p.add_argument("--ray-verbose", type=int, default=0, choices=[0, 1, 2],
                   help="Ray Tune's own output: 0 (default) none besides this script's line per trial, "
                        "1 its status table and per-trial tables, 2 also every result")
    p.add_argument("--dry-run", action="store_true")
    args = p.parse_args(argv)
    if args.num_samples < 1:
        p.error("--num-samples must be >= 1")
    if args.cpus is not None and args.cpus < 1:
        p.error("--cpus must be >= 1")
    if any(kv.split(":", 1)[0] == "sea_codes" for kv in args.env_kwargs):
        p.error("use --sea-codes, not --env-kwargs sea_codes:...")
    if args.eval_freq <= 0 or args.eval_freq > args.n_timesteps:
        p.error("--eval-freq must be in 1..--n-timesteps: each trial reports its best validation reward")
    # absolute paths now: Ray runs every trial in a directory of its own
    args.log_dir = str(Path(args.log_dir).expanduser().resolve())
    args.storage = str(Path(args.storage or Path(args.log_dir) / "ray").expanduser().resolve())
    if args.conf:
        args.conf = str(Path(args.conf).expanduser().resolve())
    return args


def _slug(v) -> str:
    return re.sub(r"[^A-Za-z0-9.+-]", "", str(v))[:40]


def trial_name(cfg: dict, args) -> str:
    name = f"{args.algo}_{args.env.split('/')[-1]}_c{cfg['sea_codes']}_s{cfg['seed']}"
    for k, v in sorted(cfg.get("hyperparams", {}).items()):
        name += f"_{k}{_slug(v)}"
    if cfg.get("repeat"):
        name += f"_r{cfg['repeat']}"
    return name


def trial_argv(cfg: dict, args) -> list[str]:
    hp = [f"{k}:{v!r}" for k, v in sorted(cfg.get("hyperparams", {}).items())]
    argv = ["--algo", args.algo, "--env", args.env, "--seed", str(cfg["seed"]), "--n-timesteps", str(args.n_timesteps),
            "--log-dir", args.log_dir, "--name", trial_name(cfg, args), "--eval-freq", str(args.eval_freq),
            "--no-progress-bar", "--env-kwargs", f"sea_codes:{tuple(int(c) for c in str(cfg['sea_codes']))!r}",
            *args.env_kwargs]
    if hp:
        argv += ["--hyperparams", *hp]
    if args.conf:
        argv += ["--conf", args.conf]
    if args.n_envs:
        argv += ["--n-envs", str(args.n_envs)]
    if args.eval_episodes:
        argv += ["--eval-episodes", str(args.eval_episodes)]
    if args.max_minutes:
        argv += ["--max-minutes", str(args.max_minutes)]
    return argv


def grid(args) -> list[dict]:
    import ast
    names = [p[0] for p in args.param]
    values = [[ast.literal_eval(v) for v in p[1:]] for p in args.param]
    out = []
    for rep in range(args.num_samples):
        for seed, codes in itertools.product(args.seeds, args.sea_codes):
            for combo in itertools.product(*values) if values else [()]:
                cfg = {"seed": seed, "sea_codes": str(codes), "hyperparams": dict(zip(names, combo)), "repeat": rep}
                cfg["name"] = trial_name(cfg, args)
                out.append(cfg)
    dup = {c["name"] for c in out if sum(d["name"] == c["name"] for d in out) > 1}
    if dup:
        raise SystemExit(f"tune_ray.py: repeated trials (same run folder): {sorted(dup)}")
    return out


def run_trial(cfg: dict, args) -> dict:
    """Run one trial (train.py's main in this process); return its best validation reward and policy path."""
    from agents import train
    argv = trial_argv(cfg, args)
    rc = train.main(argv)
    if rc:
        raise RuntimeError(f"train.py exited with {rc}")
    run = Path(args.log_dir) / cfg["name"]
    info = json.loads((run / "run_info.json").read_text())
    best = None
    ev = run / "eval" / "evaluations.npz"
    if ev.exists():
        import numpy as np
        with np.load(ev) as d:
            if d["results"].size:
                best = float(d["results"].mean(axis=1).max())
    return {"best_validation_reward": best, "num_timesteps": info["num_timesteps"], "policy": info["exported"],
            "run_dir": str(run), "wall_seconds": info["wall_seconds"]}


def missing_extras() -> list[str]:
    """The extras this script lacks ("rl": SB3 and friends for train.py, "ray": Ray Tune)."""
    missing = []
    if missing_modules(RL_COMMAND_MODULES):
        missing.append("rl")
    try:
        import ray  # noqa: F401
        from ray import tune  # noqa: F401
    except ImportError:
        missing.append("ray")
    return missing


def _finite_or_none(x):
    return x if isinstance(x, (int, float)) and math.isfinite(x) else None


def main(argv=None):
    args = parse_args(argv)
    trials = grid(args)
    if not trials:
        print("tune_ray.py: no trials (give at least one value to --seeds and --sea-codes)", file=sys.stderr)
        return 2
    if args.dry_run:
        for cfg in trials:
            print("python scripts/train.py " + " ".join(trial_argv(cfg, args)))
        return 0
    missing = missing_extras()
    if missing:
        ex = ",".join(missing)
        print(f'tune_ray.py needs the extra{"s" if len(missing) > 1 else ""} {" and ".join(missing)}: '
              f'pip install "towenv[{ex}]" (from a checkout: pip install ".[{ex}]"); --dry-run works without them',
              file=sys.stderr)
        return 2

    import ray
    from ray import tune
    try:
        from ray.tune import RunConfig
    except ImportError:                          # older Ray
        from ray.train import RunConfig

    os.environ.setdefault("OMP_NUM_THREADS", "1")
    address = args.address or os.environ.get("RAY_ADDRESS") or None
    local = address in (None, "local")
    if local:        # "local": always a new instance (never silently joins a cluster left by `ray start`)
        ray.init(address="local", num_cpus=args.cpus, include_dashboard=False, ignore_reinit_error=True)
    else:
        try:
            ray.init(address=address, ignore_reinit_error=True)
        except ConnectionError as e:
            print(f"tune_ray.py: cannot connect to the Ray cluster at {address} ({e}); is `ray start --head` "
                  f"running there? With token authentication, set RAY_AUTH_MODE=token and the cluster's token "
                  f"(~/.ray/auth_token or RAY_AUTH_TOKEN)", file=sys.stderr)
            return 1
    if __name__ != "__main__" and __name__ in sys.modules:   # imported (tests): ship this module by value
        try:
            ray.cloudpickle.register_pickle_by_value(sys.modules[__name__])
        except Exception:
            pass
    res = ray.cluster_resources()
    print(f"[tune] {len(trials)} trial(s) of {args.n_timesteps} steps on "
          f"{'a new local Ray instance' if local else 'the Ray cluster at ' + address} "
          f"({res.get('CPU', 0):g} CPUs); run folders in {args.log_dir}", flush=True)

    report = getattr(tune, "report", None)
    if report is None:                           # older Ray: ray.train.report
        from ray import train as _train
        report = _train.report

    def trainable(config):
        out = run_trial(config["trial"], args)
        metrics = dict(out)
        metrics["best_validation_reward"] = (out["best_validation_reward"]
                                             if out["best_validation_reward"] is not None else float("-inf"))
        report(metrics)

    class Progress(tune.Callback):
        """One line per trial as it starts and ends (Ray's status table comes only every half minute)."""

        def __init__(self, n):
            self.n, self.started, self.ended, self.t0 = n, 0, 0, {}

        def _name(self, trial):
            return trial.config["trial"]["name"]

        def on_trial_start(self, iteration, trials, trial, **info):
            self.started += 1
            self.t0[trial.trial_id] = time.time()
            print(f"[tune] start {self.started}/{self.n}: {self._name(trial)}", flush=True)

        def on_trial_complete(self, iteration, trials, trial, **info):
            self.ended += 1
            r = trial.last_result or {}
            print(f"[tune] done  {self.ended}/{self.n}: {self._name(trial)}: best validation reward "
                  f"{r.get('best_validation_reward')}, {r.get('num_timesteps')} steps, "
                  f"{time.time() - self.t0.get(trial.trial_id, time.time()):.0f} s", flush=True)

        def on_trial_error(self, iteration, trials, trial, **info):
            self.ended += 1
            print(f"[tune] FAILED {self.ended}/{self.n}: {self._name(trial)} (traceback above and in "
                  f"{Path(trial.local_path) / 'error.txt'})", flush=True)

    t0 = time.time()
    tuner = tune.Tuner(
        tune.with_resources(trainable, {"cpu": 1}),
        param_space={"trial": tune.grid_search(trials)},
        tune_config=tune.TuneConfig(metric="best_validation_reward", mode="max",
                                    max_concurrent_trials=None if local else args.cpus,
                                    trial_name_creator=lambda t: t.config["trial"]["name"],
                                    trial_dirname_creator=lambda t: f"{t.config['trial']['name']}_{t.trial_id}"),
        run_config=RunConfig(name=f"towenv_sweep_{time.strftime('%Y%m%d-%H%M%S')}", storage_path=args.storage,
                             callbacks=[Progress(len(trials))], verbose=args.ray_verbose))
    try:
        results = tuner.fit()
    finally:
        if local:
            ray.shutdown()
    rows, failed = [], []
    for r in results:
        cfg = r.config["trial"]
        m = r.metrics or {}
        row = {"name": cfg["name"], "seed": cfg["seed"], "sea_codes": cfg["sea_codes"],
               "hyperparams": cfg["hyperparams"], "repeat": cfg["repeat"],
               "best_validation_reward": _finite_or_none(m.get("best_validation_reward")),
               "num_timesteps": m.get("num_timesteps"), "policy": m.get("policy"), "run_dir": m.get("run_dir"),
               "wall_seconds": m.get("wall_seconds"), "error": None}
        if r.error is not None:
            lines = [ln.strip() for ln in re.sub(r"\x1b\[[0-9;]*m", "", str(r.error)).splitlines() if ln.strip()]
            row["error"] = (lines[-1] if lines else type(r.error).__name__)[:500]    # the root exception
            failed.append(cfg["name"])
        rows.append(row)
    rows.sort(key=lambda x: x["name"])
    ok = [x for x in rows if x["best_validation_reward"] is not None]
    best = max(ok, key=lambda x: x["best_validation_reward"]) if ok else None
    out = Path(args.log_dir) / "tune_results.json"
    out.parent.mkdir(parents=True, exist_ok=True)
    atomic_write(out, json.dumps({"argv": sys.argv[1:] if argv is None else list(argv),
                                   "ray_address": address or "local", "experiment": str(results.experiment_path),
                                   "wall_seconds": round(time.time() - t0, 1),
                                   "best": best["name"] if best else None, "trials": rows},
                                  indent=1, default=str) + "\n")
    if best:
        print(f"[tune] best: {best['name']} -> {best['best_validation_reward']:.4g} ({best['policy']})", flush=True)
    print(f"[tune] {len(rows) - len(failed)}/{len(trials)} trials finished in {time.time() - t0:.0f} s; "
          f"results: {out}", flush=True)
    if failed or len(rows) != len(trials):
        print(f"[tune] failed: {', '.join(failed) or '(missing trials)'}", file=sys.stderr, flush=True)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
